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
#include <optional>
#include <queue>
#include <string>
#include <tuple>

#include "mesh_support.h"

namespace hsi::baselines {

using namespace detail;
namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
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
  MeshComponents components;
  std::vector<std::vector<cd>> centroid;      // per keyframe, per component
  std::optional<PoissonSolver> poisson;

  std::pair<int, double> locate(double t) const { return detail::locate(times, t, "ARAP"); }

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
    std::vector<cd> x = poisson->solve(tris, A);
    // E leaves each component's translation free: move its centroid linearly between the keyframes'.
    std::vector<cd> target(centroid[at(k)].size());
    for (size_t c = 0; c < target.size(); ++c) target[c] = (1 - s) * centroid[at(k)][c] + s * centroid[at(k + 1)][c];
    components.move_centroids(x, target);
    return x;
  }

  double energy(const std::vector<Mat2>& A, std::span<const cd> x) const { return PoissonSolver::energy(tris, A, x); }
};

ArapInterpolation::ArapInterpolation(const TriMesh& rest, std::vector<ArapKeyframe> keyframes) {
  auto impl = std::make_shared<Impl>();
  Impl& m = *impl;
  m.n = rest.vertex_count();
  m.tris = rest_triangles(rest);
  const size_t T = m.tris.size();
  check_keyframes(rest, keyframes, "ARAP");
  // Connected components (a vertex in no triangle would leave K singular).
  m.components = mesh_components(m.n, m.tris);
  const size_t C = m.components.component_mass.size();
  const std::vector<int>& component = m.components.component;
  check_orientation(m.tris, keyframes, "ARAP", "ARAP's polar decomposition needs det J > 0");

  // Polar decompositions J = R(θ) S of every keyframe triangle.
  const size_t K = keyframes.size();
  std::vector<std::vector<double>> theta(K, std::vector<double>(T));
  m.stretch.assign(K, std::vector<std::array<double, 3>>(T));
  m.centroid.assign(K, std::vector<cd>(C));
  for (size_t k = 0; k < K; ++k) {
    const std::vector<cd>& x = keyframes[k].positions;
    for (size_t t = 0; t < T; ++t) {
      const Mat2 J = jacobian(m.tris[t], x);
      theta[k][t] = polar_angle(J);
      const Mat2 S = rotation(theta[k][t]).transpose() * J;
      m.stretch[k][t] = {S(0, 0), 0.5 * (S(0, 1) + S(1, 0)), S(1, 1)};
    }
    m.centroid[k] = m.components.centroids(x);
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
    for (size_t t = 0; t < T; ++t) mean[at(component[at(m.tris[t].v[0])])] += m.tris[t].area * std::polar(1.0, d[t]);
    std::vector<int> seed(C, -1);
    for (size_t t = 0; t < T; ++t) {
      const size_t c = at(component[at(m.tris[t].v[0])]);
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
    for (size_t t = 0; t < T; ++t) turn[at(component[at(m.tris[t].v[0])])] += m.tris[t].area * delta[t];
    for (size_t c = 0; c < C; ++c) {
      const double full_turns = std::round(turn[c] / m.components.component_mass[c] / (2 * std::numbers::pi));
      turn[c] = -2 * std::numbers::pi * full_turns;
    }
    for (size_t t = 0; t < T; ++t)
      m.alpha[k + 1][t] = m.alpha[k][t] + delta[t] + turn[at(component[at(m.tris[t].v[0])])];
  }

  m.poisson.emplace(m.n, m.tris, m.components, "ARAP");

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
