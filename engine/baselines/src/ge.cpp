// GE interpolation (hsi/baselines/ge.h): per-triangle blended metrics, the symmetric
// Dirichlet energy against them with SGK19's analytic eigensystem, and a flip-free
// projected Newton per frame with one sparse Cholesky per iteration.
#include "hsi/baselines/ge.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <string>

#include "mesh_support.h"

namespace hsi::baselines {

using namespace detail;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
using Clock = std::chrono::steady_clock;

// vec(F) index of F(r, c), column-major.
constexpr int vec_index(int r, int c) { return r + 2 * c; }

Eigen::Vector4d vec(const Mat2& A) { return {A(0, 0), A(1, 0), A(0, 1), A(1, 1)}; }

// f_z of J: its conformal part, J acting as z ↦ f_z z + f_z̄ z̄.
cd f_z(const Mat2& J) { return 0.5 * cd(J(0, 0) + J(1, 1), J(1, 0) - J(0, 1)); }

// The smallest s > 0 with det(X + s D) = 0 given det X > 0 (orientation-signed), +∞ if none.
double first_degenerate_step(const Mat2& X, const Mat2& D, double sign) {
  const double a = sign * D.determinant();
  const double b = sign * (X(0, 0) * D(1, 1) + D(0, 0) * X(1, 1) - X(0, 1) * D(1, 0) - D(0, 1) * X(1, 0));
  const double c = sign * X.determinant();
  const double scale = std::abs(a) + std::abs(b) + std::abs(c);
  if (std::abs(a) <= 1e-14 * scale) return b < 0 ? -c / b : kInf;
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return kInf;  // det keeps its sign (a > 0 here, as c > 0)
  // Both roots without cancellation: q = −(b + sign(b)√disc)/2, roots q/a and c/q.
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  double best = kInf;
  for (double r : {q / a, q != 0 ? c / q : kInf})
    if (r > 0) best = std::min(best, r);
  return best;
}

}  // namespace

SymmetricDirichletEigensystem symmetric_dirichlet_eigensystem(const Eigen::Matrix2d& F) {
  if (!F.allFinite()) throw InputError("symmetric Dirichlet: F is not finite");
  if (!(F.determinant() > 0)) throw InputError("symmetric Dirichlet: det F = " + num(F.determinant()) + " is not positive");
  // F acts as z ↦ a z + b z̄; F = R(α) diag(σ1, σ2) R(−β) with a = |a| e^{i(α−β)}, b = |b| e^{i(α+β)}.
  const cd a = f_z(F);
  const cd b = 0.5 * cd(F(0, 0) - F(1, 1), F(1, 0) + F(0, 1));
  const double s1 = std::abs(a) + std::abs(b), s2 = std::abs(a) - std::abs(b);
  const double arg_b = std::abs(b) > 0 ? std::arg(b) : 0.0;
  const double alpha = 0.5 * (std::arg(a) + arg_b), beta = 0.5 * (arg_b - std::arg(a));
  const Mat2 U = rotation(alpha), V = rotation(beta);
  SymmetricDirichletEigensystem e;
  e.psi = 0.5 * (s1 * s1 + s2 * s2 + 1 / (s1 * s1) + 1 / (s2 * s2));
  e.gradient = vec(U * Eigen::Vector2d(s1 - 1 / (s1 * s1 * s1), s2 - 1 / (s2 * s2 * s2)).asDiagonal() * V.transpose());
  const double p3 = s1 * s1 * s1 * s2 * s2 * s2;
  e.eigenvalues << 1 + 3 / (s1 * s1 * s1 * s1), 1 + 3 / (s2 * s2 * s2 * s2), 1 + (s1 * s1 + s1 * s2 + s2 * s2) / p3,
      1 - (s1 * s1 - s1 * s2 + s2 * s2) / p3;
  Mat2 D1, D2, L, T;
  D1 << 1, 0, 0, 0;
  D2 << 0, 0, 0, 1;
  L << 0, 1, 1, 0;
  T << 0, -1, 1, 0;
  e.eigenvectors.col(0) = vec(U * D1 * V.transpose());
  e.eigenvectors.col(1) = vec(U * D2 * V.transpose());
  e.eigenvectors.col(2) = vec(U * L * V.transpose()) / std::numbers::sqrt2;
  e.eigenvectors.col(3) = vec(U * T * V.transpose()) / std::numbers::sqrt2;
  return e;
}

Eigen::Matrix4d SymmetricDirichletEigensystem::hessian(bool project) const {
  Eigen::Vector4d l = eigenvalues;
  if (project) l = l.cwiseMax(0.0);
  return eigenvectors * l.asDiagonal() * eigenvectors.transpose();
}

struct GeInterpolation::Impl {
  int n = 0;
  std::vector<RestTriangle> tris;
  std::vector<double> orientation;            // per triangle: sign of det E_inv (det F > 0 ⇔ sign·det X > 0)
  double total_area = 0;
  std::vector<double> times;
  std::vector<MeshKeyframe> keyframes;
  std::vector<std::vector<std::array<double, 3>>> metric;  // per keyframe, per triangle: M = JᵀJ (m00, m01, m11)
  MeshComponents components;
  std::vector<std::vector<cd>> centroid;      // per keyframe, per component
  std::vector<std::vector<double>> turn;      // per keyframe, per component: lifted arg Σ area f_z
  GeOptions options;
  // The Hessian's pattern over 2n coordinates (x_i at 2i, y_i at 2i+1), built once: per
  // triangle its 6×6 slots, per coordinate its diagonal slot.
  std::optional<FixedPattern> pattern;
  std::vector<std::array<int, 36>> slots;
  std::vector<int> diagonal;

  // Per triangle at one time: B with F = X B (X the edge matrix of x).
  std::vector<Mat2> operators(double t) const {
    const auto [k, s] = locate(times, t, "GE");
    std::vector<Mat2> B(tris.size());
    for (size_t i = 0; i < tris.size(); ++i) {
      const auto &m0 = metric[at(k)][i], &m1 = metric[at(k + 1)][i];
      const double a = (1 - s) * m0[0] + s * m1[0], b = (1 - s) * m0[1] + s * m1[1], c = (1 - s) * m0[2] + s * m1[2];
      // M = L Lᵀ, G = Lᵀ, G⁻¹ upper triangular.
      const double l00 = std::sqrt(a), l10 = b / l00, l11 = std::sqrt(std::max(c - l10 * l10, 0.0));
      Mat2 G_inv;
      G_inv << 1 / l00, -l10 / (l00 * l11), 0, 1 / l11;
      B[i] = tris[i].E_inv * G_inv;
    }
    return B;
  }

  Mat2 edges(size_t i, std::span<const cd> x) const {
    const auto& v = tris[i].v;
    return edge_matrix(x[at(v[0])], x[at(v[1])], x[at(v[2])]);
  }

  double energy(std::span<const Mat2> B, std::span<const cd> x) const {
    double e = 0;
    for (size_t i = 0; i < tris.size(); ++i) {
      const Mat2 X = edges(i, x);
      if (!(orientation[i] * X.determinant() > 0)) return kInf;
      const Mat2 F = X * B[i];
      const Mat2 F_inv = F.inverse();
      e += tris[i].area * 0.5 * (F.squaredNorm() + F_inv.squaredNorm());
    }
    return e;
  }

  // ∂F_{rc}/∂x_{v_j, r} = coefficient(j, c).
  static std::array<std::array<double, 2>, 3> coefficients(const Mat2& B) {
    return {{{-B(0, 0) - B(1, 0), -B(0, 1) - B(1, 1)}, {B(0, 0), B(0, 1)}, {B(1, 0), B(1, 1)}}};
  }

  // Gradient (2n) and, if H is given, the Hessian's values in the fixed pattern (projected or exact).
  void derivatives(std::span<const Mat2> B, std::span<const cd> x, Eigen::VectorXd& g, FixedPattern* H, bool project) const {
    g = Eigen::VectorXd::Zero(2 * n);
    if (H) H->zero();
    for (size_t i = 0; i < tris.size(); ++i) {
      const Mat2 F = edges(i, x) * B[i];
      const SymmetricDirichletEigensystem e = symmetric_dirichlet_eigensystem(F);
      const auto c = coefficients(B[i]);
      const double area = tris[i].area;
      // A: 4×6, vec F = A x_T with x_T = (x_v0, y_v0, x_v1, y_v1, x_v2, y_v2).
      Eigen::Matrix<double, 4, 6> A = Eigen::Matrix<double, 4, 6>::Zero();
      for (int j = 0; j < 3; ++j)
        for (int r = 0; r < 2; ++r)
          for (int col = 0; col < 2; ++col) A(vec_index(r, col), 2 * j + r) = c[at(j)][at(col)];
      const Eigen::Matrix<double, 6, 1> gt = area * A.transpose() * e.gradient;
      const auto& v = tris[i].v;
      for (int j = 0; j < 3; ++j)
        for (int r = 0; r < 2; ++r) g[2 * v[at(j)] + r] += gt[2 * j + r];
      if (H) {
        const Eigen::Matrix<double, 6, 6> Ht = area * A.transpose() * e.hessian(project) * A;
        double* values = H->values();
        const auto& s = slots[i];
        for (int p = 0; p < 6; ++p)
          for (int q = 0; q < 6; ++q) values[s[at(6 * p + q)]] += Ht(p, q);
      }
    }
  }

  double max_step(std::span<const cd> x, const Eigen::VectorXd& d) const {
    double s_max = kInf;
    for (size_t i = 0; i < tris.size(); ++i) {
      const auto& v = tris[i].v;
      auto dv = [&](int j) { return cd(d[2 * v[at(j)]], d[2 * v[at(j)] + 1]); };
      s_max = std::min(s_max, first_degenerate_step(edges(i, x), edge_matrix(dv(0), dv(1), dv(2)), orientation[i]));
    }
    return s_max;
  }

  void check_start(std::span<const cd> x, const std::string& what) const {
    for (size_t i = 0; i < tris.size(); ++i) {
      const double det = orientation[i] * edges(i, x).determinant();
      if (!(det > 0))
        throw InputError(what + ": " + triangle_name(static_cast<int>(i), tris[i].v) + " is " +
                         (det < 0 ? "flipped" : "degenerate") + "; GE's Newton needs a start without flipped triangles");
    }
  }

  // Per component: the mean turn arg Σ_T area_T f_z,T and whether it is defined.
  std::vector<std::pair<double, bool>> turns(std::span<const cd> x) const {
    std::vector<cd> sum(at(components.count()));
    std::vector<double> magnitude(sum.size());
    for (size_t i = 0; i < tris.size(); ++i) {
      const cd fz = f_z(jacobian(tris[i], x));
      const size_t c = at(components.component[at(tris[i].v[0])]);
      sum[c] += tris[i].area * fz;
      magnitude[c] += tris[i].area * std::abs(fz);
    }
    std::vector<std::pair<double, bool>> r(sum.size());
    for (size_t c = 0; c < sum.size(); ++c) r[c] = {std::arg(sum[c]), std::abs(sum[c]) > 1e-9 * magnitude[c]};
    return r;
  }

  // Rigid placement of each component at time t (ge.h: centroid and mean turn linear in s).
  void place(double t, std::vector<cd>& x) const {
    const auto [k, s] = locate(times, t, "GE");
    const std::vector<cd> now = components.centroids(x);
    const auto now_turn = turns(x);
    std::vector<cd> spin(now.size(), 1.0);
    for (size_t c = 0; c < now.size(); ++c)
      if (now_turn[c].second) spin[c] = std::polar(1.0, (1 - s) * turn[at(k)][c] + s * turn[at(k + 1)][c] - now_turn[c].first);
    for (size_t i = 0; i < x.size(); ++i) {
      const size_t c = at(components.component[i]);
      x[i] = now[c] + spin[c] * (x[i] - now[c]);
    }
    std::vector<cd> target(now.size());
    for (size_t c = 0; c < target.size(); ++c) target[c] = (1 - s) * centroid[at(k)][c] + s * centroid[at(k + 1)][c];
    components.move_centroids(x, target);
  }

  GeFrame solve(double t, std::vector<cd> x) const {
    const auto t0 = Clock::now();
    GeFrame f;
    f.time = t;
    const std::vector<Mat2> B = operators(t);
    // Gauge: per component its first vertex pinned, and the y of the vertex farthest from it along x.
    std::vector<char> pinned(at(2 * n), 0);
    {
      std::vector<int> first(at(components.count()), -1), far(first.size(), -1);
      for (int i = 0; i < n; ++i) {
        const size_t c = at(components.component[at(i)]);
        if (first[c] < 0) {
          first[c] = i;
        } else if (far[c] < 0 || std::abs(x[at(i)].real() - x[at(first[c])].real()) >
                                     std::abs(x[at(far[c])].real() - x[at(first[c])].real())) {
          far[c] = i;
        }
      }
      for (size_t c = 0; c < first.size(); ++c) {
        pinned[at(2 * first[c])] = pinned[at(2 * first[c] + 1)] = 1;
        pinned[at(2 * far[c] + 1)] = 1;
      }
    }
    FixedPattern H = *pattern;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
    ldlt.analyzePattern(H.matrix());  // the pattern is the mesh's: the ordering is reused by every iteration
    Eigen::VectorXd g, d;
    double E = energy(B, x);
    std::vector<cd> trial(x.size());
    while (f.iterations < options.max_iterations) {
      derivatives(B, x, g, &H, true);
      // Pinned coordinates: identity rows and columns, zero gradient.
      double max_diag = 0;
      for (int j = 0; j < 2 * n; ++j)
        if (!pinned[at(j)]) max_diag = std::max(max_diag, H.values()[diagonal[at(j)]]);
      for (int col = 0; col < 2 * n; ++col)
        for (Eigen::SparseMatrix<double>::InnerIterator it(H.matrix(), col); it; ++it)
          if (pinned[static_cast<size_t>(it.row())] || pinned[at(col)]) it.valueRef() = it.row() == col ? max_diag : 0.0;
      for (int j = 0; j < 2 * n; ++j)
        if (pinned[at(j)]) g[j] = 0;
      bool factored = false;
      for (int attempt = 0; attempt <= 12 && !factored; ++attempt) {
        if (attempt > 0) {
          const double ridge = 1e-12 * std::pow(10.0, attempt - 1) * max_diag;
          for (int j = 0; j < 2 * n; ++j)
            if (!pinned[at(j)]) H.values()[diagonal[at(j)]] += attempt == 1 ? ridge : 0.9 * ridge;
        }
        ldlt.factorize(H.matrix());
        ++f.factorisations;
        factored = ldlt.info() == Eigen::Success && ldlt.vectorD().minCoeff() > 0;
      }
      if (!factored) break;
      d = -ldlt.solve(g);
      const double slope = g.dot(d);
      if (!(slope < 0) || -slope / 2 <= options.tolerance * std::abs(E)) {
        f.converged = -slope / 2 <= options.tolerance * std::abs(E);
        break;
      }
      double step = std::min(1.0, options.safe_fraction * max_step(x, d));
      double E_trial = kInf;
      bool accepted = false;
      for (int b = 0; b <= options.max_backtracks; ++b, step *= options.shrink) {
        for (int i = 0; i < n; ++i) trial[at(i)] = x[at(i)] + step * cd(d[2 * i], d[2 * i + 1]);
        E_trial = energy(B, trial);
        if (E_trial <= E + options.armijo * step * slope) {
          accepted = true;
          break;
        }
      }
      if (!accepted) break;
      std::swap(x, trial);
      ++f.iterations;
      const double decrease = E - E_trial;
      E = E_trial;
      if (decrease < options.tolerance * std::abs(E)) {
        f.converged = true;
        break;
      }
    }
    place(t, x);
    f.positions = std::move(x);
    f.energy = E / total_area;
    f.ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    return f;
  }
};

GeInterpolation::GeInterpolation(const TriMesh& rest, std::vector<MeshKeyframe> keyframes, GeOptions options) {
  auto impl = std::make_shared<Impl>();
  Impl& m = *impl;
  m.n = rest.vertex_count();
  m.tris = rest_triangles(rest);
  m.options = options;
  if (!(options.tolerance >= 0) || options.max_iterations < 0 || !(options.armijo > 0 && options.armijo < 1) ||
      !(options.shrink > 0 && options.shrink < 1) || !(options.safe_fraction > 0 && options.safe_fraction < 1) ||
      options.max_backtracks < 0)
    throw InputError("GE options: tolerance ≥ 0, max_iterations ≥ 0, armijo, shrink and safe_fraction in (0, 1), "
                     "max_backtracks ≥ 0");
  check_keyframes(rest, keyframes, "GE");
  m.components = mesh_components(m.n, m.tris);
  check_orientation(m.tris, keyframes, "GE", "GE's energy needs det J > 0 (its metric and barrier)");
  const size_t T = m.tris.size(), K = keyframes.size(), C = at(m.components.count());
  for (const RestTriangle& tri : m.tris) {
    m.orientation.push_back(tri.E_inv.determinant() > 0 ? 1.0 : -1.0);
    m.total_area += tri.area;
  }
  m.metric.assign(K, std::vector<std::array<double, 3>>(T));
  m.centroid.resize(K);
  m.turn.assign(K, std::vector<double>(C));
  for (size_t k = 0; k < K; ++k) {
    const std::vector<cd>& x = keyframes[k].positions;
    for (size_t t = 0; t < T; ++t) {
      const Mat2 J = jacobian(m.tris[t], x);
      const Mat2 M = J.transpose() * J;
      m.metric[k][t] = {M(0, 0), 0.5 * (M(0, 1) + M(1, 0)), M(1, 1)};
    }
    m.centroid[k] = m.components.centroids(x);
    const auto turns = m.turns(x);
    for (size_t c = 0; c < C; ++c) {
      if (!turns[c].second)
        throw InputError(keyframe_name("GE", k, keyframes[k].time) + ": component " + std::to_string(c) +
                         " has no mean turn (its triangles' conformal parts cancel)");
      m.turn[k][c] = k == 0 ? turns[c].first : m.turn[k - 1][c] + wrap(turns[c].first - m.turn[k - 1][c]);
    }
  }
  // The Hessian's pattern: every pair of coordinates of a triangle's vertices.
  std::vector<std::pair<int, int>> entries;
  entries.reserve(36 * T + 2 * at(m.n));
  for (int j = 0; j < 2 * m.n; ++j) entries.emplace_back(j, j);
  for (const RestTriangle& tri : m.tris)
    for (int p = 0; p < 6; ++p)
      for (int q = 0; q < 6; ++q) entries.emplace_back(2 * tri.v[at(p / 2)] + p % 2, 2 * tri.v[at(q / 2)] + q % 2);
  m.pattern.emplace(2 * m.n, entries);
  m.slots.resize(T);
  for (size_t t = 0; t < T; ++t)
    for (int p = 0; p < 6; ++p)
      for (int q = 0; q < 6; ++q)
        m.slots[t][at(6 * p + q)] =
            m.pattern->slot(2 * m.tris[t].v[at(p / 2)] + p % 2, 2 * m.tris[t].v[at(q / 2)] + q % 2);
  for (int j = 0; j < 2 * m.n; ++j) m.diagonal.push_back(m.pattern->slot(j, j));
  for (const MeshKeyframe& kf : keyframes) m.times.push_back(kf.time);
  m.keyframes = std::move(keyframes);
  impl_ = std::move(impl);
}

std::vector<GeFrame> GeInterpolation::sequence(std::span<const double> times,
                                               const std::function<void(const GeFrame&, int, int)>& progress) const {
  std::vector<GeFrame> frames;
  if (times.empty()) return frames;
  const Impl& m = *impl_;
  if (std::isnan(times[0])) throw InputError("GE interpolation: the time is NaN");
  size_t nearest = 0;
  for (size_t k = 1; k < m.times.size(); ++k)
    if (std::abs(m.times[k] - times[0]) < std::abs(m.times[nearest] - times[0])) nearest = k;
  std::vector<cd> start = m.keyframes[nearest].positions;
  for (double t : times) {
    frames.push_back(m.solve(t, start));
    start = frames.back().positions;
    if (progress) progress(frames.back(), static_cast<int>(frames.size()) - 1, static_cast<int>(times.size()));
  }
  return frames;
}

GeFrame GeInterpolation::frame(double t, std::span<const cd> start) const {
  const Impl& m = *impl_;
  if (std::isnan(t)) throw InputError("GE interpolation: the time is NaN");
  if (start.size() != at(m.n))
    throw InputError("GE start has " + std::to_string(start.size()) + " positions; the rest mesh has " + std::to_string(m.n) +
                     " vertices");
  for (size_t i = 0; i < start.size(); ++i)
    if (!std::isfinite(start[i].real()) || !std::isfinite(start[i].imag()))
      throw InputError("GE start: vertex " + std::to_string(i) + " is not finite " + point(start[i]));
  m.check_start(start, "GE start");
  return m.solve(t, std::vector<cd>(start.begin(), start.end()));
}

double GeInterpolation::energy(double t, std::span<const cd> x) const {
  if (x.size() != at(impl_->n)) throw InputError("GE energy: wrong number of positions");
  return impl_->energy(impl_->operators(t), x);
}

Eigen::VectorXd GeInterpolation::gradient(double t, std::span<const cd> x) const {
  if (x.size() != at(impl_->n)) throw InputError("GE gradient: wrong number of positions");
  impl_->check_start(x, "GE gradient");
  Eigen::VectorXd g;
  impl_->derivatives(impl_->operators(t), x, g, nullptr, false);
  return g;
}

Eigen::SparseMatrix<double> GeInterpolation::hessian(double t, std::span<const cd> x, bool project) const {
  if (x.size() != at(impl_->n)) throw InputError("GE Hessian: wrong number of positions");
  impl_->check_start(x, "GE Hessian");
  FixedPattern H = *impl_->pattern;
  Eigen::VectorXd g;
  impl_->derivatives(impl_->operators(t), x, g, &H, project);
  return H.matrix();
}

double GeInterpolation::t_begin() const { return impl_->times.front(); }
double GeInterpolation::t_end() const { return impl_->times.back(); }
int GeInterpolation::keyframe_count() const { return static_cast<int>(impl_->times.size()); }
const GeOptions& GeInterpolation::options() const { return impl_->options; }

}  // namespace hsi::baselines
