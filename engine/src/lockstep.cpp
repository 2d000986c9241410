// The lockstep group's proxy stepper and the serial batch stepper (hsi/lockstep.h).
#include "hsi/lockstep.h"

#include <deque>
#include <stdexcept>
#include <string>

namespace hsi {

namespace {

using Kind = StepRequest::Kind;

// System s's NewtonStepper: each call a request through the group's gate. The calls
// whose results the loop does not wait for (start_deferred, linearize, certify_ahead,
// accept: void) are held and posted as one chain with the next call that it does wait
// for, so that they cost no round of their own; the system's calls are served in the
// order it made them, and what a held call threw is rethrown by the call it travelled
// with (the loop's next, before it could have used the held call's effect).
class ProxyStepper final : public NewtonStepper {
 public:
  ProxyStepper(LockstepGate<StepRequest>& gate, int system) : gate_(gate), system_(system) {}
  ~ProxyStepper() override {
    // Held calls that no call followed (a loop that ended on one): served now, since
    // the backend's state for this system carries over to its next stepper.
    if (held_.empty()) return;
    try {
      flush(nullptr);
    } catch (...) {
      // (no loop is left to tell)
    }
  }

  double start(const Eigen::VectorXd& x0) override {
    StepRequest r = request(Kind::Start);
    r.x0 = &x0;
    post(r);
    return r.energy;
  }
  void start_deferred(const Eigen::VectorXd& x0) override {
    Held& h = hold(Kind::StartDeferred);
    h.x0 = x0;
    h.r.x0 = &h.x0;
  }
  double start_energy() override {
    StepRequest r = request(Kind::StartEnergy);
    post(r);
    return r.energy;
  }
  void linearize(const HessianChoice& choice) override {
    Held& h = hold(Kind::Linearize);
    h.choice = choice;
    h.r.choice = &h.choice;
  }
  NewtonSystem solve(double ridge) override { return system_call(Kind::Solve, ridge); }
  NewtonSystem decrement(double ridge) override { return system_call(Kind::Decrement, ridge); }
  NewtonSystem direction() override { return system_call(Kind::Direction, 0); }
  void trial_energies(std::span<const double> steps, std::span<double> energies) override {
    StepRequest r = request(Kind::TrialEnergies);
    r.steps = steps;
    r.energies = energies;
    post(r);
  }
  CertificateResult certify(double step, bool full) override {
    StepRequest r = request(Kind::Certify);
    r.number = step;
    r.full = full;
    post(r);
    return std::move(r.certificate);
  }
  void certify_ahead(double step) override { hold(Kind::CertifyAhead).r.number = step; }
  void accept(double step) override { hold(Kind::Accept).r.number = step; }
  Eigen::VectorXd x() override {
    StepRequest r = request(Kind::X);
    post(r);
    return std::move(r.x);
  }
  bool keep(KeptSystem& slot) override {
    StepRequest r = request(Kind::Keep);
    r.slot = &slot;
    post(r);
    return r.ok;
  }
  bool linearize_kept(const KeptSystem& slot) override {
    StepRequest r = request(Kind::LinearizeKept);
    r.kept = &slot;
    post(r);
    return r.ok;
  }

 private:
  // A held call and the arguments it keeps (the loop's may not outlive the call).
  struct Held {
    StepRequest r;
    Eigen::VectorXd x0;
    HessianChoice choice;
  };

  StepRequest request(Kind kind) const {
    StepRequest r;
    r.kind = kind;
    r.system = system_;
    return r;
  }
  Held& hold(Kind kind) {
    held_.emplace_back();
    held_.back().r = request(kind);
    return held_.back();
  }
  // The held calls, then `last` (if any), as one chain; the first error among them rethrown.
  void flush(StepRequest* last) {
    std::vector<StepRequest*> chain;
    std::vector<int> keys;
    for (Held& h : held_) {
      chain.push_back(&h.r);
      keys.push_back(static_cast<int>(h.r.kind));
    }
    if (last) {
      chain.push_back(last);
      keys.push_back(static_cast<int>(last->kind));
    }
    std::deque<Held> held;
    held.swap(held_);
    gate_.call(std::span<StepRequest* const>(chain), std::span<const int>(keys));
    for (StepRequest* r : chain)
      if (r->error) std::rethrow_exception(r->error);
  }
  void post(StepRequest& r) { flush(&r); }
  NewtonSystem system_call(Kind kind, double ridge) {
    StepRequest r = request(kind);
    r.number = ridge;
    post(r);
    return r.system_result;
  }

  LockstepGate<StepRequest>& gate_;
  int system_;
  std::deque<Held> held_;  // (a deque: the requests' addresses stay put)
};

}  // namespace

const char* to_string(StepRequest::Kind kind) {
  switch (kind) {
    case Kind::Start: return "start";
    case Kind::StartDeferred: return "start_deferred";
    case Kind::StartEnergy: return "start_energy";
    case Kind::Linearize: return "linearize";
    case Kind::Solve: return "solve";
    case Kind::Decrement: return "decrement";
    case Kind::Direction: return "direction";
    case Kind::TrialEnergies: return "trial_energies";
    case Kind::Certify: return "certify";
    case Kind::CertifyAhead: return "certify_ahead";
    case Kind::Accept: return "accept";
    case Kind::X: return "x";
    case Kind::Keep: return "keep";
    case Kind::LinearizeKept: return "linearize_kept";
  }
  return "unknown";
}

SerialBatchStepper::SerialBatchStepper(std::vector<std::unique_ptr<NewtonStepper>> steppers) : steppers_(std::move(steppers)) {
  for (const auto& s : steppers_)
    if (!s) throw std::invalid_argument("SerialBatchStepper: a null stepper");
}

void SerialBatchStepper::serve(Kind kind, std::span<StepRequest* const> batch) {
  for (StepRequest* r : batch) {
    if (r->system < 0 || r->system >= systems() || r->kind != kind)
      throw std::logic_error("SerialBatchStepper: a request for system " + std::to_string(r->system) + " of " +
                             std::to_string(systems()) + " or of another kind");
    NewtonStepper& s = *steppers_[static_cast<size_t>(r->system)];
    try {
      serve_one(s, *r);
    } catch (...) {
      r->error = std::current_exception();  // this system's loop alone
    }
  }
}

void SerialBatchStepper::serve_one(NewtonStepper& s, StepRequest& r) {
  switch (r.kind) {
    case Kind::Start: r.energy = s.start(*r.x0); break;
    case Kind::StartDeferred: s.start_deferred(*r.x0); break;
    case Kind::StartEnergy: r.energy = s.start_energy(); break;
    case Kind::Linearize: s.linearize(*r.choice); break;
    case Kind::Solve: r.system_result = s.solve(r.number); break;
    case Kind::Decrement: r.system_result = s.decrement(r.number); break;
    case Kind::Direction: r.system_result = s.direction(); break;
    case Kind::TrialEnergies: s.trial_energies(r.steps, r.energies); break;
    case Kind::Certify: r.certificate = s.certify(r.number, r.full); break;
    case Kind::CertifyAhead: s.certify_ahead(r.number); break;
    case Kind::Accept: s.accept(r.number); break;
    case Kind::X: r.x = s.x(); break;
    case Kind::Keep: r.ok = s.keep(*r.slot); break;
    case Kind::LinearizeKept: r.ok = s.linearize_kept(*r.kept); break;
  }
}

LockstepGroup::LockstepGroup(BatchStepper& batch, std::chrono::microseconds window)
    : batch_(batch),
      gate_(
          batch.systems(),
          [this](int key, std::span<StepRequest* const> requests) { batch_.serve(static_cast<StepRequest::Kind>(key), requests); },
          [](const StepRequest& r) { return r.error != nullptr; }, window) {}

std::unique_ptr<NewtonStepper> LockstepGroup::stepper(int system) {
  if (system < 0 || system >= batch_.systems())
    throw std::invalid_argument("LockstepGroup: system " + std::to_string(system) + " of " + std::to_string(batch_.systems()));
  return std::make_unique<ProxyStepper>(gate_, system);
}

namespace {

class SerialLockstepBackend final : public LockstepBackend {
 public:
  SerialLockstepBackend(const ShapeSetup& setup, int systems, const std::function<std::unique_ptr<NewtonCore>()>& make_core) {
    if (systems < 1) throw InputError("a lockstep group needs at least 1 system (got " + std::to_string(systems) + ")");
    std::vector<std::unique_ptr<NewtonStepper>> steppers;
    for (int s = 0; s < systems; ++s) {
      cores_.push_back(make_core());
      if (!cores_.back()) throw InputError("the core factory made no core");
      std::unique_ptr<NewtonStepper> st = cores_.back()->make_stepper(setup.metric_space, &setup.certifier, nullptr);
      steppers.push_back(st ? std::move(st) : make_host_stepper(*cores_.back(), setup.metric_space, &setup.certifier, nullptr));
    }
    batch_ = std::make_unique<SerialBatchStepper>(std::move(steppers));
  }
  BatchStepper& batch() override { return *batch_; }
  void set_targets(int system, const std::vector<Metric>& g) override { cores_.at(static_cast<size_t>(system))->set_targets(g); }
  ExactSamples preferred_exact_samples() const override { return cores_.front()->preferred_exact_samples(); }

 private:
  std::vector<std::unique_ptr<NewtonCore>> cores_;
  std::unique_ptr<SerialBatchStepper> batch_;
};

class LockstepCore final : public NewtonCore {
 public:
  LockstepCore(const ShapeSetup& setup, LockstepBackend& backend, LockstepGroup& group, int system)
      : setup_(setup), backend_(backend), group_(group), system_(system) {}
  int n() const override { return static_cast<int>(setup_.D_G.cols()); }
  const char* name() const override { return "lockstep"; }
  ExactSamples preferred_exact_samples() const override { return backend_.preferred_exact_samples(); }
  void set_targets(const std::vector<Metric>& g) override { backend_.set_targets(system_, g); }
  std::unique_ptr<NewtonStepper> make_stepper(const MapSpace& space, const Certifier* certifier, const QuadraticTerm* quad) override {
    if (&space != &setup_.metric_space || quad || (certifier && certifier != &setup_.certifier)) return nullptr;
    return group_.stepper(system_);
  }
  std::optional<CertificateResult> certify_map(const Certifier& certifier, const HarmonicMap& map) override {
    return backend_.certify_map(certifier, map);
  }
  void set_coefficients(const Eigen::VectorXd&) override { only_steps(); }
  double energy() override { only_steps(); }
  Eigen::VectorXd gradient() override { only_steps(); }
  Eigen::MatrixXd hessian(HessianProjection, bool, bool) override { only_steps(); }
  void set_direction(const Eigen::VectorXd&) override { only_steps(); }
  double max_safe_step() override { only_steps(); }
  double energy_at(double) override { only_steps(); }

 private:
  [[noreturn]] static void only_steps() {
    throw std::logic_error("a lockstep core only steps its interpolation space's solves (per-call NewtonCore methods are not served)");
  }
  const ShapeSetup& setup_;
  LockstepBackend& backend_;
  LockstepGroup& group_;
  int system_;
};

}  // namespace

std::unique_ptr<LockstepBackend> make_serial_lockstep_backend(const ShapeSetup& setup, int systems,
                                                              const std::function<std::unique_ptr<NewtonCore>()>& make_core) {
  return std::make_unique<SerialLockstepBackend>(setup, systems, make_core);
}

std::unique_ptr<NewtonCore> make_lockstep_core(const ShapeSetup& setup, LockstepBackend& backend, LockstepGroup& group, int system) {
  if (system < 0 || system >= backend.batch().systems())
    throw std::invalid_argument("make_lockstep_core: system " + std::to_string(system) + " of " + std::to_string(backend.batch().systems()));
  return std::make_unique<LockstepCore>(setup, backend, group, system);
}

}  // namespace hsi
