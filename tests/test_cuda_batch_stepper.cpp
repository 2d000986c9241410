// The lockstep batch's device stepper (hsi/cuda/batch_stepper.h, issue #23): systems of
// one setup solved together through a LockstepGroup served by the DeviceBatchStepper get
// the solves each gets alone with the CUDA core's own stepper: the same verdicts and
// iterations, x and the energy as close as the Newton stop tests leave them (the
// batched products sum in other orders than one system's). Three frames per system
// carry a kept factor (chord steps), with the exact systems over H and over G (the CUDA
// default), on two shapes. Needs a GPU (skips with a warning without one).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include "bench_scenes.h"
#include "cuda_test.h"
#include "hsi/batch.h"
#include "hsi/cage.h"
#include "hsi/cuda/batch_stepper.h"
#include "hsi/cuda/newton_core.h"
#include "hsi/lockstep.h"
#include "hsi/newton.h"
#include "hsi/runtime/backend.h"
#include "hsi/shape_setup.h"
#include "test_shapes.h"
#include "test_targets.h"

using namespace hsi;
using hsi::test::perturbed;

TEST_CASE("the batch's device stepper: bad sizes are refused", "[cuda][lockstep][batch]") {
  const Shape shape = test::annulus();
  const ShapeSetup setup(shape, build_cage(shape), 500, 0.3);
  CHECK_THROWS_WITH(cuda::make_batch_stepper(setup, 0), Catch::Contains("0 systems"));
  CHECK_THROWS_WITH(cuda::make_batch_stepper(setup, 70000), Catch::Contains("70000 systems"));
  HSI_REQUIRE_GPU();
  auto batch = cuda::make_batch_stepper(setup, 2);
  CHECK_THROWS_WITH(batch->set_targets(2, {}), Catch::Contains("system 2 of 2"));
  CHECK_THROWS_WITH(batch->set_targets(1, std::vector<Metric>(3)), Catch::Contains("3 target metrics for 500 samples"));
}

TEST_CASE("systems solved together by the batch's device stepper get their solves alone", "[cuda][lockstep][batch]") {
  HSI_REQUIRE_GPU();
  for (const Shape& shape : {test::annulus(), test::bar_with_holes()}) {
    const ShapeSetup setup(shape, build_cage(shape), 2000, 0.2);
    const MapSpace& space = setup.metric_space;
    const Eigen::VectorXd id = space.reduce(identity_map(setup.cage)).x;
    const bool rotation_invariant = space.gauge() == Gauge::ModuloRigid;
    constexpr int S = 6, kFrames = 3;
    // System s: three frames' targets from maps near the identity, farther each frame,
    // one system moved by a larger amount (more iterations).
    std::vector<std::vector<std::vector<Metric>>> targets(S);
    for (int s = 0; s < S; ++s)
      for (int f = 0; f < kFrames; ++f)
        targets[size_t(s)].push_back(test::metrics_of(setup, perturbed(id, 31u * unsigned(s) + unsigned(f), (s == 3 ? 0.03 : 0.015) + 0.005 * f)));
    for (const ExactSamples exact : {ExactSamples::Subset, ExactSamples::All}) {
      INFO("exact systems over " << to_string(exact));
      NewtonOptions options;
      options.exact_samples = exact;

      // Alone: the CUDA core's own stepper, one system's frames after another (its kept
      // factor is the core's; no other system comes between its frames).
      std::vector<std::vector<NewtonResult>> alone(S);
      {
        auto core = cuda::make_newton_core(setup);
        for (int s = 0; s < S; ++s) {
          auto stepper = core->make_stepper(space, &setup.certifier, nullptr);
          REQUIRE(stepper);
          alone[size_t(s)] = test::solve_frames(*stepper, [&](const std::vector<Metric>& g) { core->set_targets(g); },
                                                targets[size_t(s)], id, options, rotation_invariant);
        }
      }

      // Together: every system's loop on its thread, the calls served by the batch.
      auto batch = cuda::make_batch_stepper(setup, S);
      LockstepGroup group(*batch);
      std::vector<std::vector<NewtonResult>> together(S);
      std::vector<std::string> failed(S);
      std::vector<std::thread> threads;
      for (int s = 0; s < S; ++s)
        threads.emplace_back([&, s] {
          try {
            auto proxy = group.stepper(s);
            together[size_t(s)] = test::solve_frames(*proxy, [&](const std::vector<Metric>& g) { batch->set_targets(s, g); },
                                                     targets[size_t(s)], id, options, rotation_invariant);
          } catch (const std::exception& e) {
            failed[size_t(s)] = e.what();
          }
          group.done();
        });
      for (auto& t : threads) t.join();

      int iterations = 0;
      for (int s = 0; s < S; ++s) {
        INFO("system " << s);
        REQUIRE(failed[size_t(s)].empty());
        REQUIRE(together[size_t(s)].size() == size_t(kFrames));
        for (int f = 0; f < kFrames; ++f) {
          INFO("frame " << f);
          const NewtonResult &a = alone[size_t(s)][size_t(f)], &b = together[size_t(s)][size_t(f)];
          CHECK(a.converged);
          CHECK(a.certified);
          CHECK(b.converged == a.converged);
          CHECK(b.certified == a.certified);
          CHECK(b.stop == a.stop);
          CHECK(b.iterations == a.iterations);
          // Both stop at the Newton tolerances, from products summed in other orders: x
          // agrees to what the stop tests leave (bench_batch_stepper, H100: ≤ 3.2e-6 of
          // |x|∞ over 704 frames), and so do the maps' metrics at the samples; the energy
          // closer. (An H100 run of 2026-12-08 saw x 1.2e-2 of |x|∞ apart with the same
          // iterations and energies: the batch's start left the rotation slot of [x; 0]
          // to whatever the pinned staging held, so its trial points moved along u.)
          const double scale = a.x.cwiseAbs().maxCoeff();
          CHECK((b.x - a.x).cwiseAbs().maxCoeff() <= 1e-4 * scale);
          const std::vector<Metric> ma = test::metrics_of(setup, a.x), mb = test::metrics_of(setup, b.x);
          double metric_diff = 0, metric_scale = 0;
          for (size_t i = 0; i < ma.size(); ++i) {
            metric_diff = std::max(metric_diff, (mb[i] - ma[i]).cwiseAbs().maxCoeff());
            metric_scale = std::max(metric_scale, ma[i].cwiseAbs().maxCoeff());
          }
          CHECK(metric_diff <= 1e-4 * metric_scale);
          CHECK(std::abs(b.energy - a.energy) <= 1e-8 * std::abs(a.energy));
          iterations += a.iterations;
        }
      }
      CHECK(iterations > S * kFrames);  // not every frame one step: line searches, exact systems, chords
      const auto stats = group.stats();
      INFO("rounds " << stats.rounds << ", batches " << stats.batches << ", calls " << stats.calls);
      CHECK(stats.rounds < stats.calls);  // some calls of several systems served together
    }
  }
}

namespace {

using Kind = StepRequest::Kind;

// What a tee saw: per call kind and result, the largest relative difference between the
// device batch's result and the reference's, and every verdict that differed.
struct TeeLog {
  std::mutex mutex;
  std::map<std::string, double> largest;  // "kind field" → max |a − b| / max(|a|, |b|)
  std::vector<std::string> verdicts;       // the first verdicts that differed
  size_t verdicts_differing = 0, calls = 0;
  void number(Kind k, const char* field, double device, double ref) {
    const double scale = std::max({std::abs(device), std::abs(ref), 1e-300});
    double d = std::isnan(device) && std::isnan(ref) ? 0.0 : std::abs(device - ref) / scale;
    if (std::isnan(d)) d = 1;
    double& m = largest[std::string(to_string(k)) + " " + field];
    m = std::max(m, d);
  }
  void verdict(Kind k, int system, const char* field, bool device, bool ref) {
    if (device == ref) return;
    ++verdicts_differing;
    if (verdicts.size() < 20)
      verdicts.push_back(std::string("call ") + std::to_string(calls) + " " + to_string(k) + " system " + std::to_string(system) + ": " +
                         field + " device " + (device ? "true" : "false") + ", reference " + (ref ? "true" : "false"));
  }
};

// The device batch and, beside it, the reference for the same calls: each system its own
// CUDA core and that core's own stepper (make_serial_lockstep_backend), a batch served
// one call after another. The loops follow the device's results; after every accepted
// step the reference restarts at the device's x, so that each call compares the two on
// the same point.
class TeeBackend final : public LockstepBackend, public BatchStepper {
 public:
  TeeBackend(const ShapeSetup& setup, int systems, TeeLog& log)
      : device_(cuda::make_batch_stepper(setup, systems)),
        ref_(make_serial_lockstep_backend(setup, systems, [&setup] { return cuda::make_newton_core(setup); })),
        log_(log) {}
  BatchStepper& batch() override { return *this; }
  int systems() const override { return device_->systems(); }
  void set_targets(int system, const std::vector<Metric>& g) override {
    device_->set_targets(system, g);
    ref_->set_targets(system, g);
  }
  ExactSamples preferred_exact_samples() const override { return device_->preferred_exact_samples(); }
  std::optional<CertificateResult> certify_map(const Certifier& certifier, const HarmonicMap& map) override {
    return device_->certify_map(certifier, map);
  }

  void serve(Kind kind, std::span<StepRequest* const> batch) override {
    std::vector<StepRequest> ref(batch.size());
    std::vector<std::vector<double>> energies(batch.size());
    std::vector<StepRequest*> ref_ptrs;
    for (size_t i = 0; i < batch.size(); ++i) {
      const StepRequest& r = *batch[i];
      StepRequest& c = ref[i];
      c.kind = r.kind;
      c.system = r.system;
      c.x0 = r.x0;
      c.choice = r.choice;
      c.number = r.number;
      c.full = r.full;
      c.steps = r.steps;
      energies[i].assign(r.energies.size(), 0.0);
      c.energies = energies[i];
      if (r.slot) c.slot = &slots_[r.slot];
      if (r.kept) {
        const auto it = slots_.find(r.kept);
        c.kept = it == slots_.end() ? &none_ : &it->second;
      }
      ref_ptrs.push_back(&c);
    }
    ref_->batch().serve(kind, ref_ptrs);
    device_->serve(kind, batch);
    std::lock_guard<std::mutex> lock(log_.mutex);
    for (size_t i = 0; i < batch.size(); ++i) {
      const StepRequest &d = *batch[i], &c = ref[i];
      ++log_.calls;
      log_.verdict(kind, d.system, "threw", d.error != nullptr, c.error != nullptr);
      if (d.error || c.error) continue;
      switch (kind) {
        case Kind::Start:
        case Kind::StartEnergy: log_.number(kind, "energy", d.energy, c.energy); break;
        case Kind::Solve:
        case Kind::Decrement:
        case Kind::Direction: {
          const NewtonSystem &a = d.system_result, &b = c.system_result;
          log_.verdict(kind, d.system, "factored", a.factored, b.factored);
          log_.verdict(kind, d.system, "has_direction", a.has_direction, b.has_direction);
          log_.number(kind, "slope", a.slope, b.slope);
          log_.number(kind, "gradient_norm", a.gradient_norm, b.gradient_norm);
          log_.number(kind, "diagonal_max", a.diagonal_max, b.diagonal_max);
          if (a.has_direction) log_.number(kind, "max_safe_step", a.max_safe_step, b.max_safe_step);
          break;
        }
        case Kind::TrialEnergies:
          for (size_t j = 0; j < d.energies.size(); ++j) log_.number(kind, "energy", d.energies[j], energies[i][j]);
          break;
        case Kind::Certify:
          log_.verdict(kind, d.system, "certified", d.certificate.certified, c.certificate.certified);
          if (d.certificate.certified && c.certificate.certified) log_.number(kind, "k_max", d.certificate.k_max, c.certificate.k_max);
          break;
        case Kind::Keep:
        case Kind::LinearizeKept: log_.verdict(kind, d.system, "ok", d.ok, c.ok); break;
        default: break;
      }
      if (kind == Kind::X && d.x.size() == c.x.size())
        log_.largest["x relative"] = std::max(log_.largest["x relative"], (d.x - c.x).lpNorm<Eigen::Infinity>() /
                                                                              std::max(d.x.lpNorm<Eigen::Infinity>(), 1e-300));
    }
    if (kind == Kind::Accept) resync(batch);
  }

 private:
  // The reference restarted at the device's x for the systems of an accept.
  void resync(std::span<StepRequest* const> batch) {
    std::vector<StepRequest> xs(batch.size()), starts(batch.size());
    std::vector<StepRequest*> xp, sp;
    for (size_t i = 0; i < batch.size(); ++i) {
      if (batch[i]->error) continue;
      xs[i].kind = Kind::X;
      xs[i].system = batch[i]->system;
      xp.push_back(&xs[i]);
    }
    if (xp.empty()) return;
    device_->serve(Kind::X, xp);
    for (size_t i = 0; i < batch.size(); ++i) {
      if (batch[i]->error || xs[i].error) continue;
      starts[i].kind = Kind::Start;
      starts[i].system = batch[i]->system;
      starts[i].x0 = &xs[i].x;
      sp.push_back(&starts[i]);
    }
    if (!sp.empty()) ref_->batch().serve(Kind::Start, sp);
  }

  std::unique_ptr<cuda::DeviceBatchStepper> device_;
  std::unique_ptr<LockstepBackend> ref_;
  TeeLog& log_;
  std::map<const KeptSystem*, KeptSystem> slots_;  // the caller's slot → the reference's
  KeptSystem none_;
};

}  // namespace

TEST_CASE("solve_batch in lockstep on the device's batched stepper: every call as the CUDA core's own stepper serves it",
          "[cuda][lockstep][batch][tee]") {
  HSI_REQUIRE_GPU();
  // The bundled scenes at their own |G|, four sequences each (bench_batch's: uniform
  // frames, and every keyframe time a frame), in groups of 16 systems.
  std::vector<bench::Loaded> scenes = bench::load_folder(HSI_ASSETS_DIR, 0, 0, "test");
  REQUIRE(!scenes.empty());
  std::vector<BatchSequence> sequences;
  for (int repeat = 0; repeat < 4; ++repeat)
    for (const bench::Loaded& L : scenes) sequences.push_back(bench::batch_sequence(L, repeat, 60 + 7 * repeat));
  TeeLog log;
  BatchOptions o;
  runtime::set_batch_backend(o, runtime::Backend::Cuda, runtime::cuda_status());  // each thread's boundary image on the GPU, as hsi bake
  o.lockstep_systems = 16;
  o.make_lockstep = [&log](const ShapeSetup& setup, int n) { return std::make_unique<TeeBackend>(setup, n, log); };
  const BatchResult tee = solve_batch(sequences, o);
  // The reference backend alone: the loops follow its own results.
  o.make_lockstep = [](const ShapeSetup& setup, int n) {
    return make_serial_lockstep_backend(setup, n, [&setup] { return cuda::make_newton_core(setup); });
  };
  const BatchResult ref = solve_batch(sequences, o);
  // The device batch alone, as bench_batch --lockstep runs it.
  runtime::set_batch_lockstep(o, runtime::Backend::Cuda, 16);
  const BatchResult alone = solve_batch(sequences, o);
  size_t converged_alone = 0;
  for (size_t q = 0; q < alone.sequences.size(); ++q) {
    CHECK(alone.sequences[q].error == "");
    for (const FrameResult& f : alone.sequences[q].frames) {
      converged_alone += f.converged;
      if (!f.converged)
        std::printf("  device batch alone: %s t = %.4f not converged (%s, %d iterations)\n", sequences[q].name.c_str(), f.t,
                    to_string(f.stop), f.iterations);
    }
  }
  size_t frames = 0, converged = 0, converged_ref = 0, certified = 0;
  for (size_t s = 0; s < sequences.size(); ++s) {
    INFO(sequences[s].name);
    CHECK(tee.sequences[s].error == "");
    CHECK(ref.sequences[s].error == "");
    for (const FrameResult& f : tee.sequences[s].frames) {
      ++frames;
      converged += f.converged;
      certified += f.certified;
      if (!f.converged) std::printf("  device batch: %s t = %.4f not converged (%s, %d iterations)\n", sequences[s].name.c_str(), f.t, to_string(f.stop), f.iterations);
    }
    for (const FrameResult& f : ref.sequences[s].frames) converged_ref += f.converged;
  }
  std::printf("tee over %zu calls: %zu frames, %zu certified, %zu converged (reference alone: %zu, device batch alone: %zu); %zu verdicts differ\n",
              log.calls, frames, certified, converged, converged_ref, converged_alone, log.verdicts_differing);
  for (const std::string& v : log.verdicts) std::printf("  %s\n", v.c_str());
  for (const auto& [what, d] : log.largest) std::printf("  largest relative difference, %s: %.3g\n", what.c_str(), d);
  CHECK(certified == frames);
  CHECK(log.verdicts_differing == 0);
  CHECK(converged == converged_ref);
  CHECK(converged == frames);
  CHECK(converged_alone == frames);
  // The same points (the reference restarted at the device's x): energies there alike to
  // the sums' order; along d, which the two factorisations (potrfBatched, the core's own)
  // give alike to ~1e-5, the trial energies to ~1e-6.
  CHECK(log.largest["start energy"] < 1e-12);
  CHECK(log.largest["x relative"] < 1e-12);
  CHECK(log.largest["trial_energies energy"] < 1e-5);
}
