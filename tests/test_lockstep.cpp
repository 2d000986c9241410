// The lockstep group (hsi/lockstep.h): several systems' Newton loops, each on its own
// thread against a proxy stepper, their calls served together by a SerialBatchStepper,
// give each system exactly the solve it gets alone (the same x bit for bit, iterations,
// verdicts), over two solves per system that carry a kept factor for chord steps; the
// calls were served in rounds, not one by one; one system's failing call reaches its
// own loop alone.
#include <catch2/catch.hpp>

#include <stdexcept>
#include <thread>

#include "hsi/cage.h"
#include "hsi/lockstep.h"
#include "hsi/newton.h"
#include "hsi/shape_setup.h"
#include "test_shapes.h"
#include "test_targets.h"

using namespace hsi;
using hsi::test::metrics_of;
using hsi::test::perturbed;

TEST_CASE("a lockstep group gives every system the solve it gets alone", "[lockstep]") {
  for (const Shape& shape : {test::annulus(), test::bar_with_holes()}) {
    const ShapeSetup setup(shape, build_cage(shape), 1000, 0.3);
    const MapSpace& space = setup.metric_space;
    const Eigen::VectorXd id = space.reduce(identity_map(setup.cage)).x;
    constexpr int S = 5, kSolves = 2;
    // System s: two frames' targets, from two maps near the identity (seeded per system).
    std::vector<std::vector<std::vector<Metric>>> targets(S);
    for (int s = 0; s < S; ++s)
      for (int f = 0; f < kSolves; ++f)
        targets[size_t(s)].push_back(metrics_of(setup, perturbed(id, 17u * unsigned(s) + unsigned(f), 0.02 + 0.01 * f)));
    NewtonOptions options;
    options.exact_samples = ExactSamples::Subset;
    const bool rotation_invariant = space.gauge() == Gauge::ModuloRigid;

    // Alone: each system's core and host stepper, its solves one after another.
    std::vector<std::vector<NewtonResult>> alone(S);
    for (int s = 0; s < S; ++s) {
      auto core = make_cpu_newton_core(setup.D_G, setup.H);
      auto stepper = make_host_stepper(*core, space, &setup.certifier, nullptr);
      alone[size_t(s)] = test::solve_frames(*stepper, [&](const std::vector<Metric>& g) { core->set_targets(g); }, targets[size_t(s)], id,
                                            options, rotation_invariant);
    }

    // Together: the same cores and steppers behind one group, each loop on its thread.
    std::vector<std::unique_ptr<NewtonCore>> cores;
    std::vector<std::unique_ptr<NewtonStepper>> own;
    for (int s = 0; s < S; ++s) {
      cores.push_back(make_cpu_newton_core(setup.D_G, setup.H));
      own.push_back(make_host_stepper(*cores.back(), space, &setup.certifier, nullptr));
    }
    SerialBatchStepper batch(std::move(own));
    LockstepGroup group(batch);
    std::vector<std::vector<NewtonResult>> together(S);
    std::vector<std::thread> threads;
    for (int s = 0; s < S; ++s)
      threads.emplace_back([&, s] {
        auto proxy = group.stepper(s);
        // Targets are each system's own data (not stepper calls): set between its solves,
        // while the other threads wait at the gate or run.
        together[size_t(s)] = test::solve_frames(*proxy, [&](const std::vector<Metric>& g) { cores[size_t(s)]->set_targets(g); },
                                                 targets[size_t(s)], id, options, rotation_invariant);
        group.done();
      });
    for (auto& t : threads) t.join();

    int calls_alone = 0;
    for (int s = 0; s < S; ++s)
      for (int f = 0; f < kSolves; ++f) {
        INFO("system " << s << ", solve " << f);
        const NewtonResult &a = alone[size_t(s)][size_t(f)], &b = together[size_t(s)][size_t(f)];
        CHECK(b.x == a.x);
        CHECK(b.energy == a.energy);
        CHECK(b.iterations == a.iterations);
        CHECK(b.converged == a.converged);
        CHECK(b.certified == a.certified);
        CHECK(b.stop == a.stop);
        CHECK(a.converged);
        calls_alone += a.iterations;
      }
    const auto stats = group.stats();
    INFO("rounds " << stats.rounds << ", batches " << stats.batches << ", calls " << stats.calls);
    CHECK(stats.calls > static_cast<std::uint64_t>(calls_alone));  // several calls per iteration
    CHECK(stats.rounds < stats.calls / 2);                         // served in rounds of several systems
  }
}

namespace {

// A stepper whose start() gives the sum of x0, or throws (the other calls are never
// reached in this test).
struct StartOnlyStepper final : NewtonStepper {
  explicit StartOnlyStepper(bool throws) : throws_(throws) {}
  double start(const Eigen::VectorXd& x0) override {
    if (throws_) throw std::runtime_error("this system's start failed");
    return x0.sum();
  }
  void linearize(const HessianChoice&) override {}
  NewtonSystem solve(double) override { return {}; }
  void trial_energies(std::span<const double>, std::span<double>) override {}
  CertificateResult certify(double, bool) override { return {}; }
  void accept(double) override {}
  Eigen::VectorXd x() override { return {}; }

 private:
  bool throws_;
};

}  // namespace

TEST_CASE("a lockstep group: one system's failing call reaches its own loop alone", "[lockstep]") {
  std::vector<std::unique_ptr<NewtonStepper>> steppers;
  for (const bool throws : {false, true, false}) steppers.push_back(std::make_unique<StartOnlyStepper>(throws));
  SerialBatchStepper batch(std::move(steppers));
  LockstepGroup group(batch);
  std::vector<double> energy(3, 0);
  std::vector<int> threw(3, 0);
  std::vector<std::thread> threads;
  for (int s = 0; s < 3; ++s)
    threads.emplace_back([&, s] {
      auto proxy = group.stepper(s);
      const Eigen::VectorXd x0 = Eigen::VectorXd::Constant(4, s + 1);
      try {
        energy[size_t(s)] = proxy->start(x0);
      } catch (const std::runtime_error&) {
        threw[size_t(s)] = 1;
      }
      group.done();
    });
  for (auto& t : threads) t.join();
  CHECK(threw == std::vector<int>{0, 1, 0});
  CHECK(energy[0] == 4);
  CHECK(energy[2] == 12);
  CHECK(group.stats().rounds == 1);
  CHECK(group.stats().batches == 1);
  CHECK_THROWS_WITH(group.stepper(3), Catch::Contains("system 3 of 3"));
  std::vector<std::unique_ptr<NewtonStepper>> with_null(1);
  CHECK_THROWS_WITH(SerialBatchStepper(std::move(with_null)), Catch::Contains("null stepper"));
}
