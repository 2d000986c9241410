// Newton loops of many systems stepped together (issue #23: the lockstep batch). Each
// system's loop (newton_run, unchanged) runs on its own thread against a proxy
// NewtonStepper whose calls go through one LockstepGate per group; once every live
// thread has posted, each kind of call is served as one batch by the group's
// BatchStepper. The calls a loop does not wait for (start_deferred, linearize,
// certify_ahead, accept) travel with its next call that it does wait for, as one chain
// (LockstepGate::call): a round per waited-for call, not per call. A backend's batched
// stepper (one launch per kind of call for the whole group) implements BatchStepper;
// SerialBatchStepper serves each system with its own stepper, one after another: the
// reference it is tested against, and what the CPU uses. The design and what it would
// reach on the GPU: bench/results/lockstep_stages_2026-12-07.md.
#pragma once

#include <chrono>
#include <exception>
#include <functional>
#include <optional>
#include <memory>
#include <span>
#include <vector>

#include "hsi/lockstep_gate.h"
#include "hsi/newton.h"
#include "hsi/shape_setup.h"

namespace hsi {

// One NewtonStepper call of one system: its arguments and, once served, its results.
struct StepRequest {
  enum class Kind : int {
    Start,
    StartDeferred,
    StartEnergy,
    Linearize,
    Solve,
    Decrement,
    Direction,
    TrialEnergies,
    Certify,
    CertifyAhead,
    Accept,
    X,
    Keep,
    LinearizeKept,
  };
  Kind kind = Kind::Start;
  int system = 0;
  // Arguments (those of the call's kind).
  const Eigen::VectorXd* x0 = nullptr;     // Start, StartDeferred
  const HessianChoice* choice = nullptr;   // Linearize
  double number = 0;                       // Solve / Decrement: the ridge; Certify, CertifyAhead, Accept: the step
  bool full = false;                       // Certify
  std::span<const double> steps;           // TrialEnergies
  std::span<double> energies;              // TrialEnergies: written
  KeptSystem* slot = nullptr;              // Keep: written
  const KeptSystem* kept = nullptr;        // LinearizeKept
  // Results.
  double energy = 0;                       // Start, StartEnergy
  NewtonSystem system_result;              // Solve, Decrement, Direction
  CertificateResult certificate;           // Certify
  Eigen::VectorXd x;                       // X
  bool ok = false;                         // Keep, LinearizeKept
  std::exception_ptr error;                // what this system's call threw (rethrown to its loop alone)
};

// "start", "start_deferred", …, "linearize_kept": the NewtonStepper call's name.
const char* to_string(StepRequest::Kind kind);

// A group's steppers: serve() makes the calls of one batch (all of one kind, each for
// its own system < systems()), writing each request's results.
class BatchStepper {
 public:
  virtual ~BatchStepper() = default;
  virtual int systems() const = 0;
  virtual void serve(StepRequest::Kind kind, std::span<StepRequest* const> batch) = 0;
};

// Each system's own stepper, the batch's calls made one after another.
class SerialBatchStepper final : public BatchStepper {
 public:
  explicit SerialBatchStepper(std::vector<std::unique_ptr<NewtonStepper>> steppers);
  int systems() const override { return static_cast<int>(steppers_.size()); }
  void serve(StepRequest::Kind kind, std::span<StepRequest* const> batch) override;

 private:
  static void serve_one(NewtonStepper& s, StepRequest& r);
  std::vector<std::unique_ptr<NewtonStepper>> steppers_;
};

// The systems of one group stepped together: stepper(s) is system s's proxy for
// newton_run on its own thread; a thread whose loop has ended (returned or thrown) calls
// done(), so that the others stop waiting for it. Every system's thread must either run
// its loop and call done() or just call done().
class LockstepGroup {
 public:
  // window: how long a call waits for the systems not yet at the gate before its round
  // is served without them (LockstepGate; zero: until every live system has posted).
  explicit LockstepGroup(BatchStepper& batch, std::chrono::microseconds window = std::chrono::microseconds::zero());
  std::unique_ptr<NewtonStepper> stepper(int system);
  void done() { gate_.leave(); }
  LockstepGate<StepRequest>::Stats stats() const { return gate_.stats(); }

 private:
  BatchStepper& batch_;
  LockstepGate<StepRequest> gate_;
};

// What a batch needs of a backend to step a setup's sequences in lockstep (solve_batch,
// BatchOptions::make_lockstep): the batched stepper of `systems` systems and each
// system's targets. set_targets(s, ·) is called from system s's own thread between its
// solves (while other systems' calls are served). certify_map: a keyframe's
// certificate on the backend where it can (NewtonCore::certify_map; called from any
// of the group's threads, so it serialises itself), else nullopt (the host certifies).
class LockstepBackend {
 public:
  virtual ~LockstepBackend() = default;
  virtual BatchStepper& batch() = 0;
  virtual void set_targets(int system, const std::vector<Metric>& g) = 0;
  virtual ExactSamples preferred_exact_samples() const { return ExactSamples::Subset; }
  virtual std::optional<CertificateResult> certify_map(const Certifier& /*certifier*/, const HarmonicMap& /*map*/) {
    return std::nullopt;
  }
};

// The reference backend: a core per system (made by `make_core`, e.g. the CPU core),
// each system's stepper that core's own (or the host stepper over it) for the setup's
// interpolation space and certifier, served one after another (SerialBatchStepper).
std::unique_ptr<LockstepBackend> make_serial_lockstep_backend(const ShapeSetup& setup, int systems,
                                                              const std::function<std::unique_ptr<NewtonCore>()>& make_core);

// System s of a lockstep group as a NewtonCore for an Interpolator of `setup`: its
// targets go to the backend's system s, its stepper for the setup's interpolation space
// (with the setup's certifier or none, no quadratic term) is the group's proxy s. It
// only steps: energy(), gradient() and the other per-call methods throw std::logic_error,
// and make_stepper for any other space returns null (newton_solve would then drive it
// through the host stepper, which calls them): an Interpolator solves only in that space.
std::unique_ptr<NewtonCore> make_lockstep_core(const ShapeSetup& setup, LockstepBackend& backend, LockstepGroup& group, int system);

}  // namespace hsi
