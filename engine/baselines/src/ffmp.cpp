// FFMP interpolation (hsi/baselines/ffmp.h): connection maps between edge-adjacent
// triangles blended linearly, the frames from one sparse least-squares solve per frame,
// the positions from ARAP's factorised Poisson system.
#include "hsi/stopwatch.h"
#include "hsi/baselines/ffmp.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <string>

#include "mesh_support.h"

namespace hsi::baselines {

using namespace detail;

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

struct FfmpInterpolation::Impl {
  int n = 0;
  std::vector<RestTriangle> tris;
  std::vector<double> times;
  MeshComponents components;
  std::vector<std::vector<cd>> centroid;  // per keyframe, per component
  std::optional<PoissonSolver> poisson;

  struct Pair {
    int i = 0, j = 0;
    double w = 0;                     // mean rest area of the two triangles
    std::vector<Mat2> Q_ij, Q_ji;     // per keyframe: J_i⁻¹ J_j and J_j⁻¹ J_i
    std::array<int, 16> slots{};      // blocks (i,i), (i,j), (j,i), (j,j), row-major 2×2 each; −1 where not free
  };
  std::vector<Pair> pairs;
  std::vector<int> anchors;                         // per edge-connected set
  std::vector<int> free_index;                      // per triangle: its block in the frame system, −1 for an anchor
  int free_count = 0;
  // Per anchor: per keyframe the lifted polar angle and the stretch (s00, s01, s11).
  std::vector<std::vector<double>> anchor_angle;
  std::vector<std::vector<std::array<double, 3>>> anchor_stretch;
  std::optional<FixedPattern> pattern;

  std::pair<int, double> locate(double t) const { return detail::locate(times, t, "FFMP"); }

  // Solve 1: the frames at (k, s), and the frame system's relative residual.
  std::vector<Mat2> frames(int k, double s, double& residual) const {
    std::vector<Mat2> J(tris.size());
    for (size_t a = 0; a < anchors.size(); ++a) {
      const auto &S0 = anchor_stretch[a][at(k)], &S1 = anchor_stretch[a][at(k + 1)];
      Mat2 S;
      S << (1 - s) * S0[0] + s * S1[0], (1 - s) * S0[1] + s * S1[1], (1 - s) * S0[1] + s * S1[1], (1 - s) * S0[2] + s * S1[2];
      J[at(anchors[a])] = rotation((1 - s) * anchor_angle[a][at(k)] + s * anchor_angle[a][at(k + 1)]) * S;
    }
    std::vector<Mat2> Q(pairs.size()), P(pairs.size());
    for (size_t p = 0; p < pairs.size(); ++p) {
      Q[p] = (1 - s) * pairs[p].Q_ij[at(k)] + s * pairs[p].Q_ij[at(k + 1)];
      P[p] = (1 - s) * pairs[p].Q_ji[at(k)] + s * pairs[p].Q_ji[at(k + 1)];
    }
    if (free_count > 0) {
      // Normal equations per row ρ of the frames, x_i = (row ρ of J_i)ᵀ: the residual
      // Qᵀ x_i − x_j of a direction gives blocks M_ii += w QQᵀ, M_ij −= w Q, M_ji −= w Qᵀ,
      // M_jj += w I; an anchor's known x moves to the right-hand side.
      FixedPattern M = *pattern;
      M.zero();
      double* values = M.values();
      Eigen::MatrixXd b = Eigen::MatrixXd::Zero(2 * free_count, 2);
      auto direction = [&](int i, int j, const Mat2& q, double w, const std::array<int, 16>& slot, bool flip) {
        const int fi = free_index[at(i)], fj = free_index[at(j)];
        const Mat2 blocks[4] = {w * q * q.transpose(), -w * q, -w * q.transpose(), w * Mat2::Identity()};
        // With flip the pair's (i, j) are this direction's (j, i): blocks (i,i)↔(j,j), (i,j)↔(j,i).
        const int order[4] = {flip ? 3 : 0, flip ? 2 : 1, flip ? 1 : 2, flip ? 0 : 3};
        for (int B = 0; B < 4; ++B)
          for (int e = 0; e < 4; ++e) {
            const int sl = slot[at(4 * order[B] + e)];
            if (sl >= 0) values[sl] += blocks[B](e / 2, e % 2);
          }
        const Mat2 Xi = J[at(i)].transpose(), Xj = J[at(j)].transpose();
        if (fi < 0 && fj >= 0) b.middleRows(2 * fj, 2) += w * q.transpose() * Xi;
        if (fj < 0 && fi >= 0) b.middleRows(2 * fi, 2) += w * q * Xj;
      };
      for (size_t p = 0; p < pairs.size(); ++p) {
        const Pair& pr = pairs[p];
        direction(pr.i, pr.j, Q[p], pr.w / 2, pr.slots, false);
        direction(pr.j, pr.i, P[p], pr.w / 2, pr.slots, true);
      }
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(M.matrix());
      if (ldlt.info() != Eigen::Success)
        throw std::runtime_error("FFMP: the frame system could not be factorised (blended connection maps degenerate)");
      const Eigen::MatrixXd X = ldlt.solve(b);
      for (size_t t = 0; t < tris.size(); ++t) {
        const int f = free_index[t];
        if (f >= 0) J[t] << X(2 * f, 0), X(2 * f + 1, 0), X(2 * f, 1), X(2 * f + 1, 1);
      }
    }
    double r = 0, norm = 0;
    for (size_t p = 0; p < pairs.size(); ++p) {
      const Pair& pr = pairs[p];
      r += pr.w / 2 * ((J[at(pr.i)] * Q[p] - J[at(pr.j)]).squaredNorm() + (J[at(pr.j)] * P[p] - J[at(pr.i)]).squaredNorm());
      norm += pr.w / 2 * (J[at(pr.j)].squaredNorm() + J[at(pr.i)].squaredNorm());
    }
    residual = norm > 0 ? std::sqrt(r / norm) : 0;
    return J;
  }

  FfmpFrame frame(double t) const {
    const auto [k, s] = locate(t);
    FfmpFrame f;
    auto t0 = Clock::now();
    const std::vector<Mat2> J = frames(k, s, f.frame_residual);
    f.frames_ms = ms_since(t0);
    t0 = Clock::now();
    f.positions = poisson->solve(tris, J);
    std::vector<cd> target(centroid[at(k)].size());
    for (size_t c = 0; c < target.size(); ++c) target[c] = (1 - s) * centroid[at(k)][c] + s * centroid[at(k + 1)][c];
    components.move_centroids(f.positions, target);
    f.positions_ms = ms_since(t0);
    double norm = 0;
    for (size_t i = 0; i < J.size(); ++i) norm += tris[i].area * J[i].squaredNorm();
    f.position_residual = std::sqrt(PoissonSolver::energy(tris, J, f.positions) / norm);
    return f;
  }
};

FfmpInterpolation::FfmpInterpolation(const TriMesh& rest, std::vector<MeshKeyframe> keyframes, FfmpOptions options) {
  auto impl = std::make_shared<Impl>();
  Impl& m = *impl;
  m.n = rest.vertex_count();
  m.tris = rest_triangles(rest);
  const int T = static_cast<int>(m.tris.size());
  if (options.anchor_triangle < -1 || options.anchor_triangle >= T)
    throw InputError("FFMP options: anchor_triangle " + std::to_string(options.anchor_triangle) + " is not a triangle (0.." +
                     std::to_string(T - 1) + ") or -1");
  check_keyframes(rest, keyframes, "FFMP");
  m.components = mesh_components(m.n, m.tris);
  check_orientation(m.tris, keyframes, "FFMP", "FFMP's connection maps need J invertible and its anchors det J > 0");
  const size_t K = keyframes.size();

  std::vector<std::vector<Mat2>> J(K, std::vector<Mat2>(at(T)));
  m.centroid.resize(K);
  for (size_t k = 0; k < K; ++k) {
    for (int t = 0; t < T; ++t) J[k][at(t)] = jacobian(m.tris[at(t)], keyframes[k].positions);
    m.centroid[k] = m.components.centroids(keyframes[k].positions);
  }

  // Edge-adjacent pairs (an edge of more than two triangles links them in a chain) and
  // the edge-connected sets they make.
  std::map<std::pair<int, int>, std::vector<int>> edge_triangles;
  for (int t = 0; t < T; ++t)
    for (int e = 0; e < 3; ++e) {
      const int a = m.tris[at(t)].v[at(e)], b = m.tris[at(t)].v[at((e + 1) % 3)];
      edge_triangles[{std::min(a, b), std::max(a, b)}].push_back(t);
    }
  std::vector<int> parent(at(T));
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[at(i)] != i) i = parent[at(i)] = parent[at(parent[at(i)])];
    return i;
  };
  for (const auto& [edge, ts] : edge_triangles)
    for (size_t q = 1; q < ts.size(); ++q) {
      Impl::Pair p;
      p.i = ts[q - 1];
      p.j = ts[q];
      p.w = 0.5 * (m.tris[at(p.i)].area + m.tris[at(p.j)].area);
      for (size_t k = 0; k < K; ++k) {
        p.Q_ij.push_back(J[k][at(p.i)].inverse() * J[k][at(p.j)]);
        p.Q_ji.push_back(J[k][at(p.j)].inverse() * J[k][at(p.i)]);
      }
      m.pairs.push_back(std::move(p));
      parent[at(find(ts[q]))] = find(ts[q - 1]);
    }

  // One anchor per set: the triangle nearest the set's area-weighted rest centroid.
  std::vector<int> set_of(at(T), -1), root_set(at(T), -1);
  std::vector<cd> set_centroid;
  std::vector<double> set_area;
  auto rest_centroid = [&](int t) {
    const auto& v = m.tris[at(t)].v;
    return (rest.vertices[at(v[0])] + rest.vertices[at(v[1])] + rest.vertices[at(v[2])]) / 3.0;
  };
  for (int t = 0; t < T; ++t) {
    int& s = root_set[at(find(t))];
    if (s < 0) {
      s = static_cast<int>(set_area.size());
      set_area.push_back(0);
      set_centroid.push_back(0);
    }
    set_of[at(t)] = s;
    set_area[at(s)] += m.tris[at(t)].area;
    set_centroid[at(s)] += m.tris[at(t)].area * rest_centroid(t);
  }
  m.anchors.assign(set_area.size(), -1);
  for (int t = 0; t < T; ++t) {
    const size_t s = at(set_of[at(t)]);
    const cd c = set_centroid[s] / set_area[s];
    if (m.anchors[s] < 0 || std::abs(rest_centroid(t) - c) < std::abs(rest_centroid(m.anchors[s]) - c)) m.anchors[s] = t;
  }
  if (options.anchor_triangle >= 0) m.anchors[at(set_of[at(options.anchor_triangle)])] = options.anchor_triangle;

  // The anchors' own interpolation: polar decompositions, angles lifted the short way.
  for (int a : m.anchors) {
    std::vector<double> angle;
    std::vector<std::array<double, 3>> stretch;
    for (size_t k = 0; k < K; ++k) {
      const double theta = polar_angle(J[k][at(a)]);
      angle.push_back(k == 0 ? theta : angle.back() + wrap(theta - angle.back()));
      const Mat2 S = rotation(theta).transpose() * J[k][at(a)];
      stretch.push_back({S(0, 0), 0.5 * (S(0, 1) + S(1, 0)), S(1, 1)});
    }
    m.anchor_angle.push_back(std::move(angle));
    m.anchor_stretch.push_back(std::move(stretch));
  }

  // The frame system's pattern over the free triangles (2 unknowns each).
  m.free_index.assign(at(T), -1);
  std::vector<char> is_anchor(at(T), 0);
  for (int a : m.anchors) is_anchor[at(a)] = 1;
  for (int t = 0; t < T; ++t)
    if (!is_anchor[at(t)]) m.free_index[at(t)] = m.free_count++;
  if (m.free_count > 0) {
    std::vector<std::pair<int, int>> entries;
    for (int t = 0; t < T; ++t)
      if (m.free_index[at(t)] >= 0)
        for (int e = 0; e < 4; ++e) entries.emplace_back(2 * m.free_index[at(t)] + e / 2, 2 * m.free_index[at(t)] + e % 2);
    for (const Impl::Pair& p : m.pairs) {
      const int fi = m.free_index[at(p.i)], fj = m.free_index[at(p.j)];
      if (fi >= 0 && fj >= 0)
        for (int e = 0; e < 4; ++e) {
          entries.emplace_back(2 * fi + e / 2, 2 * fj + e % 2);
          entries.emplace_back(2 * fj + e / 2, 2 * fi + e % 2);
        }
    }
    m.pattern.emplace(2 * m.free_count, entries);
    for (Impl::Pair& p : m.pairs) {
      const int f[2] = {m.free_index[at(p.i)], m.free_index[at(p.j)]};
      const int block_rows[4] = {0, 0, 1, 1}, block_cols[4] = {0, 1, 0, 1};  // (i,i), (i,j), (j,i), (j,j)
      for (int B = 0; B < 4; ++B) {
        const int r = f[block_rows[B]], c = f[block_cols[B]];
        for (int e = 0; e < 4; ++e)
          p.slots[at(4 * B + e)] = r >= 0 && c >= 0 ? m.pattern->slot(2 * r + e / 2, 2 * c + e % 2) : -1;
      }
    }
  }

  m.poisson.emplace(m.n, m.tris, m.components, "FFMP");
  for (const MeshKeyframe& kf : keyframes) m.times.push_back(kf.time);
  impl_ = std::move(impl);
}

std::vector<cd> FfmpInterpolation::positions(double t) const { return impl_->frame(t).positions; }
FfmpFrame FfmpInterpolation::frame(double t) const { return impl_->frame(t); }
double FfmpInterpolation::t_begin() const { return impl_->times.front(); }
double FfmpInterpolation::t_end() const { return impl_->times.back(); }
int FfmpInterpolation::keyframe_count() const { return static_cast<int>(impl_->times.size()); }
std::vector<int> FfmpInterpolation::anchors() const { return impl_->anchors; }

}  // namespace hsi::baselines
