// NewtonStepper's split solve (decrement(), then direction()) against solve() on one
// stepper: the same factor status, a decrement equal to −gᵀd to round-off, and then the
// same direction (slope, safe step, trial energies, the accepted point) bit for bit. Used
// by the CPU stepper's test (test_newton.cpp) and the GPU stepper's (test_cuda_core.cpp).
#pragma once

#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <functional>
#include <memory>

#include "hsi/newton.h"
#include "hsi/shape_setup.h"

namespace hsi::test {

// A stepper with a core of its own (steppers of one core share its buffers).
struct CoreStepper {
  std::unique_ptr<NewtonCore> core;  // declared first: outlives the stepper
  std::unique_ptr<NewtonStepper> stepper;
};

// How many systems factored, and how many of those decrement() split (no direction yet).
struct SplitCounts {
  int factored = 0, split = 0;
};

// `make` gives a fresh core and stepper in the same state each call. x0: a posed point,
// where the gradient is far from 0. Checks each system kind that factors there.
inline SplitCounts check_split_solve(const std::function<CoreStepper()>& make, const Eigen::VectorXd& x0) {
  SplitCounts counts;
  const std::array<HessianChoice, 4> choices{{{false, HessianProjection::Delete, false, false},
                                              {false, HessianProjection::PartProj, true, false},
                                              {true, HessianProjection::PartProj, true, false},
                                              {true, HessianProjection::PartProj, false, true}}};
  for (const HessianChoice& c : choices) {
    INFO("exact " << c.exact << ", free rotation " << c.free_rotation << ", all samples " << c.all_samples);
    CoreStepper a = make(), b = make();
    NewtonStepper* const whole = a.stepper.get();
    NewtonStepper* const split = b.stepper.get();
    const double e0 = whole->start(x0);
    CHECK(split->start(x0) == e0);
    whole->linearize(c);
    split->linearize(c);
    const double ridge = c.exact ? 1e-15 : 0.0;  // (relative: NewtonStepper::solve)
    const NewtonSystem w = whole->solve(ridge);
    const NewtonSystem s = split->decrement(ridge);
    CHECK(w.has_direction);
    REQUIRE(s.factored == w.factored);
    if (!w.factored) continue;
    ++counts.factored;
    counts.split += !s.has_direction;
    CHECK(s.gradient_norm == w.gradient_norm);
    CHECK(s.diagonal_max == w.diagonal_max);
    CHECK(s.slope < 0);
    CHECK(std::abs(s.slope - w.slope) <= 1e-10 * std::abs(w.slope));
    const NewtonSystem d = s.has_direction ? s : split->direction();
    CHECK(d.has_direction);
    CHECK(d.factored);
    CHECK(d.slope == w.slope);
    CHECK(d.max_safe_step == w.max_safe_step);
    const double step = std::min(1.0, 0.5 * w.max_safe_step);
    std::array<double, 2> steps{step, step / 2}, ew{}, es{};
    whole->trial_energies(steps, ew);
    split->trial_energies(steps, es);
    CHECK(es == ew);
    whole->accept(step);
    split->accept(step);
    CHECK(split->x() == whole->x());
  }
  return counts;
}

}  // namespace hsi::test
