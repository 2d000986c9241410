// Exact comparisons of what the engine reports (frames, overlap results), for tests
// that prove two paths give the same answer: every field, numbers bit for bit (NaN
// equal to NaN), timings aside.
#pragma once

#include <catch2/catch.hpp>

#include <cmath>

#include "hsi/interpolation.h"
#include "hsi/overlap.h"

namespace hsi::test {

// The same double, NaN included (e.g. the crossing point of two segments of size
// ~1e300 overflows in every search).
inline bool same_number(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

// Every field, the crossing point bit for bit.
inline void require_same(const OverlapResult& got, const OverlapResult& want) {
  INFO(describe(want));
  CHECK(got.checked == want.checked);
  CHECK(got.crossings == want.crossings);
  CHECK(got.points == want.points);
  CHECK(got.loop_a == want.loop_a);
  CHECK(got.edge_a == want.edge_a);
  CHECK(got.loop_b == want.loop_b);
  CHECK(got.edge_b == want.edge_b);
  CHECK(same_number(got.point.real(), want.point.real()));
  CHECK(same_number(got.point.imag(), want.point.imag()));
}

inline void require_same(const Distortion& a, const Distortion& b) {
  CHECK(same_number(a.sigma1_max, b.sigma1_max));
  CHECK(same_number(a.sigma2_min, b.sigma2_min));
  CHECK(same_number(a.conformal_max, b.conformal_max));
  CHECK(same_number(a.isometric_max, b.isometric_max));
}

// Every field a frame has but its timings.
inline void require_same(const FrameResult& a, const FrameResult& b) {
  INFO("t = " << b.t);
  CHECK(a.t == b.t);
  CHECK(a.map.phi == b.map.phi);
  CHECK(a.map.psi == b.map.psi);
  CHECK(a.x == b.x);
  CHECK(a.keyframe == b.keyframe);
  CHECK(a.held == b.held);
  CHECK(a.certified == b.certified);
  CHECK(a.converged == b.converged);
  CHECK(a.certificate.certified == b.certificate.certified);
  CHECK(a.certificate.reason == b.certificate.reason);
  CHECK(a.certificate.winding == b.certificate.winding);
  CHECK(a.certificate.sigma1_max == b.certificate.sigma1_max);
  CHECK(a.certificate.sigma2_min == b.certificate.sigma2_min);
  CHECK(a.certificate.observed_isometric_max == b.certificate.observed_isometric_max);
  CHECK(a.certificate.segments == b.certificate.segments);
  CHECK(a.certificate.subdivisions == b.certificate.subdivisions);
  CHECK(a.iterations == b.iterations);
  CHECK(a.energy == b.energy);
  require_same(a.distortion, b.distortion);
  require_same(a.distortion_certified, b.distortion_certified);
  require_same(a.bound, b.bound);
  require_same(a.certified_bound, b.certified_bound);
  CHECK(same_number(a.bound_excess, b.bound_excess));
  CHECK(same_number(a.certified_bound_excess, b.certified_bound_excess));
  CHECK(a.message == b.message);
  require_same(a.overlap, b.overlap);
}

}  // namespace hsi::test
