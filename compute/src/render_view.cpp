// The Vulkan-free parts of renderer.h: the view (world to pixels), the distortion
// colour map and its round range, and the unwelded mesh for per-triangle values.
#include "hsi/compute/renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>

namespace hsi::compute {

std::array<double, 3> colormap(double t) {
  t = std::clamp(std::isnan(t) ? 1.0 : t, 0.0, 1.0);
  static constexpr double c[7][3] = {
      {0.2777273272234177, 0.005407344544966578, 0.3340998053353061},
      {0.1050930431085774, 1.404613529898575, 1.384590162594685},
      {-0.3308618287255563, 0.214847559468213, 0.09509516302823659},
      {-4.634230498983486, -5.799100973351585, -19.33244095627987},
      {6.228269936347081, 14.17993336680509, 56.69055260068105},
      {4.776384997670288, -13.74514537774601, -65.35303263337234},
      {-5.435455855934631, 4.645852612178535, 26.3124352495832}};
  std::array<double, 3> out{};
  for (int k = 0; k < 3; ++k) {
    double v = c[6][k];
    for (int i = 5; i >= 0; --i) v = c[i][k] + t * v;
    out[static_cast<size_t>(k)] = std::clamp(v, 0.0, 1.0);
  }
  return out;
}

View View::fit(const BoundingBox& world, int width, int height, double margin_px, double bottom_px) {
  const cd ext = world.hi - world.lo;
  const double aw = width - 2 * margin_px, ah = height - 2 * margin_px - bottom_px;
  if (!(std::isfinite(ext.real()) && std::isfinite(ext.imag())) || (ext.real() <= 0 && ext.imag() <= 0))
    throw InputError("View::fit: the box to show is empty or not finite");
  if (aw <= 1 || ah <= 1)
    throw InputError("View::fit: a " + std::to_string(width) + " x " + std::to_string(height) +
                     " image leaves no room inside its margins");
  double s = std::numeric_limits<double>::infinity();
  if (ext.real() > 0) s = std::min(s, aw / ext.real());
  if (ext.imag() > 0) s = std::min(s, ah / ext.imag());
  View v;
  v.world_center = 0.5 * (world.lo + world.hi);
  v.pixels_per_unit = s;
  v.pixel_center = {0.5 * width, margin_px + 0.5 * ah};
  return v;
}

double round_distortion_hi(double hi) {
  const double span = std::max(hi - 1.0, 1e-3);
  const double base = std::pow(10.0, std::floor(std::log10(span / 4)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (4 * m * base >= span * (1 - 1e-12)) return 1.0 + 4 * m * base;
  return 1.0 + 40 * base;
}

UnweldedMesh unweld(const TriMesh& mesh) {
  UnweldedMesh u;
  const size_t nt = mesh.triangles.size();
  u.mesh.vertices.reserve(3 * nt);
  u.mesh.triangles.reserve(nt);
  u.source.reserve(3 * nt);
  u.mesh.boundary_loop.reserve(3 * nt);
  // Each boundary edge (a, b) has the shape on its left: it is the edge a -> b of
  // exactly one counter-clockwise triangle.
  std::unordered_map<uint64_t, std::array<int, 2>> directed;
  directed.reserve(3 * nt);
  const auto key = [](int a, int b) { return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b); };
  for (size_t t = 0; t < nt; ++t) {
    std::array<int, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.triangles[t][static_cast<size_t>(k)];
      tri[static_cast<size_t>(k)] = static_cast<int>(u.mesh.vertices.size());
      u.mesh.vertices.push_back(mesh.vertices[static_cast<size_t>(v)]);
      u.mesh.boundary_loop.push_back(mesh.boundary_loop.empty() ? -1 : mesh.boundary_loop[static_cast<size_t>(v)]);
      u.source.push_back(v);
    }
    for (int k = 0; k < 3; ++k)
      directed[key(mesh.triangles[t][static_cast<size_t>(k)], mesh.triangles[t][static_cast<size_t>((k + 1) % 3)])] = {
          tri[static_cast<size_t>(k)], tri[static_cast<size_t>((k + 1) % 3)]};
    u.mesh.triangles.push_back(tri);
  }
  u.mesh.boundary_edges.reserve(mesh.boundary_edges.size());
  for (const auto& [a, b] : mesh.boundary_edges) {
    const auto it = directed.find(key(a, b));
    if (it == directed.end())
      throw InputError("unweld: boundary edge (" + std::to_string(a) + ", " + std::to_string(b) +
                       ") is not an edge of a counter-clockwise triangle");
    u.mesh.boundary_edges.push_back(it->second);
  }
  return u;
}

}  // namespace hsi::compute
