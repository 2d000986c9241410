// Boundary samples G and the Hessian subset H (math.md §1, paper §5.2).
#pragma once

#include <vector>

#include "hsi/domain.h"

namespace hsi {

struct BoundarySamples {
  std::vector<cd> points;   // on ∂Ω, loop by loop, in loop order
  std::vector<int> loop;    // loop of each sample (0 = outer)
  std::vector<int> edge;    // polygon edge each sample lies on
  std::vector<int> loop_begin;  // first sample index of each loop, plus a final end index
  size_t size() const { return points.size(); }
};

// |G| = count points uniform by arc length over all loops, split among loops in
// proportion to their length (at least 8 per loop). Deterministic: each loop starts
// at its vertex 0 shifted by half a spacing.
BoundarySamples sample_boundary(const Shape& shape, int count);

// Indices of a uniform subset H ⊂ G: on each loop, every k-th sample by a fixed
// stride, round(ratio |G_loop|) of them (at least 1) — but at least
// min_per_loop[l] on loop l when given (capped by that loop's samples), so that a
// small hole keeps enough Hessian samples for its cage's coefficients. ratio in (0, 1].
std::vector<int> hessian_subset(const BoundarySamples& g, double ratio, const std::vector<int>& min_per_loop = {});

}  // namespace hsi
