// Newton loops of many systems stepped together (issue #23: the lockstep batch). Each
// system's loop (newton_run, unchanged) runs on its own thread against a proxy
// NewtonStepper whose calls go through one LockstepGate per group; once every live
// thread has posted, each kind of call is served as one batch by the group's
// BatchStepper. A backend's batched stepper (one launch per kind of call for the whole
// group) implements BatchStepper; SerialBatchStepper serves each system with its own
// stepper, one after another: the reference it is tested against, and what the CPU uses.
// The design and what it would reach on the GPU: bench/results/lockstep_stages_2026-12-07.md.
#pragma once

#include <exception>
#include <memory>
#include <span>
#include <vector>

#include "hsi/lockstep_gate.h"
#include "hsi/newton.h"

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
  explicit LockstepGroup(BatchStepper& batch);
  std::unique_ptr<NewtonStepper> stepper(int system);
  void done() { gate_.leave(); }
  LockstepGate<StepRequest>::Stats stats() const { return gate_.stats(); }

 private:
  BatchStepper& batch_;
  LockstepGate<StepRequest> gate_;
};

}  // namespace hsi
