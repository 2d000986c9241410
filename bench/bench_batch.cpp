// Batched baking benchmark (issue #23): S sequences made from the bundled scenes (every
// assets/*.json with keyframes, repeated with other frame counts and, every other
// repeat, every keyframe time a frame), solved one at a time (a core and an
// Interpolator per sequence, then Interpolator::sequence: what a loop over `hsi bake`
// or hsi_interpolator_sequence does) and by solve_batch with W workers for each W of
// the list, in one run on one backend. Prints per path: frames, wall time, frames/s,
// speed-up over one at a time, the set-up inside it (cores, interpolators), the process's
// CPU time over the row and how many host cores that kept busy on average (waiting
// threads that spin count: --cuda-wait block shows the host's own work), certified
// and converged frames, and whether the frames are identical to the first batch row's
// (the batch's output must not depend on W). Every time counts everything after the
// shapes' setups are built (cores, interpolators with their keyframe certificates,
// solves). Not a test.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <set>

#include <sys/resource.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "bench_args.h"
#include "bench_scenes.h"
#include "hsi/batch.h"
#include "hsi/lockstep.h"
#include "hsi/machine.h"
#include "hsi/runtime/backend.h"
#include "trace_range.h"

using namespace hsi;

namespace {

using Clock = std::chrono::steady_clock;
double s_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The process's CPU time so far, user and system, in seconds (every thread's).
double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// A frame's wall clock split into its parts (FrameResult::parts, the solve by
// NewtonResult::timing), summed over the frames that were solved (keyframes and held
// frames cost nothing and are left out).
struct PartSums {
  size_t solved = 0;
  double iterations = 0, ms = 0, targets = 0, solve = 0, pose = 0, image = 0, crossings = 0, crossings_wait = 0, distortion = 0;
  NewtonResult::Timing t;
  void add(const FrameResult& f) {
    if (f.keyframe || f.held) return;  // the keyframe itself: nothing solved
    ++solved;
    iterations += f.iterations;
    ms += f.ms;
    targets += f.parts.targets;
    solve += f.parts.solve;
    pose += f.parts.pose;
    image += f.parts.image;
    crossings += f.parts.crossings;
    crossings_wait += f.parts.crossings_wait;
    distortion += f.parts.distortion;
    t += f.timing;
  }
};

struct Row {
  std::string path;
  int workers = 0;
  size_t frames = 0, certified = 0, converged = 0, failed = 0;
  PartSums parts;
  double seconds = 0, set_up_s = 0, core_set_up_s = 0;
  double cpu_s = 0;  // the process's CPU time (user + system, every thread) over the row
  int cores = 0, runs = 0, interpolators = 0;
  std::string wait = "-";  // the CUDA wait (--cuda-wait); "-" on the CPU
  std::string exact;       // the exact systems' samples (--exact-samples)
  std::string image;       // where the boundary's image is made (--image)
  std::string same;  // identical to the first batch row of the same --exact-samples
  std::array<size_t, kNewtonStopCount> stops{};  // the frames not converged, by why their solve stopped
  size_t differ_converged = 0, differ_iterations = 0;  // frames whose verdict / iterations differ from the first batch row's
};

void count(Row& row, const std::vector<FrameResult>& frames) {
  row.frames += frames.size();
  for (const FrameResult& f : frames) {
    row.certified += f.certified;
    row.converged += f.converged;
    if (!f.converged) ++row.stops[static_cast<size_t>(f.stop)];
    row.parts.add(f);
  }
}

// Frames whose convergence verdict, and whose iteration count, differ between a and b.
void count_differences(Row& row, const std::vector<BatchSequenceResult>& a, const std::vector<BatchSequenceResult>& b) {
  for (size_t s = 0; s < std::min(a.size(), b.size()); ++s)
    for (size_t i = 0; i < std::min(a[s].frames.size(), b[s].frames.size()); ++i) {
      row.differ_converged += a[s].frames[i].converged != b[s].frames[i].converged;
      row.differ_iterations += a[s].frames[i].iterations != b[s].frames[i].iterations;
    }
}

// Every frame's coefficients and flags alike (the time each took aside).
bool same_frames(const std::vector<BatchSequenceResult>& a, const std::vector<BatchSequenceResult>& b) {
  if (a.size() != b.size()) return false;
  for (size_t s = 0; s < a.size(); ++s) {
    if (a[s].frames.size() != b[s].frames.size()) return false;
    for (size_t i = 0; i < a[s].frames.size(); ++i) {
      const FrameResult &x = a[s].frames[i], &y = b[s].frames[i];
      if (x.x != y.x || x.map.phi != y.map.phi || x.map.psi != y.map.psi || x.certified != y.certified || x.converged != y.converged ||
          x.iterations != y.iterations)
        return false;
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("hsi batched baking benchmark: many sequences one at a time against solve_batch with W workers (issue #23)");
  std::string backend = "cpu", workers_list = "1,2,4,8,16,32,64", assets = HSI_ASSETS_DIR;
  int sequences = 64, frames = 100, samples = 0, threads_per_worker = 1;
  double ratio = 0;
  bool skip_single = false;
  std::vector<std::string> waits = {"auto"};
  std::vector<std::string> exacts = {to_string(InterpolationOptions{}.exact_samples)};
  std::vector<std::string> images = {"backend"};
  std::string predict = to_string(InterpolationOptions{}.predict_start);
  app.add_option("--backend", backend, runtime::kBackendHelp)->capture_default_str()->check(CLI::IsMember(runtime::backend_names()));
  app.add_option("--workers", workers_list, "Batch worker counts W, comma-separated")->capture_default_str();
  app.add_option("--sequences", sequences, "Sequences S, made from the bundled scenes in turn")->capture_default_str()->check(CLI::Range(1, 100000));
  app.add_option("--frames", frames, "Frames of the first sequence of each scene; each repeat of a scene adds 7")
      ->capture_default_str()
      ->check(CLI::Range(2, 1000000));
  app.add_option("--samples", samples, "Boundary samples |G| (default: each scene's, 10000 for the bundled ones)")->check(CLI::Range(100, 10000000));
  app.add_option("--ratio", ratio, "Hessian sample ratio r (default: each scene's)")->check(CLI::Range(1e-6, 1.0));
  app.add_option("--threads-per-worker", threads_per_worker, "OpenMP threads in each batch worker (0: OpenMP's default)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  app.add_option("--assets", assets, "Folder of scene files (.json with two or more keyframes)")->capture_default_str();
  app.add_option("--cuda-wait", waits,
                 std::string("How the workers wait for the GPU, comma-separated: every W runs with each (") + runtime::kCudaWaitHelp + ")")
      ->delimiter(',')
      ->capture_default_str()
      ->check(CLI::IsMember(runtime::cuda_wait_names()));
  app.add_option("--exact-samples", exacts,
                 "The samples the frames' exact Newton systems sum over, comma-separated: every W runs with each "
                 "(InterpolationOptions::exact_samples: subset, subset-then-all, all, auto = the core's choice; the "
                 "one-at-a-time path runs the first)")
      ->delimiter(',')
      ->capture_default_str()
      ->check(CLI::IsMember(exact_samples_names()));
  app.add_option("--image", images,
                 "Where each frame's image of the boundary (the overlap check's points) is made, comma-separated: every W "
                 "runs with each (backend: on the core's backend, as hsi bake and the C API; host: the setup's CPU "
                 "evaluator, on the worker's thread; the one-at-a-time path runs the first)")
      ->delimiter(',')
      ->capture_default_str()
      ->check(CLI::IsMember({"backend", "host"}));
  app.add_option("--predict-start", predict,
                 "Where every sequence's frames start (InterpolationOptions::predict_start: off, always, auto)")
      ->capture_default_str()
      ->check(CLI::IsMember(predict_start_names()));
  std::string lockstep_list, serial_list;
  app.add_option("--lockstep", lockstep_list,
                 "Lockstep group sizes, comma-separated: after the W rows, one row per size with each setup's runs solved by a group "
                 "of that many threads stepped together (runtime::set_batch_lockstep; on CUDA the device's batched stepper)");
  int window_us = 0;
  app.add_option("--lockstep-window", window_us,
                 "Microseconds a lockstep group's call waits for the group's threads that are away before its round is served "
                 "without them (BatchOptions::lockstep_window; 0: every round waits for every live thread)")
      ->capture_default_str()
      ->check(CLI::Range(0, 10000000));
  app.add_option("--lockstep-serial", serial_list,
                 "Lockstep group sizes for the reference backend, comma-separated: each system its own core of the backend (on "
                 "CUDA a CUDA core and its own stepper), a group's calls served one after another (make_serial_lockstep_backend); "
                 "the same loops as --lockstep without the batched stepper");
  app.add_flag("--skip-single", skip_single, "Leave out the one-at-a-time path (the speed-up column is then empty)");
  CLI11_PARSE(app, argc, argv);
  std::vector<int> worker_counts, lockstep_counts, serial_counts;
  try {
    worker_counts = bench::parse_counts(workers_list, "--workers");
    if (!lockstep_list.empty()) lockstep_counts = bench::parse_counts(lockstep_list, "--lockstep");
    if (!serial_list.empty()) serial_counts = bench::parse_counts(serial_list, "--lockstep-serial");
  } catch (const CLI::Error& e) {
    return app.exit(e);
  }

  // The backend, decided once: every core of every path is of this kind.
  const runtime::Backend requested = runtime::parse_backend(backend);
  const runtime::CudaStatus cuda = requested == runtime::Backend::Cpu ? runtime::CudaStatus{} : runtime::cuda_status();
  runtime::BackendChoice choice;
  try {
    choice = runtime::choose_backend(requested, cuda);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_batch: %s\n", e.what());
    return 1;
  }
  // The factories hsi bake and the C API use: the core, and on CUDA the image of the
  // boundary on the GPU (--image host leaves it to the setup's CPU evaluator).
  BatchOptions factories;
  runtime::set_batch_backend(factories, choice.used, cuda);
  const auto boundary_of = [&](const ShapeSetup& setup, bool host) {
    return host || !factories.make_boundary ? nullptr : factories.make_boundary(setup);
  };

  // The scenes, then the sequences.
  std::vector<bench::Loaded> scenes = bench::load_folder(assets, samples, ratio, "bench_batch");
  if (scenes.empty()) {
    std::fprintf(stderr, "bench_batch: no scene with keyframes in %s\n", assets.c_str());
    return 1;
  }
  std::vector<BatchSequence> batch;
  for (int i = 0; i < sequences; ++i) {
    const bench::Loaded& L = scenes[static_cast<size_t>(i) % scenes.size()];
    const int repeat = i / static_cast<int>(scenes.size());
    BatchSequence q = bench::batch_sequence(L, repeat, frames + 7 * repeat);
    q.options.exact_samples = parse_exact_samples(exacts.front());
    q.options.predict_start = parse_predict_start(predict);
    batch.push_back(std::move(q));
  }
  size_t total = 0;
  for (const BatchSequence& q : batch) total += q.times.size();

  const Machine machine = this_machine();
#ifdef _OPENMP
  const int omp_threads = omp_get_max_threads();
#else
  const int omp_threads = 1;
#endif
  std::printf("Machine: %s, %d logical cores, %d OpenMP threads by default\n", machine.cpu.c_str(), machine.cores, omp_threads);
  std::printf("Newton core: %s\n", runtime::describe(choice).c_str());
  if (choice.used == runtime::Backend::Cuda) std::printf("GPU clocks: %s\n", runtime::gpu_clocks().c_str());
  std::set<const ShapeSetup*> setups;
  for (const BatchSequence& q : batch) setups.insert(q.setup);
  std::printf("%d sequences from %zu scenes (%zu shapes), %zu frames; |G| = %s, first sequence of each scene %d frames (+7 per repeat)\n",
              sequences, scenes.size(), setups.size(), total, samples > 0 ? std::to_string(samples).c_str() : "each scene's", frames);
  std::printf("one at a time: a core and an Interpolator per sequence, %d OpenMP threads; batch: W workers x %d OpenMP thread(s) each; "
              "start prediction %s\n\n",
              omp_threads, threads_per_worker, predict.c_str());

  // Warm-up outside every timing: libraries loaded, the first core's modules.
  {
    const BatchSequence& q = batch.front();
    Interpolator I(*q.setup, q.key_times, q.keyframes, q.options, factories.make_core(*q.setup), boundary_of(*q.setup, false));
    I.sequence(std::vector<double>(q.times.begin(), q.times.begin() + std::min<size_t>(3, q.times.size())));
  }

  std::vector<Row> rows;
  if (!skip_single) {
    Row row;
    row.path = "one at a time";
    row.workers = 1;
    row.core_set_up_s = -1;  // each core is made inside its Interpolator's expression: not timed apart
    row.exact = exacts.front();
    row.image = images.front();
    const auto t0 = Clock::now();
    const double c0 = process_cpu_s();
    for (const BatchSequence& q : batch) {
      const auto ts = Clock::now();
      Interpolator I(*q.setup, q.key_times, q.keyframes, q.options, factories.make_core(*q.setup),
                     boundary_of(*q.setup, images.front() == "host"));
      row.set_up_s += s_since(ts);
      ++row.cores;
      ++row.interpolators;
      count(row, I.sequence(q.times));
      std::fprintf(stderr, "\r[one at a time] %zu/%zu frames   ", row.frames, total);
    }
    row.seconds = s_since(t0);
    row.cpu_s = process_cpu_s() - c0;
    row.runs = static_cast<int>(batch.size());
    std::fprintf(stderr, "\n");
    rows.push_back(row);
  }
  const bool on_gpu = choice.used == runtime::Backend::Cuda;
  for (const std::string& exact : exacts)
    for (const std::string& image : images) {
      for (BatchSequence& q : batch) q.options.exact_samples = parse_exact_samples(exact);
      std::vector<BatchSequenceResult> first;  // this setting's first batch row
      for (const std::string& wait : on_gpu ? waits : std::vector<std::string>{"-"})
        for (size_t config = 0; config < worker_counts.size() + lockstep_counts.size() + serial_counts.size(); ++config) {
          const size_t nw = worker_counts.size(), nl = lockstep_counts.size();
          const bool serial = config >= nw + nl, lockstep = config >= nw;
          const int W = serial ? serial_counts[config - nw - nl] : lockstep ? lockstep_counts[config - nw] : worker_counts[config];
          if (on_gpu)
            if (const std::string why = runtime::set_cuda_wait(wait); !why.empty()) {
              std::fprintf(stderr, "bench_batch: --cuda-wait %s: %s\n", wait.c_str(), why.c_str());
              return 1;
            }
          BatchOptions o;
          o.workers = W;
          o.threads_per_worker = threads_per_worker;
          o.make_core = factories.make_core;
          o.make_boundary = image == "host" ? nullptr : factories.make_boundary;
          if (lockstep) runtime::set_batch_lockstep(o, choice.used, W);
          o.lockstep_window = std::chrono::microseconds(window_us);
          if (serial) {
            o.lockstep_systems = W;
            o.make_lockstep = [make_core = factories.make_core](const ShapeSetup& setup, int n) {
              return make_serial_lockstep_backend(setup, n, [&] { return make_core(setup); });
            };
          }
          const double c0 = process_cpu_s();
          const BatchResult r = [&] {
            const bench::TraceRange range("batch W=" + std::to_string(W) + " wait " + wait + " exact " + exact + " image " + image);  // (bench/cuda_trace)
            return solve_batch(batch, o, [&](const FrameResult&, int, int, size_t done, size_t all) {
              if (done % 100 == 0 || done == all) std::fprintf(stderr, "\r[batch W = %d, wait %s, exact %s, image %s] %zu/%zu frames   ", W, wait.c_str(), exact.c_str(),
                                                       image.c_str(), done, all);
              return true;
            });
          }();
          std::fprintf(stderr, "\n");
          Row row;
          row.path = serial ? "lockstep serial " + std::to_string(W) : lockstep ? "lockstep " + std::to_string(W) : "batch";
          if (lockstep && window_us > 0) row.path += " (window " + std::to_string(window_us) + " us)";
          row.wait = wait;
          row.exact = exact;
          row.image = image;
          row.workers = r.stats.workers;
          row.seconds = r.stats.seconds;
          row.cpu_s = process_cpu_s() - c0;
          row.set_up_s = r.stats.set_up_s;
          row.core_set_up_s = r.stats.core_set_up_s;
          row.cores = r.stats.cores_made;
          row.interpolators = r.stats.interpolators_built;
          row.runs = r.stats.runs;
          for (const BatchSequenceResult& s : r.sequences) {
            count(row, s.frames);
            if (!s.error.empty()) {
              ++row.failed;
              std::fprintf(stderr, "bench_batch: W = %d: %s\n", W, s.error.c_str());
            }
          }
          if (first.empty()) {
            first = r.sequences;
            row.same = "(first)";
          } else {
            row.same = same_frames(first, r.sequences) ? "yes" : "NO";
            count_differences(row, first, r.sequences);
          }
          rows.push_back(row);
        }
    }

  const double base = skip_single ? 0 : static_cast<double>(rows.front().frames) / rows.front().seconds;
  std::printf("| path | exact systems | image | CUDA wait | W | frames | s | frames/s | speed-up | set-up s (summed) | of it cores s | cores made | interpolators | runs | host CPU s | host cores busy | certified | converged | same frames as first batch row |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  bool all_certified = true;
  for (const Row& r : rows) {
    const double fps = static_cast<double>(r.frames) / std::max(r.seconds, 1e-12);
    const bool every = r.certified == total && r.failed == 0;
    all_certified = all_certified && every;
    char speed[32] = "";
    if (base > 0) std::snprintf(speed, sizeof speed, "%.2fx", fps / base);
    char cores_s[32] = "-";
    if (r.core_set_up_s >= 0) std::snprintf(cores_s, sizeof cores_s, "%.2f", r.core_set_up_s);
    std::printf("| %s | %s | %s | %s | %d | %zu | %.2f | %.0f | %s | %.2f | %s | %d | %d | %d | %.2f | %.1f | %zu%s | %zu | %s |\n", r.path.c_str(),
                r.exact.c_str(), r.image.c_str(), r.wait.c_str(), r.workers,
                r.frames, r.seconds, fps, speed, r.set_up_s, cores_s, r.cores, r.interpolators, r.runs, r.cpu_s,
                r.cpu_s / std::max(r.seconds, 1e-12), r.certified, every ? "" : " (NOT ALL CERTIFIED)", r.converged,
                r.same.empty() ? "-" : r.same.c_str());
  }
  // Where a solved frame's wall clock goes, per row: what grows with W is what the
  // workers contend for.
  std::printf("\nWhere a solved frame's time goes (mean ms per solved frame, each part timed apart on the worker's thread; "
              "crossings ran on a thread of their own, wait is what the worker waited for them; solve = E+grad + Hessian + "
              "factor + line search + certificate):\n\n");
  std::printf("| path | exact systems | image | CUDA wait | W | solved frames | it/frame | frame | targets | solve | E+grad | Hessian | factor | "
              "line search | certificate | pose | image | crossings | wait | distortion |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Row& r : rows) {
    const PartSums& p = r.parts;
    const double k = 1.0 / static_cast<double>(std::max<size_t>(p.solved, 1));
    std::printf("| %s | %s | %s | %s | %d | %zu | %.2f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n",
                r.path.c_str(), r.exact.c_str(), r.image.c_str(), r.wait.c_str(), r.workers, p.solved, p.iterations * k, p.ms * k, p.targets * k,
                p.solve * k, p.t.energy_gradient * k, p.t.hessian * k, p.t.solve * k, p.t.line_search * k, p.t.certificate * k,
                p.pose * k, p.image * k, p.crossings * k, p.crossings_wait * k, p.distortion * k);
  }
  // The frames not converged, by why their solve stopped, and how a row's frames differ
  // from its setting's first batch row's.
  bool any = false;
  for (const Row& r : rows) {
    std::string why;
    for (int k = 0; k < kNewtonStopCount; ++k)
      if (r.stops[static_cast<size_t>(k)])
        why += (why.empty() ? "" : ", ") + std::to_string(r.stops[static_cast<size_t>(k)]) + " " + to_string(static_cast<NewtonStop>(k));
    if (why.empty() && r.differ_converged == 0 && r.differ_iterations == 0) continue;
    if (!any) std::printf("\nFrames NOT CONVERGED, by why their solve stopped; frames differing from the setting's first batch row:\n\n");
    any = true;
    std::printf("- %s (exact %s, W %d): %s; verdict differs in %zu frames, iterations in %zu\n", r.path.c_str(), r.exact.c_str(), r.workers,
                why.empty() ? "every frame converged" : why.c_str(), r.differ_converged, r.differ_iterations);
  }
  std::printf("\n%s\n", all_certified ? "every frame of every path certified" : "SOME FRAMES NOT CERTIFIED (or sequences failed): see the table");
  return all_certified ? 0 : 3;
}
