// What the mesh baselines share (mesh_support.h): rest triangles, keyframe checks,
// components, the factorised Poisson system and fixed-pattern sparse matrices.
#include "mesh_support.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>

namespace hsi::baselines::detail {

std::string num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}
std::string point(cd p) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "(%.6g, %.6g)", p.real(), p.imag());
  return buf;
}
std::string triangle_name(int t, const std::array<int, 3>& v) {
  return "triangle " + std::to_string(t) + " (vertices " + std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " +
         std::to_string(v[2]) + ")";
}

double wrap(double x) { return std::remainder(x, 2 * std::numbers::pi); }

Mat2 edge_matrix(cd a, cd b, cd c) {
  Mat2 m;
  m << (b - a).real(), (c - a).real(), (b - a).imag(), (c - a).imag();
  return m;
}

double polar_angle(const Mat2& J) { return std::atan2(J(1, 0) - J(0, 1), J(0, 0) + J(1, 1)); }

Mat2 rotation(double angle) {
  Mat2 R;
  R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  return R;
}

std::array<Eigen::Vector2d, 3> RestTriangle::gradients() const {
  const Eigen::Vector2d g1 = E_inv.row(0).transpose(), g2 = E_inv.row(1).transpose();
  return {-g1 - g2, g1, g2};
}

std::vector<RestTriangle> rest_triangles(const TriMesh& rest) {
  const int n = rest.vertex_count();
  for (int i = 0; i < n; ++i) {
    const cd p = rest.vertices[at(i)];
    if (!std::isfinite(p.real()) || !std::isfinite(p.imag()))
      throw InputError("rest mesh: vertex " + std::to_string(i) + " is not finite " + point(p));
  }
  if (rest.triangles.empty()) throw InputError("rest mesh has no triangles");
  std::vector<RestTriangle> tris(rest.triangles.size());
  for (int t = 0; t < rest.triangle_count(); ++t) {
    const auto& v = rest.triangles[at(t)];
    for (int j : v)
      if (j < 0 || j >= n)
        throw InputError("rest mesh: " + triangle_name(t, v) + " refers to a vertex outside 0.." + std::to_string(n - 1));
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
      throw InputError("rest mesh: " + triangle_name(t, v) + " repeats a vertex");
    const cd a = rest.vertices[at(v[0])], b = rest.vertices[at(v[1])], c = rest.vertices[at(v[2])];
    const Mat2 E = edge_matrix(a, b, c);
    const double det = E.determinant();
    const double scale = std::max({std::norm(b - a), std::norm(c - b), std::norm(a - c)});
    // Relative to the edges, so that the test means the same at any scale of the shape.
    if (!(std::abs(det) > 1e-12 * scale))
      throw InputError("rest mesh: " + triangle_name(t, v) + " is degenerate (area " + num(std::abs(det) / 2) + ")");
    tris[at(t)] = {v, std::abs(det) / 2, E.inverse()};
  }
  return tris;
}

void check_positions(const TriMesh& rest, std::span<const cd> positions, const std::string& what) {
  if (positions.size() != rest.vertices.size())
    throw InputError(what + " has " + std::to_string(positions.size()) + " positions; the rest mesh has " +
                     std::to_string(rest.vertices.size()) + " vertices");
  for (size_t i = 0; i < positions.size(); ++i)
    if (!std::isfinite(positions[i].real()) || !std::isfinite(positions[i].imag()))
      throw InputError(what + ": vertex " + std::to_string(i) + " is not finite " + point(positions[i]));
}

Mat2 jacobian(const RestTriangle& T, std::span<const cd> x) {
  return edge_matrix(x[at(T.v[0])], x[at(T.v[1])], x[at(T.v[2])]) * T.E_inv;
}

std::string keyframe_name(const std::string& method, size_t k, double time) {
  return method + " keyframe " + std::to_string(k) + " (t = " + num(time) + ")";
}

void check_keyframes(const TriMesh& rest, std::span<const MeshKeyframe> keyframes, const std::string& method) {
  if (keyframes.size() < 2)
    throw InputError(method + " interpolation needs at least 2 keyframes (got " + std::to_string(keyframes.size()) + ")");
  for (size_t k = 0; k < keyframes.size(); ++k) {
    const std::string name = keyframe_name(method, k, keyframes[k].time);
    if (!std::isfinite(keyframes[k].time)) throw InputError(name + ": the time is not finite");
    if (k > 0 && !(keyframes[k].time > keyframes[k - 1].time))
      throw InputError(name + " is not after keyframe " + std::to_string(k - 1) + " (t = " + num(keyframes[k - 1].time) +
                       "): times must increase strictly");
    check_positions(rest, keyframes[k].positions, name);
  }
}

void check_orientation(std::span<const RestTriangle> tris, std::span<const MeshKeyframe> keyframes, const std::string& method,
                       const std::string& why) {
  for (size_t k = 0; k < keyframes.size(); ++k)
    for (size_t t = 0; t < tris.size(); ++t) {
      const double det = jacobian(tris[t], keyframes[k].positions).determinant();
      if (!(det > 0))
        throw InputError(keyframe_name(method, k, keyframes[k].time) + ": " + triangle_name(static_cast<int>(t), tris[t].v) +
                         " is " + (det < 0 ? "flipped" : "degenerate") + " (det J = " + num(det) + "); " + why);
    }
}

std::pair<int, double> locate(std::span<const double> times, double t, const std::string& method) {
  if (std::isnan(t)) throw InputError(method + " interpolation: the time is NaN");
  t = std::clamp(t, times.front(), times.back());
  const int last = static_cast<int>(times.size()) - 2;
  const int k = std::clamp(static_cast<int>(std::upper_bound(times.begin(), times.end(), t) - times.begin()) - 1, 0, last);
  return {k, std::clamp((t - times[at(k)]) / (times[at(k + 1)] - times[at(k)]), 0.0, 1.0)};
}

std::vector<cd> MeshComponents::centroids(std::span<const cd> x) const {
  std::vector<cd> c(component_mass.size());
  for (size_t i = 0; i < x.size(); ++i) c[at(component[i])] += mass[i] * x[i];
  for (size_t k = 0; k < c.size(); ++k) c[k] /= component_mass[k];
  return c;
}

void MeshComponents::move_centroids(std::vector<cd>& x, std::span<const cd> target) const {
  const std::vector<cd> now = centroids(x);
  for (size_t i = 0; i < x.size(); ++i) x[i] += target[at(component[i])] - now[at(component[i])];
}

MeshComponents mesh_components(int vertex_count, std::span<const RestTriangle> tris) {
  std::vector<int> parent(at(vertex_count));
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[at(i)] != i) i = parent[at(i)] = parent[at(parent[at(i)])];
    return i;
  };
  MeshComponents m;
  m.mass.assign(at(vertex_count), 0.0);
  for (const RestTriangle& tri : tris) {
    for (int j : tri.v) m.mass[at(j)] += tri.area / 3;
    parent[at(find(tri.v[1]))] = find(tri.v[0]);
    parent[at(find(tri.v[2]))] = find(tri.v[0]);
  }
  m.component.assign(at(vertex_count), -1);
  std::vector<int> root_component(at(vertex_count), -1);
  for (int i = 0; i < vertex_count; ++i) {
    if (m.mass[at(i)] == 0) throw InputError("rest mesh: vertex " + std::to_string(i) + " is in no triangle");
    int& c = root_component[at(find(i))];
    if (c < 0) {
      c = m.count();
      m.component_mass.push_back(0);
    }
    m.component[at(i)] = c;
    m.component_mass[at(c)] += m.mass[at(i)];
  }
  return m;
}

PoissonSolver::PoissonSolver(int vertex_count, std::span<const RestTriangle> tris, const MeshComponents& components,
                             const std::string& method)
    : n_(vertex_count) {
  // The first vertex of each component is pinned (E leaves its translation free).
  reduced_.assign(at(n_), -1);
  std::vector<char> seen(at(components.count()), 0);
  for (int i = 0; i < n_; ++i) {
    char& s = seen[at(components.component[at(i)])];
    if (s)
      reduced_[at(i)] = reduced_count_++;
    else
      s = 1;
  }
  // The cotangent stiffness matrix K_uv = Σ_T area_T ∇φ_u · ∇φ_v without the pinned rows.
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(9 * tris.size());
  for (const RestTriangle& tri : tris) {
    const auto g = tri.gradients();
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const int ra = reduced_[at(tri.v[at(a)])], rb = reduced_[at(tri.v[at(b)])];
        if (ra >= 0 && rb >= 0) entries.emplace_back(ra, rb, tri.area * g[at(a)].dot(g[at(b)]));
      }
  }
  Eigen::SparseMatrix<double> stiffness(reduced_count_, reduced_count_);
  stiffness.setFromTriplets(entries.begin(), entries.end());
  if (reduced_count_ > 0) {
    ldlt_.compute(stiffness);
    if (ldlt_.info() != Eigen::Success)
      throw InputError("rest mesh: the " + method + " system cannot be factorised (triangles too far from well-shaped)");
  }
}

std::vector<cd> PoissonSolver::solve(std::span<const RestTriangle> tris, std::span<const Mat2> A) const {
  // Normal equations K x_c = b_c per coordinate c, with b_u = Σ_T area_T A_T^T ∇φ_u.
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(reduced_count_, 2);
  for (size_t t = 0; t < tris.size(); ++t) {
    const RestTriangle& T = tris[t];
    const auto g = T.gradients();
    for (int j = 0; j < 3; ++j) {
      const int r = reduced_[at(T.v[at(j)])];
      if (r >= 0) b.row(r) += T.area * (A[t] * g[at(j)]).transpose();
    }
  }
  const Eigen::MatrixXd X = reduced_count_ > 0 ? Eigen::MatrixXd(ldlt_.solve(b)) : b;
  std::vector<cd> x(at(n_));
  for (int i = 0; i < n_; ++i) {
    const int r = reduced_[at(i)];
    x[at(i)] = r >= 0 ? cd(X(r, 0), X(r, 1)) : cd(0);
  }
  return x;
}

double PoissonSolver::energy(std::span<const RestTriangle> tris, std::span<const Mat2> A, std::span<const cd> x) {
  double e = 0;
  for (size_t t = 0; t < tris.size(); ++t) e += tris[t].area * (jacobian(tris[t], x) - A[t]).squaredNorm();
  return e;
}

FixedPattern::FixedPattern(int size, std::span<const std::pair<int, int>> entries) : matrix_(size, size) {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(entries.size());
  for (const auto& [r, c] : entries) t.emplace_back(r, c, 0.0);
  matrix_.setFromTriplets(t.begin(), t.end());
  matrix_.makeCompressed();
}

int FixedPattern::slot(int row, int column) const {
  const int* begin = matrix_.innerIndexPtr() + matrix_.outerIndexPtr()[column];
  const int* end = matrix_.innerIndexPtr() + matrix_.outerIndexPtr()[column + 1];
  const int* p = std::lower_bound(begin, end, row);
  if (p == end || *p != row) throw std::logic_error("FixedPattern: entry outside the pattern");
  return static_cast<int>(p - matrix_.innerIndexPtr());
}

void FixedPattern::zero() { std::fill(matrix_.valuePtr(), matrix_.valuePtr() + matrix_.nonZeros(), 0.0); }

}  // namespace hsi::baselines::detail
