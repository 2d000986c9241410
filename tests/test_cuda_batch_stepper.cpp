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
#include <random>
#include <thread>

#include "cuda_test.h"
#include "hsi/cage.h"
#include "hsi/cuda/batch_stepper.h"
#include "hsi/cuda/newton_core.h"
#include "hsi/lockstep.h"
#include "hsi/newton.h"
#include "hsi/shape_setup.h"
#include "test_shapes.h"

using namespace hsi;

namespace {

std::vector<Metric> metrics_at(const ShapeSetup& setup, const Eigen::VectorXd& x) {
  const MapValues v = evaluate_map(evaluate_basis(setup.cage, setup.G.points, kBasisD), setup.metric_space.expand(x));
  return pullback_metrics(v.f_z, v.fzbar_conj);
}

Eigen::VectorXd perturbed(const Eigen::VectorXd& x0, unsigned seed, double amp) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, amp);
  Eigen::VectorXd x = x0;
  for (Eigen::Index i = 0; i < x.size(); ++i) x(i) += g(rng);
  return x;
}

}  // namespace

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
        targets[size_t(s)].push_back(metrics_at(setup, perturbed(id, 31u * unsigned(s) + unsigned(f), (s == 3 ? 0.03 : 0.015) + 0.005 * f)));
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
          KeptSystem slot;
          NewtonOptions o = options;
          o.kept_system = &slot;
          Eigen::VectorXd x = id;
          for (int f = 0; f < kFrames; ++f) {
            core->set_targets(targets[size_t(s)][size_t(f)]);
            alone[size_t(s)].push_back(newton_run(*stepper, true, rotation_invariant, x, o));
            x = alone[size_t(s)].back().x;
          }
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
            KeptSystem slot;
            NewtonOptions o = options;
            o.kept_system = &slot;
            Eigen::VectorXd x = id;
            for (int f = 0; f < kFrames; ++f) {
              batch->set_targets(s, targets[size_t(s)][size_t(f)]);
              together[size_t(s)].push_back(newton_run(*proxy, true, rotation_invariant, x, o));
              x = together[size_t(s)].back().x;
            }
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
          // |x|∞ over 704 frames), the energy closer.
          const double scale = a.x.cwiseAbs().maxCoeff();
          CHECK((b.x - a.x).cwiseAbs().maxCoeff() <= 1e-4 * scale);
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
