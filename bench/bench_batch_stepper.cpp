// Whole warm frames of S sequences of one setup on the GPU, three ways in one run (issue
// #23: the lockstep batch): S systems, each F frames whose targets move from the scene's
// first keyframe's metrics to its last one's (a blend per frame, each system at its own
// phase), each frame warm-started from the system's previous one with its kept factor
// (chord steps), every frame's Newton loop newton_run's with the certificate:
//   one core   one CUDA core's stepper, the systems one after another (a sequence alone);
//   W workers  W threads, each its own CUDA core and stream, the systems shared out
//              (solve_batch's workers, without the Interpolator around the solve);
//   lockstep   S threads, each system's loop against a LockstepGroup's proxy, the calls
//              served by the DeviceBatchStepper (hsi/cuda/batch_stepper.h).
// Per row: frames, seconds, frames/s, speed-up over one core, iterations per frame,
// certified and converged frames, and for lockstep the largest difference of its x from
// one core's (relative to |x|∞) and the frames whose iterations differ. Set-up (cores, the
// batch) is outside the timed part; one warm-up frame per system precedes each timing.
// Prints Markdown; exit status 3 if a frame is not certified or did not converge.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "bench_scenes.h"
#include "hsi/cuda/batch_stepper.h"
#include "hsi/cuda/clocks.h"
#include "hsi/cuda/newton_core.h"
#include "hsi/lockstep.h"

using namespace hsi;
namespace hc = hsi::cuda;

namespace {

using Clock = std::chrono::steady_clock;

struct Frames {
  std::vector<std::vector<NewtonResult>> results;  // [system][frame]
  double seconds = 0;
  LockstepGate<StepRequest>::Stats stats;  // lockstep: the timed pass's rounds
};

struct Job {
  const ShapeSetup* setup = nullptr;
  std::vector<Metric> first, last;  // the scene's first and last keyframes' metrics at G
  Eigen::VectorXd x0;               // the first keyframe in the reduced space
  int S = 0, F = 0;
  NewtonOptions options;
  bool rotation_invariant = true;

  // Frame f of system s: the blend at t = (f + 1 + s/S) / (F + 1).
  std::vector<Metric> targets(int s, int f) const {
    const double t = (f + 1 + static_cast<double>(s) / S) / (F + 1);
    std::vector<Metric> g(first.size());
    for (size_t i = 0; i < g.size(); ++i) g[i] = (1 - t) * first[i] + t * last[i];
    return g;
  }
};

// System s's frames [begin, end) through `stepper`, its targets set by `set`.
template <class Set>
void run_frames(const Job& job, NewtonStepper& stepper, int s, int begin, int end, KeptSystem& slot, Eigen::VectorXd& x,
                std::vector<NewtonResult>& out, Set&& set) {
  NewtonOptions o = job.options;
  o.kept_system = &slot;
  for (int f = begin; f < end; ++f) {
    set(job.targets(s, f));
    NewtonResult r = newton_run(stepper, true, job.rotation_invariant, x, o);
    x = r.x;
    out.push_back(std::move(r));
  }
}

Frames one_core(const Job& job) {
  Frames out;
  out.results.resize(size_t(job.S));
  auto core = hc::make_newton_core(*job.setup);
  std::vector<std::unique_ptr<NewtonStepper>> steppers;
  std::vector<KeptSystem> slots(size_t(job.S));
  std::vector<Eigen::VectorXd> x(size_t(job.S), job.x0);
  std::vector<std::vector<NewtonResult>> warm(size_t(job.S));
  for (int s = 0; s < job.S; ++s) steppers.push_back(core->make_stepper(job.setup->metric_space, &job.setup->certifier, nullptr));
  // One core keeps one factor: each system's frames in a row (the warm-up frame first).
  const auto t0 = Clock::now();
  double warm_s = 0;
  for (int s = 0; s < job.S; ++s) {
    const auto w0 = Clock::now();
    run_frames(job, *steppers[size_t(s)], s, 0, 1, slots[size_t(s)], x[size_t(s)], warm[size_t(s)],
               [&](const std::vector<Metric>& g) { core->set_targets(g); });
    warm_s += std::chrono::duration<double>(Clock::now() - w0).count();
    run_frames(job, *steppers[size_t(s)], s, 1, job.F, slots[size_t(s)], x[size_t(s)], out.results[size_t(s)],
               [&](const std::vector<Metric>& g) { core->set_targets(g); });
  }
  out.seconds = std::chrono::duration<double>(Clock::now() - t0).count() - warm_s;
  return out;
}

// Every system's first frame (a warm-up, untimed), then the rest into `into`, by `pass`
// (begin, end, results): the seconds of the timed pass.
template <class Pass>
double warm_then_timed(const Job& job, Pass& pass, std::vector<std::vector<NewtonResult>>& into) {
  std::vector<std::vector<NewtonResult>> warm(size_t(job.S));
  pass(0, 1, warm);
  const auto t0 = Clock::now();
  pass(1, job.F, into);
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

Frames workers(const Job& job, int W) {
  Frames out;
  out.results.resize(size_t(job.S));
  std::vector<std::unique_ptr<NewtonCore>> cores;
  for (int w = 0; w < W; ++w) cores.push_back(hc::make_newton_core(*job.setup));
  std::vector<KeptSystem> slots(size_t(job.S));
  std::vector<Eigen::VectorXd> x(size_t(job.S), job.x0);
  auto pass = [&](int begin, int end, std::vector<std::vector<NewtonResult>>& into) {
    std::vector<std::thread> threads;
    for (int w = 0; w < W; ++w)
      threads.emplace_back([&, w] {
        NewtonCore& core = *cores[size_t(w)];
        auto stepper = core.make_stepper(job.setup->metric_space, &job.setup->certifier, nullptr);
        for (int s = w; s < job.S; s += W) {
          // A worker's core keeps one factor: a system's slot from another frame range is stale
          // only if another system used the core since (then no chord step, as in solve_batch).
          run_frames(job, *stepper, s, begin, end, slots[size_t(s)], x[size_t(s)], into[size_t(s)],
                     [&](const std::vector<Metric>& g) { core.set_targets(g); });
        }
      });
    for (auto& t : threads) t.join();
  };
  out.seconds = warm_then_timed(job, pass, out.results);
  return out;
}

Frames lockstep(const Job& job, size_t* bytes) {
  Frames out;
  out.results.resize(size_t(job.S));
  auto batch = hc::make_batch_stepper(*job.setup, job.S);
  *bytes = batch->device_bytes();
  std::vector<KeptSystem> slots(size_t(job.S));
  std::vector<Eigen::VectorXd> x(size_t(job.S), job.x0);
  LockstepGate<StepRequest>::Stats stats;
  auto pass = [&](int begin, int end, std::vector<std::vector<NewtonResult>>& into) {
    LockstepGroup group(*batch);
    std::vector<std::thread> threads;
    std::vector<std::string> failed(size_t(job.S));
    for (int s = 0; s < job.S; ++s)
      threads.emplace_back([&, s] {
        try {
          auto proxy = group.stepper(s);
          run_frames(job, *proxy, s, begin, end, slots[size_t(s)], x[size_t(s)], into[size_t(s)],
                     [&](const std::vector<Metric>& g) { batch->set_targets(s, g); });
        } catch (const std::exception& e) {
          failed[size_t(s)] = e.what();
        }
        group.done();
      });
    for (auto& t : threads) t.join();
    for (int s = 0; s < job.S; ++s)
      if (!failed[size_t(s)].empty()) throw std::runtime_error("lockstep system " + std::to_string(s) + ": " + failed[size_t(s)]);
    stats = group.stats();
  };
  out.seconds = warm_then_timed(job, pass, out.results);
  out.stats = stats;
  return out;
}

// Where the lockstep row's wall time goes: each call kind's batches, their mean size
// and the time the serving thread spent in them; the rest is the systems' threads (their
// loops' own work and the hand-overs of every round).
void print_rounds(const Frames& f) {
  const LockstepGate<StepRequest>::Stats& s = f.stats;
  std::printf("lockstep rounds (timed frames): %llu rounds, %llu batches, %llu calls; serving %.1f ms of %.1f ms wall (%.0f%%), "
              "%.1f us per round outside serve\n\n",
              static_cast<unsigned long long>(s.rounds), static_cast<unsigned long long>(s.batches), static_cast<unsigned long long>(s.calls),
              1e3 * s.serve_s, 1e3 * f.seconds, 100 * s.serve_s / std::max(f.seconds, 1e-12),
              1e6 * (f.seconds - s.serve_s) / std::max<double>(1, static_cast<double>(s.rounds)));
  std::printf("| call | batches | mean batch | serve ms | us per batch |\n|---|---:|---:|---:|---:|\n");
  for (size_t k = 0; k < s.key_batches.size(); ++k)
    if (s.key_batches[k])
      std::printf("| %s | %llu | %.1f | %.1f | %.0f |\n", to_string(static_cast<StepRequest::Kind>(k)),
                  static_cast<unsigned long long>(s.key_batches[k]), double(s.key_calls[k]) / double(s.key_batches[k]),
                  1e3 * s.key_serve_s[k], 1e6 * s.key_serve_s[k] / double(s.key_batches[k]));
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Whole warm frames of S sequences of one setup: one core, W workers, and the lockstep batch (issue #23)"};
  std::vector<std::string> scenes = {"assets/bar_holes.json"};
  std::vector<int> systems = {16, 64};
  std::vector<std::string> exact_names = {"all"};
  int samples = 10000, frames = 20, workers_n = 16;
  double ratio = 0.2;
  app.add_option("scenes", scenes, "scene files (each needs two keyframes or more)");
  app.add_option("--systems", systems, "batch sizes S")->delimiter(',');
  app.add_option("--frames", frames, "frames per system (the first a warm-up, untimed)")->check(CLI::Range(2, 100000));
  app.add_option("--workers", workers_n, "W for the workers' row (0: no such row)");
  app.add_option("--samples", samples, "|G|");
  app.add_option("--ratio", ratio, "r = |H| / |G|");
  app.add_option("--exact-samples", exact_names, "the exact systems' samples, one row set each")->delimiter(',')->check(CLI::IsMember(exact_samples_names()));
  CLI11_PARSE(app, argc, argv);
  std::string why;
  if (!hc::device_available(&why)) {
    std::fprintf(stderr, "bench_batch_stepper: no CUDA device: %s\n", why.c_str());
    return 1;
  }
  std::printf("# Warm frames of S sequences of one setup: one core, %d workers, lockstep (%s)\n\n", workers_n,
              hc::clocks().describe().c_str());
  std::printf("|G| = %d, r = %.2f, %d frames per system (the first untimed), targets blended from the first to the last "
              "keyframe, each frame from the last with its kept factor; frames/s over the timed frames.\n\n",
              samples, ratio, frames);
  bool all_good = true;
  for (const std::string& path : scenes) {
    bench::Loaded L = bench::load(path, samples, ratio);
    const ShapeSetup& setup = *L.setup;
    const auto rows = evaluate_basis(setup.cage, setup.G.points, kBasisD);
    auto metrics = [&](const HarmonicMap& m) {
      const MapValues v = evaluate_map(rows, m);
      return pullback_metrics(v.f_z, v.fzbar_conj);
    };
    for (const std::string& en : exact_names) {
      for (const int S : systems) {
        Job job;
        job.setup = &setup;
        job.first = metrics(L.maps.front());
        job.last = metrics(L.maps.back());
        job.x0 = setup.metric_space.reduce(L.maps.front()).x;
        job.S = S;
        job.F = frames;
        job.options.exact_samples = parse_exact_samples(en);
        if (job.options.exact_samples == ExactSamples::Auto) job.options.exact_samples = ExactSamples::All;  // the CUDA core's
        job.rotation_invariant = setup.metric_space.gauge() == Gauge::ModuloRigid;
        std::printf("## %s, S = %d, exact systems over %s (n = %d, |G| = %d, |H| = %zu, dim = %d)\n\n", L.name.c_str(), S,
                    to_string(job.options.exact_samples), setup.metric_space.n(), int(setup.D_G.rows()), setup.H.size(),
                    setup.metric_space.dim());
        std::printf("| path | frames | s | frames/s | speed-up | iterations / frame | certified | converged | max |Δx| / |x|∞ vs one core | "
                    "frames with other iterations |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        std::fflush(stdout);
        const Frames base = one_core(job);
        size_t bytes = 0;
        std::vector<std::pair<std::string, Frames>> rows_out;
        rows_out.push_back({"one core", base});
        if (workers_n > 0) rows_out.push_back({std::to_string(workers_n) + " workers", workers(job, workers_n)});
        rows_out.push_back({"lockstep", lockstep(job, &bytes)});
        const double timed = double(S) * (frames - 1);
        for (const auto& [name, fr] : rows_out) {
          int its = 0, certified = 0, converged = 0, other = 0;
          double diff = 0;
          for (int s = 0; s < S; ++s)
            for (int f = 0; f + 1 < frames; ++f) {
              const NewtonResult& r = fr.results[size_t(s)][size_t(f)];
              const NewtonResult& b = base.results[size_t(s)][size_t(f)];
              its += r.iterations;
              certified += r.certified;
              converged += r.converged;
              other += r.iterations != b.iterations;
              diff = std::max(diff, (r.x - b.x).cwiseAbs().maxCoeff() / std::max(1e-300, b.x.cwiseAbs().maxCoeff()));
            }
          all_good = all_good && certified == int(timed) && converged == int(timed);
          std::printf("| %s | %.0f | %.3f | %.0f | %.2f× | %.2f | %.0f%s | %d | %.1e | %d |\n", name.c_str(), timed, fr.seconds,
                      timed / fr.seconds, base.seconds / fr.seconds, its / timed, double(certified),
                      certified == int(timed) ? "" : " (NOT all certified)", converged, diff, other);
        }
        std::printf("\nlockstep batch device memory: %.1f MB (%.2f MB per system)\n\n", double(bytes) / 1e6, double(bytes) / 1e6 / S);
        print_rounds(rows_out.back().second);
        std::fflush(stdout);
      }
    }
  }
  return all_good ? 0 : 3;
}
