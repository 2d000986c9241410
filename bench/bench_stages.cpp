// Throughput of the Newton stepper's stages on W threads at once (issue #23): how many
// frames per second a backend could give if every frame did only these stages, each
// thread with its own core and stepper on one bundled scene (thread t on scene t mod S),
// all W threads running the same stages side by side. A frame's work, cumulatively:
//   start        x ← a warm frame's start and its energy (the previous frame's solution)
//   + exact G    the exact Newton system modulo the rotation over all of G (linearize:
//                gradient, Hessian, reduced system), what ends a warm frame by default
//   + factor     its Cholesky factor and the triangular solves (solve)
//   + try        one trial energy and the certificate of the full step (a line search's
//                first offer)
// and beside them "+ exact H" (the same system over the subset H instead of G) and
// "chord" (start, the kept factor's triangular solves: a frame's first step). With
// one thread each row is a frame's latency in those stages; with many, the rows say
// which stage the backend runs out of first. A solved warm frame (bench_batch) does
// roughly start + chord + try + exact G + factor; compare its frames/s in the same run.
// Not a test: a measurement of capacity, every stage's numbers discarded.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <barrier>
#include <chrono>
#include <cstdio>
#include <thread>

#include "bench_args.h"
#include "bench_scenes.h"
#include "hsi/machine.h"
#include "hsi/runtime/backend.h"

using namespace hsi;

namespace {

using Clock = std::chrono::steady_clock;

enum class Stage { Start, ExactG, ExactH, Factor, Try, Chord };

struct Variant {
  const char* name;
  std::vector<Stage> stages;
};

const std::vector<Variant>& variants() {
  static const std::vector<Variant> v = {
      {"start", {Stage::Start}},
      {"start + exact G", {Stage::Start, Stage::ExactG}},
      {"start + exact G + factor", {Stage::Start, Stage::ExactG, Stage::Factor}},
      {"start + exact G + factor + try", {Stage::Start, Stage::ExactG, Stage::Factor, Stage::Try}},
      {"start + exact H", {Stage::Start, Stage::ExactH}},
      {"start + exact H + factor", {Stage::Start, Stage::ExactH, Stage::Factor}},
      {"start + chord (kept factor) + try", {Stage::Start, Stage::Chord, Stage::Try}},
  };
  return v;
}

// One thread's scene: its core, a warm frame's start and targets, its stepper.
struct Worker {
  std::unique_ptr<NewtonCore> core;
  std::unique_ptr<NewtonStepper> stepper;
  Eigen::VectorXd x;
  KeptSystem kept;
  bool factored = false;  // the exact system over G factored at x
  std::string scene;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("hsi Newton stepper stages: frames/s a backend could give per stage, on W threads at once (issue #23)");
  std::string backend = "cuda", workers_list = "1,4,16", assets = HSI_ASSETS_DIR;
  int samples = 0;
  double seconds = 2;
  app.add_option("--backend", backend, runtime::kBackendHelp)->capture_default_str()->check(CLI::IsMember(runtime::backend_names()));
  app.add_option("--workers", workers_list, "Thread counts W, comma-separated")->capture_default_str();
  app.add_option("--samples", samples, "Boundary samples |G| (default: each scene's, 10000 for the bundled ones)")->check(CLI::Range(100, 10000000));
  app.add_option("--seconds", seconds, "Wall time each row runs for")->capture_default_str()->check(CLI::Range(0.1, 600.0));
  app.add_option("--assets", assets, "Folder of bundled scenes (every *.json with two or more keyframes)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::vector<int> worker_counts;
  try {
    worker_counts = bench::parse_counts(workers_list, "--workers");
  } catch (const CLI::Error& e) {
    return app.exit(e);
  }
  const runtime::Backend requested = runtime::parse_backend(backend);
  const runtime::CudaStatus cuda = requested == runtime::Backend::Cpu ? runtime::CudaStatus{} : runtime::cuda_status();

  std::vector<bench::Loaded> scenes = bench::load_folder(assets, samples, 0, "bench_stages");
  for (const bench::Loaded& L : scenes)
    std::fprintf(stderr, "[stages] %s: n = %d, |G| = %zu, |H| = %zu\n", L.name.c_str(), L.setup->map_space.n(), L.setup->G.size(),
                 L.setup->H.size());
  if (scenes.empty()) {
    std::fprintf(stderr, "no scene with two or more keyframes in %s\n", assets.c_str());
    return 2;
  }

  const Machine machine = this_machine();
  std::printf("Machine: %s, %d logical cores\n", machine.cpu.c_str(), machine.cores);
  const int most = *std::max_element(worker_counts.begin(), worker_counts.end());
  // Threads beyond the scenes' count reuse scenes: thread t takes scene t mod S.
  std::vector<Worker> workers(static_cast<size_t>(most));
  std::string core_line;
  std::vector<std::string> skipped;  // scenes none of whose candidate points factors on this backend
  for (int t = 0; t < most; ++t) {
    Worker& w = workers[static_cast<size_t>(t)];
    // Thread t takes scene t mod S, or the next one where a warm frame's exact system
    // factors (so every row times the same work on every thread).
    for (size_t o = 0; o < scenes.size() && !w.factored; ++o) {
      const bench::Loaded& L = scenes[(static_cast<size_t>(t) + o) % scenes.size()];
      if (std::find(skipped.begin(), skipped.end(), L.name) != skipped.end()) continue;
      const ShapeSetup& setup = *L.setup;
      runtime::NewtonCoreChoice c = runtime::make_newton_core(setup, requested, cuda, false);
      if (core_line.empty()) {
        core_line = runtime::describe(c.choice);
        if (c.choice.used == runtime::Backend::Cuda) core_line += "\nGPU clocks: " + runtime::gpu_clocks();
      }
      w.core = std::move(c.core);
      // A warm frame's end: the solution at some time (a frame solved from its neighbour
      // 1 % of the interval before), with its targets: where a frame builds and factors
      // its last exact system, kept for the next frame's chord step. At some times the
      // solution leaves that system indefinite (the loop then ends on a projection and
      // keeps none): the first of these times where it factors.
      Interpolator interp(setup, L.times, L.maps, {}, borrow_core(*w.core));
      for (double u : {0.5, 0.3, 0.7, 0.1, 0.9}) {
        const double span = L.times[1] - L.times[0], at = L.times[0] + u * span;
        const FrameResult before = interp.frame(at - 0.01 * span);
        const FrameResult f = interp.frame(at, before.x, &before.certificate);
        w.x = f.x;
        w.core->set_targets(interp.blended_metric(at));
        w.stepper = w.core->make_stepper(setup.metric_space, &setup.certifier, nullptr);
        if (!w.stepper) w.stepper = make_host_stepper(*w.core, setup.metric_space, &setup.certifier, nullptr);
        w.stepper->start(w.x);
        w.stepper->linearize({true, HessianProjection::FullProj, true, true});
        w.factored = w.stepper->solve(1e-15).factored;  // (NewtonOptions::exact_ridge, relative)
        if (w.factored) {
          w.stepper->keep(w.kept);
          w.scene = L.name;
          break;
        }
      }
      if (!w.factored) skipped.push_back(L.name);
    }
    if (!w.factored) {
      std::fprintf(stderr, "no bundled scene has a warm frame whose exact system factors on this backend\n");
      return 1;
    }
  }
  std::printf("Newton core: %s\n", core_line.c_str());
  std::printf("%zu scenes; thread t on scene t mod %zu (or the next usable one); every row runs %.1f s of wall time after a warm-up\n",
              scenes.size(), scenes.size(), seconds);
  if (!skipped.empty()) {
    std::printf("left out (no warm frame tried whose exact system over G factors):");
    for (const std::string& n : skipped) std::printf(" %s", n.c_str());
    std::printf("\n");
  }
  std::printf("thread t's scene:");
  for (int t = 0; t < most; ++t) std::printf(" %s", workers[static_cast<size_t>(t)].scene.c_str());
  std::printf("\n");

  // One pass of a variant's stages on worker w.
  auto run_stages = [](Worker& w, const Variant& v) {
    NewtonStepper& st = *w.stepper;
    for (Stage s : v.stages) {
      switch (s) {
        case Stage::Start: st.start(w.x); break;
        // (a linearize the GPU stepper does not wait for is waited for by the next pass's start)
        case Stage::ExactG: st.linearize({true, HessianProjection::FullProj, true, true}); break;
        case Stage::ExactH: st.linearize({true, HessianProjection::FullProj, true, false}); break;
        case Stage::Factor: st.solve(1e-15); break;
        case Stage::Chord:
          if (!st.linearize_kept(w.kept)) throw InputError("bench_stages: the kept factor is not this stepper's");
          st.solve(0);
          break;
        case Stage::Try: {
          const double step = 1.0;
          double energy = 0;
          st.trial_energies(std::span<const double>(&step, 1), std::span<double>(&energy, 1));
          (void)st.certify(step, false);
          break;
        }
      }
    }
  };

  std::printf("\n| stages | W | frames | s | frames/s | ms per frame per thread |\n|---|---|---|---|---|---|\n");
  for (const Variant& v : variants()) {
    for (int W : worker_counts) {
      std::atomic<long> done{0};
      std::barrier sync(W + 1);
      Clock::time_point stop{};
      std::vector<std::thread> threads;
      for (int t = 0; t < W; ++t)
        threads.emplace_back([&, t] {
          Worker& w = workers[static_cast<size_t>(t)];
          for (int i = 0; i < 3; ++i) run_stages(w, v);  // warm-up (graphs captured, clocks up)
          sync.arrive_and_wait();  // ready
          sync.arrive_and_wait();  // `stop` set
          long n = 0;
          while (Clock::now() < stop) {
            run_stages(w, v);
            ++n;
          }
          done += n;
          sync.arrive_and_wait();
        });
      sync.arrive_and_wait();
      const auto t0 = Clock::now();
      stop = t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
      sync.arrive_and_wait();
      sync.arrive_and_wait();
      const double s = std::chrono::duration<double>(Clock::now() - t0).count();
      for (auto& th : threads) th.join();
      const double fps = static_cast<double>(done.load()) / s;
      std::printf("| %s | %d | %ld | %.2f | %.0f | %.3f |\n", v.name, W, done.load(), s, fps, 1000.0 * W / std::max(fps, 1e-9));
      std::fflush(stdout);
    }
  }
  return 0;
}
