// ARAP interpolation (hsi/baselines/arap.h): per-triangle polar decompositions of the
// keyframes, a consistent lift of their rotation angles, and one factorised Poisson
// system on the rest mesh that turns interpolated Jacobians into positions.
#include "hsi/baselines/arap.h"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <numeric>
#include <queue>
#include <string>
#include <tuple>

namespace hsi::baselines {
namespace {

using Mat2 = Eigen::Matrix2d;
constexpr double kInf = std::numeric_limits<double>::infinity();

size_t at(int i) { return static_cast<size_t>(i); }

std::string num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}
std::string point(cd p) { return "(" + num(p.real()) + ", " + num(p.imag()) + ")"; }
std::string triangle_name(int t, const std::array<int, 3>& v) {
  return "triangle " + std::to_string(t) + " (vertices " + std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " +
         std::to_string(v[2]) + ")";
}

// The representative of x mod 2π in [−π, π].
double wrap(double x) { return std::remainder(x, 2 * std::numbers::pi); }

// [b − a, c − a] as columns: the triangle's edge matrix.
Mat2 edge_matrix(cd a, cd b, cd c) {
  Mat2 m;
  m << (b - a).real(), (c - a).real(), (b - a).imag(), (c - a).imag();
  return m;
}

struct RestTriangle {
  std::array<int, 3> v{};
  double area = 0;
  Mat2 E_inv;  // inverse rest edge matrix: rows are ∇φ of v[1] and v[2]; ∇φ of v[0] is minus their sum
};

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

// Polar angle of J (the rotation nearest J): arg f_z, with J acting as z ↦ f_z z + f_z̄ z̄.
double polar_angle(const Mat2& J) { return std::atan2(J(1, 0) - J(0, 1), J(0, 0) + J(1, 1)); }

Mat2 rotation(double angle) {
  Mat2 R;
  R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  return R;
}

}  // namespace

MeshDistortion mesh_distortion(const TriMesh& rest, std::span<const cd> positions) {
  check_positions(rest, positions, "mesh_distortion");
  const std::vector<RestTriangle> tris = rest_triangles(rest);
  MeshDistortion d;
  d.kappa.resize(tris.size());
  d.isometric.resize(tris.size());
  for (size_t t = 0; t < tris.size(); ++t) {
    const Mat2 J = jacobian(tris[t], positions);
    // σ1 = |f_z| + |f_z̄|, σ2 = |f_z| − |f_z̄| when det J = |f_z|² − |f_z̄|² > 0.
    const double fz = std::hypot(J(0, 0) + J(1, 1), J(1, 0) - J(0, 1)) / 2;
    const double fzbar = std::hypot(J(0, 0) - J(1, 1), J(1, 0) + J(0, 1)) / 2;
    const double s1 = fz + fzbar, s2 = fz - fzbar;
    if (!(J.determinant() > 0) || !(s2 > 0)) {
      ++d.flipped;
      d.kappa[t] = d.isometric[t] = kInf;
    } else {
      d.kappa[t] = s1 / s2;
      d.isometric[t] = 0.5 * (s1 * s1 + 1 / (s1 * s1) + s2 * s2 + 1 / (s2 * s2));
    }
    d.max_kappa = std::max(d.max_kappa, d.kappa[t]);
    d.max_isometric = std::max(d.max_isometric, d.isometric[t]);
  }
  return d;
}

struct ArapInterpolation::Impl {
  int n = 0;
  std::vector<RestTriangle> tris;
  std::vector<double> times;
  // Per keyframe, per triangle: the lifted rotation angle α and the stretch S (s00, s01, s11).
  std::vector<std::vector<double>> alpha;
  std::vector<std::vector<std::array<double, 3>>> stretch;
  std::vector<int> component;                 // per vertex (connected components of the mesh)
  std::vector<double> mass;                   // per vertex: a third of its triangles' area
  std::vector<double> component_mass;
  std::vector<std::vector<cd>> centroid;      // per keyframe, per component
  std::vector<int> reduced;                   // per vertex: row in the pinned system, −1 if pinned
  int reduced_count = 0;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;

  std::pair<int, double> locate(double t) const {
    if (std::isnan(t)) throw InputError("ARAP interpolation: the time is NaN");
    t = std::clamp(t, times.front(), times.back());
    const int last = static_cast<int>(times.size()) - 2;
    const int k = std::clamp(static_cast<int>(std::upper_bound(times.begin(), times.end(), t) - times.begin()) - 1, 0, last);
    return {k, std::clamp((t - times[at(k)]) / (times[at(k + 1)] - times[at(k)]), 0.0, 1.0)};
  }

  // A_T(t) = R((1−s) α_k + s α_{k+1}) · ((1−s) S_k + s S_{k+1}), exact at s = 0 and s = 1.
  std::vector<Mat2> targets(int k, double s) const {
    std::vector<Mat2> A(tris.size());
    const auto &a0 = alpha[at(k)], &a1 = alpha[at(k + 1)];
    const auto &S0 = stretch[at(k)], &S1 = stretch[at(k + 1)];
    for (size_t t = 0; t < tris.size(); ++t) {
      Mat2 S;
      const double s00 = (1 - s) * S0[t][0] + s * S1[t][0], s01 = (1 - s) * S0[t][1] + s * S1[t][1],
                   s11 = (1 - s) * S0[t][2] + s * S1[t][2];
      S << s00, s01, s01, s11;
      A[t] = rotation((1 - s) * a0[t] + s * a1[t]) * S;
    }
    return A;
  }

  std::vector<cd> solve(const std::vector<Mat2>& A, int k, double s) const {
    // Normal equations K x_c = b_c per coordinate c, with b_u = Σ_T area_T A_T^T ∇φ_u.
    Eigen::MatrixXd b = Eigen::MatrixXd::Zero(reduced_count, 2);
    for (size_t t = 0; t < tris.size(); ++t) {
      const RestTriangle& T = tris[t];
      const Eigen::Vector2d g1 = T.E_inv.row(0).transpose(), g2 = T.E_inv.row(1).transpose();
      const std::array<Eigen::Vector2d, 3> g{-g1 - g2, g1, g2};
      for (int j = 0; j < 3; ++j) {
        const int r = reduced[at(T.v[at(j)])];
        if (r >= 0) b.row(r) += T.area * (A[t] * g[at(j)]).transpose();
      }
    }
    const Eigen::MatrixXd X = ldlt.solve(b);
    std::vector<cd> x(at(n));
    for (int i = 0; i < n; ++i) {
      const int r = reduced[at(i)];
      x[at(i)] = r >= 0 ? cd(X(r, 0), X(r, 1)) : cd(0);
    }
    // E leaves each component's translation free: move its centroid linearly between the keyframes'.
    std::vector<cd> shift(component_mass.size());
    for (size_t c = 0; c < shift.size(); ++c)
      shift[c] = (1 - s) * centroid[at(k)][c] + s * centroid[at(k + 1)][c];
    for (int i = 0; i < n; ++i) shift[at(component[at(i)])] -= mass[at(i)] / component_mass[at(component[at(i)])] * x[at(i)];
    for (int i = 0; i < n; ++i) x[at(i)] += shift[at(component[at(i)])];
    return x;
  }

  double energy(const std::vector<Mat2>& A, std::span<const cd> x) const {
    double e = 0;
    for (size_t t = 0; t < tris.size(); ++t) e += tris[t].area * (jacobian(tris[t], x) - A[t]).squaredNorm();
    return e;
  }
};

ArapInterpolation::ArapInterpolation(const TriMesh& rest, std::vector<ArapKeyframe> keyframes) {
  auto impl = std::make_shared<Impl>();
  Impl& m = *impl;
  m.n = rest.vertex_count();
  m.tris = rest_triangles(rest);
  const size_t T = m.tris.size();

  if (keyframes.size() < 2)
    throw InputError("ARAP interpolation needs at least 2 keyframes (got " + std::to_string(keyframes.size()) + ")");
  for (size_t k = 0; k < keyframes.size(); ++k) {
    const std::string name = "ARAP keyframe " + std::to_string(k) + " (t = " + num(keyframes[k].time) + ")";
    if (!std::isfinite(keyframes[k].time)) throw InputError(name + ": the time is not finite");
    if (k > 0 && !(keyframes[k].time > keyframes[k - 1].time))
      throw InputError(name + " is not after keyframe " + std::to_string(k - 1) + " (t = " + num(keyframes[k - 1].time) +
                       "): times must increase strictly");
    check_positions(rest, keyframes[k].positions, name);
  }

  // Connected components (a vertex in no triangle would leave K singular).
  std::vector<int> parent(at(m.n));
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[at(i)] != i) i = parent[at(i)] = parent[at(parent[at(i)])];
    return i;
  };
  m.mass.assign(at(m.n), 0.0);
  for (const RestTriangle& tri : m.tris) {
    for (int j : tri.v) m.mass[at(j)] += tri.area / 3;
    parent[at(find(tri.v[1]))] = find(tri.v[0]);
    parent[at(find(tri.v[2]))] = find(tri.v[0]);
  }
  m.component.assign(at(m.n), -1);
  m.reduced.assign(at(m.n), -1);
  std::vector<int> root_component(at(m.n), -1);
  for (int i = 0; i < m.n; ++i) {
    if (m.mass[at(i)] == 0) throw InputError("rest mesh: vertex " + std::to_string(i) + " is in no triangle");
    int& c = root_component[at(find(i))];
    if (c < 0) {
      c = static_cast<int>(m.component_mass.size());  // its first vertex is pinned
      m.component_mass.push_back(0);
    } else {
      m.reduced[at(i)] = m.reduced_count++;
    }
    m.component[at(i)] = c;
    m.component_mass[at(c)] += m.mass[at(i)];
  }
  const size_t C = m.component_mass.size();

  // Polar decompositions J = R(θ) S of every keyframe triangle.
  const size_t K = keyframes.size();
  std::vector<std::vector<double>> theta(K, std::vector<double>(T));
  m.stretch.assign(K, std::vector<std::array<double, 3>>(T));
  m.centroid.assign(K, std::vector<cd>(C));
  for (size_t k = 0; k < K; ++k) {
    const std::vector<cd>& x = keyframes[k].positions;
    for (size_t t = 0; t < T; ++t) {
      const Mat2 J = jacobian(m.tris[t], x);
      const double det = J.determinant();
      if (!(det > 0))
        throw InputError("ARAP keyframe " + std::to_string(k) + " (t = " + num(keyframes[k].time) + "): " +
                         triangle_name(static_cast<int>(t), m.tris[t].v) + " is " + (det < 0 ? "flipped" : "degenerate") +
                         " (det J = " + num(det) + "); ARAP's polar decomposition needs det J > 0");
      theta[k][t] = polar_angle(J);
      const Mat2 S = rotation(theta[k][t]).transpose() * J;
      m.stretch[k][t] = {S(0, 0), 0.5 * (S(0, 1) + S(1, 0)), S(1, 1)};
    }
    for (int i = 0; i < m.n; ++i) m.centroid[k][at(m.component[at(i)])] += m.mass[at(i)] * x[at(i)];
    for (size_t c = 0; c < C; ++c) m.centroid[k][c] /= m.component_mass[c];
  }

  // Triangles sharing a vertex (CSR), for lifting the angles.
  std::vector<int> first(at(m.n) + 1, 0), incident(3 * T);
  for (const RestTriangle& tri : m.tris)
    for (int j : tri.v) ++first[at(j) + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  {
    std::vector<int> fill(first.begin(), first.end() - 1);
    for (size_t t = 0; t < T; ++t)
      for (int j : m.tris[t].v) incident[at(fill[at(j)]++)] = static_cast<int>(t);
  }

  // Lift the increments θ_{k+1} − α_k over each component: seed at the triangle nearest
  // the component's area-weighted circular mean, then always extend the lift across the
  // pair of neighbours whose increments differ least (Prim on |wrap(d_U − δ_T)|), so a
  // noisy or strongly sheared triangle cannot decide the branch of its neighbourhood.
  m.alpha.assign(K, std::vector<double>(T));
  m.alpha[0] = theta[0];
  std::vector<double> d(T), delta(T);
  std::vector<char> done(T);
  for (size_t k = 0; k + 1 < K; ++k) {
    for (size_t t = 0; t < T; ++t) d[t] = wrap(theta[k + 1][t] - m.alpha[k][t]);
    std::vector<cd> mean(C);
    for (size_t t = 0; t < T; ++t) mean[at(m.component[at(m.tris[t].v[0])])] += m.tris[t].area * std::polar(1.0, d[t]);
    std::vector<int> seed(C, -1);
    for (size_t t = 0; t < T; ++t) {
      const size_t c = at(m.component[at(m.tris[t].v[0])]);
      const double mc = std::arg(mean[c]);
      if (seed[c] < 0 || std::abs(wrap(d[t] - mc)) < std::abs(wrap(d[at(seed[c])] - mc))) seed[c] = static_cast<int>(t);
    }
    std::fill(done.begin(), done.end(), char(0));
    using Entry = std::tuple<double, int, double>;  // (|step|, triangle, neighbour's lifted increment)
    std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
    for (size_t c = 0; c < C; ++c) queue.emplace(0.0, seed[c], std::arg(mean[c]));
    while (!queue.empty()) {
      const auto [cost, t, ref] = queue.top();
      queue.pop();
      if (done[at(t)]) continue;
      done[at(t)] = 1;
      delta[at(t)] = ref + wrap(d[at(t)] - ref);
      for (int j : m.tris[at(t)].v)
        for (int e = first[at(j)]; e < first[at(j) + 1]; ++e) {
          const int u = incident[at(e)];
          if (!done[at(u)]) queue.emplace(std::abs(wrap(d[at(u)] - delta[at(t)])), u, delta[at(t)]);
        }
    }
    // The lift is fixed up to 2π per component; the mean turn is taken the short way, so
    // that a coil whose ends turn more than π apart is not also spun round as a whole.
    std::vector<double> turn(C, 0.0);
    for (size_t t = 0; t < T; ++t) turn[at(m.component[at(m.tris[t].v[0])])] += m.tris[t].area * delta[t];
    for (size_t c = 0; c < C; ++c) {
      const double full_turns = std::round(turn[c] / m.component_mass[c] / (2 * std::numbers::pi));
      turn[c] = -2 * std::numbers::pi * full_turns;
    }
    for (size_t t = 0; t < T; ++t)
      m.alpha[k + 1][t] = m.alpha[k][t] + delta[t] + turn[at(m.component[at(m.tris[t].v[0])])];
  }

  // The cotangent stiffness matrix K_uv = Σ_T area_T ∇φ_u · ∇φ_v without the pinned rows.
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(9 * T);
  for (const RestTriangle& tri : m.tris) {
    const Eigen::Vector2d g1 = tri.E_inv.row(0).transpose(), g2 = tri.E_inv.row(1).transpose();
    const std::array<Eigen::Vector2d, 3> g{-g1 - g2, g1, g2};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const int ra = m.reduced[at(tri.v[at(a)])], rb = m.reduced[at(tri.v[at(b)])];
        if (ra >= 0 && rb >= 0) entries.emplace_back(ra, rb, tri.area * g[at(a)].dot(g[at(b)]));
      }
  }
  Eigen::SparseMatrix<double> stiffness(m.reduced_count, m.reduced_count);
  stiffness.setFromTriplets(entries.begin(), entries.end());
  if (m.reduced_count > 0) {
    m.ldlt.compute(stiffness);
    if (m.ldlt.info() != Eigen::Success)
      throw InputError("rest mesh: the ARAP system cannot be factorised (triangles too far from well-shaped)");
  }

  for (const ArapKeyframe& kf : keyframes) m.times.push_back(kf.time);
  impl_ = std::move(impl);
}

ArapFrame ArapInterpolation::frame(double t) const {
  const auto [k, s] = impl_->locate(t);
  const std::vector<Mat2> A = impl_->targets(k, s);
  ArapFrame f;
  f.positions = impl_->solve(A, k, s);
  double norm = 0;
  for (size_t i = 0; i < A.size(); ++i) norm += impl_->tris[i].area * A[i].squaredNorm();
  f.relative_residual = std::sqrt(impl_->energy(A, f.positions) / norm);
  return f;
}

std::vector<cd> ArapInterpolation::positions(double t) const {
  const auto [k, s] = impl_->locate(t);
  return impl_->solve(impl_->targets(k, s), k, s);
}

double ArapInterpolation::energy(double t, std::span<const cd> positions) const {
  if (positions.size() != at(impl_->n))
    throw InputError("ARAP energy: " + std::to_string(positions.size()) + " positions for a rest mesh of " +
                     std::to_string(impl_->n) + " vertices");
  const auto [k, s] = impl_->locate(t);
  return impl_->energy(impl_->targets(k, s), positions);
}

double ArapInterpolation::t_begin() const { return impl_->times.front(); }
double ArapInterpolation::t_end() const { return impl_->times.back(); }
int ArapInterpolation::keyframe_count() const { return static_cast<int>(impl_->times.size()); }

}  // namespace hsi::baselines
