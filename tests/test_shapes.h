// Shapes generated in code for unit tests, and access to the bundled assets.
#pragma once

#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>
#include <vector>

#include "hsi/domain.h"
#include "hsi/scene_io.h"

namespace hsi::test {

inline Loop circle(cd c, double r, int n, bool ccw = true) {
  Loop l;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * std::numbers::pi * i / n * (ccw ? 1 : -1);
    l.push_back(c + r * cd(std::cos(t), std::sin(t)));
  }
  return l;
}

inline Loop rect(double x0, double y0, double x1, double y1) { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }

inline Shape annulus(double r0 = 1.0, double r1 = 0.4, int n = 96) {
  return normalize(Shape{circle(0, r0, n), {circle(0, r1, n / 2)}});
}

// A 4 × 1 bar with three square-ish holes.
inline Shape bar_with_holes() {
  Shape s{rect(0, 0, 4, 1), {}};
  for (int k = 0; k < 3; ++k) s.holes.push_back(circle({0.8 + 1.2 * k, 0.5}, 0.25, 24));
  return normalize(s);
}

inline Shape disc(double r = 1.0, int n = 64) { return normalize(Shape{circle(0, r, n), {}}); }

inline std::vector<std::filesystem::path> asset_scenes() {
  std::vector<std::filesystem::path> out;
  for (const auto& e : std::filesystem::directory_iterator(HSI_ASSETS_DIR))
    if (e.path().extension() == ".json") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

// Points strictly inside the shape (rejection sampling, fixed seed).
inline std::vector<cd> interior_points(const Shape& s, int count, unsigned seed = 7) {
  const BoundingBox bb = bounding_box(s);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(bb.lo.real(), bb.hi.real()), uy(bb.lo.imag(), bb.hi.imag());
  std::vector<cd> out;
  const double margin = 1e-3 * bb.diagonal();
  while (static_cast<int>(out.size()) < count) {
    const cd p(ux(rng), uy(rng));
    if (point_in_shape(s, p) && boundary_distance(s, p) > margin) out.push_back(p);
  }
  return out;
}

}  // namespace hsi::test
