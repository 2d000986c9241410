// Target metrics and start points for unit tests of the Newton solves: the pull-back
// metric of a map at every sample (targets its solve reproduces) and a seeded Gaussian
// perturbation of a point.
#pragma once

#include <functional>
#include <random>
#include <vector>

#include "hsi/basis.h"
#include "hsi/energy.h"
#include "hsi/harmonic_map.h"
#include "hsi/newton.h"
#include "hsi/shape_setup.h"

namespace hsi::test {

// The pull-back metric of x (in the setup's interpolation space) at every sample of G.
inline std::vector<Metric> metrics_of(const ShapeSetup& setup, const Eigen::VectorXd& x) {
  const MapValues v = evaluate_map(evaluate_basis(setup.cage, setup.G.points, kBasisD), setup.metric_space.expand(x));
  return pullback_metrics(v.f_z, v.fzbar_conj);
}

// x0 plus independent Gaussian noise of standard deviation amp in every entry (seeded).
inline Eigen::VectorXd perturbed(const Eigen::VectorXd& x0, unsigned seed, double amp) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, amp);
  Eigen::VectorXd x = x0;
  for (Eigen::Index i = 0; i < x.size(); ++i) x(i) += g(rng);
  return x;
}

// One system's frames as a sequence solves them: frame f's targets set by `set`, then
// newton_run from the previous frame's x (x0 first) with one kept slot for chord steps.
inline std::vector<NewtonResult> solve_frames(NewtonStepper& stepper, const std::function<void(const std::vector<Metric>&)>& set,
                                              const std::vector<std::vector<Metric>>& targets, const Eigen::VectorXd& x0,
                                              const NewtonOptions& options, bool rotation_invariant) {
  KeptSystem slot;
  NewtonOptions o = options;
  o.kept_system = &slot;
  std::vector<NewtonResult> out;
  Eigen::VectorXd x = x0;
  for (const std::vector<Metric>& g : targets) {
    set(g);
    out.push_back(newton_run(stepper, true, rotation_invariant, x, o));
    x = out.back().x;
  }
  return out;
}

}  // namespace hsi::test
