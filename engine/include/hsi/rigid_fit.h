// The rigid motion that best carries one list of points onto another in least squares
// (2D Procrustes): for comparing maps that place a frame differently (hsi compare's Fig. 8).
#pragma once

#include <span>

#include "hsi/domain.h"

namespace hsi {

// w ↦ rotation · (w − from_centroid) + to_centroid, |rotation| = 1.
struct RigidMotion {
  cd from_centroid{0, 0}, to_centroid{0, 0};
  cd rotation{1, 0};
  cd operator()(cd w) const { return rotation * (w - from_centroid) + to_centroid; }
  // m(from) − to, formed about the centroids (no cancellation for points far from 0).
  cd residual(cd from, cd to) const { return rotation * (from - from_centroid) - (to - to_centroid); }
};

// Minimises Σ |m(from_i) − to_i|² over rigid motions m: the centroids matched, the
// rotation the phase of Σ (to_i − to̅) conj(from_i − from̅) (the identity where that sum
// is 0, e.g. for a single point). InputError if the lists differ in length or are empty.
RigidMotion rigid_fit(std::span<const cd> from, std::span<const cd> to);

}  // namespace hsi
