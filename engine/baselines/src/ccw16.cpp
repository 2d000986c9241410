// CCW16 (Chien, Chen & Weber 2016): pointwise blend of log f_z and ν, or the boundary
// metric blend with a least-squares Hilbert transform, integrated along paths
// (hsi/baselines/ccw16.h has the formulas). The shape-level checks, the branch of λ_k and
// the least-squares factorisations are fixed once; a mesh's spanning tree, nodes and
// derivative values (or basis rows) once per mesh.
#include "hsi/baselines/ccw16.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <limits>
#include <numbers>
#include <string>
#include <unordered_map>

#include "hsi/samples.h"

namespace hsi::baselines {

namespace {

constexpr double kPi = std::numbers::pi;

std::string num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}
std::string point(cd p) { return "(" + num(p.real()) + ", " + num(p.imag()) + ")"; }
std::string key_name(int k, double t) { return "CCW16 keyframe " + std::to_string(k) + " (t = " + num(t) + ")"; }

// Gauss–Legendre nodes and weights on [−1, 1] (Newton on the three-term recurrence).
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
  x.assign(static_cast<size_t>(n), 0.0);
  w.assign(static_cast<size_t>(n), 0.0);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5));
    double dp = 1;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = 0;
      for (int j = 1; j <= n; ++j) {
        const double p2 = p1;
        p1 = p0;
        p0 = ((2.0 * j - 1.0) * z * p1 - (j - 1.0) * p2) / j;
      }
      dp = n * (z * p0 - p1) / (z * z - 1.0);
      const double step = p0 / dp;
      z -= step;
      if (std::abs(step) < 1e-16) break;
    }
    const auto lo = static_cast<size_t>(i), hi = static_cast<size_t>(n - 1 - i);
    x[lo] = -z;
    x[hi] = z;
    w[lo] = w[hi] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
}

// Signed crossings of the segment p → q with the ray ρ + λ d (λ > 0): +1 when it passes
// from the ray's right to its left (counter-clockwise around ρ). Points on the ray's line
// count as left, so the crossings of a closed polygon sum to its winding number around ρ.
int ray_crossing(cd rho, cd d, cd p, cd q) {
  const double cp = std::imag(std::conj(d) * (p - rho)), cq = std::imag(std::conj(d) * (q - rho));
  const bool lp = cp >= 0, lq = cq >= 0;
  if (lp == lq) return 0;
  const cd x = p + (q - p) * (cp / (cp - cq));
  if (std::real(std::conj(d) * (x - rho)) <= 0) return 0;
  return lq ? 1 : -1;
}

// One straight piece p → q split into pieces no longer than h, `nodes`-point Gauss rule on each.
void add_nodes(cd p, cd q, double h, const std::vector<double>& gx, const std::vector<double>& gw, std::vector<cd>& pts,
               std::vector<cd>& dz) {
  const double len = std::abs(q - p);
  if (len == 0) return;
  const int pieces = std::max(1, static_cast<int>(std::ceil(len / h)));
  const cd step = (q - p) / static_cast<double>(pieces);
  for (int j = 0; j < pieces; ++j) {
    const cd start = p + step * static_cast<double>(j);
    for (size_t g = 0; g < gx.size(); ++g) {
      pts.push_back(start + step * (0.5 * (gx[g] + 1.0)));
      dz.push_back(step * (0.5 * gw[g]));
    }
  }
}

// Frobenius norm of the symmetric metric [[m1, m2], [m2, m3]] stored as (m1, m2, m3).
double metric_norm(const Metric& m) { return std::sqrt(m(0) * m(0) + 2 * m(1) * m(1) + m(2) * m(2)); }

struct Distortions {
  double kappa = 1, iso = 2, nu = 0;
  void add(cd a, cd b) {
    const double s1 = std::abs(a) + std::abs(b), s2 = std::abs(a) - std::abs(b);
    nu = std::max(nu, std::abs(b) / std::abs(a));
    if (s2 <= 0) {
      kappa = iso = std::numeric_limits<double>::infinity();
      return;
    }
    kappa = std::max(kappa, s1 / s2);
    iso = std::max(iso, 0.5 * (s1 * s1 + 1 / (s1 * s1) + s2 * s2 + 1 / (s2 * s2)));
  }
};

}  // namespace

const char* to_string(Ccw16Variant v) {
  switch (v) {
    case Ccw16Variant::LogDerivatives: return "log-derivatives";
    case Ccw16Variant::BoundaryMetric: return "boundary-metric";
  }
  return "unknown";
}

Ccw16Interpolation::Ccw16Interpolation(const Shape& shape, const Cage& cage, std::vector<Ccw16Keyframe> keyframes,
                                       const Ccw16Options& options)
    : shape_(normalize(shape)), cage_(cage), keys_(std::move(keyframes)), options_(options) {
  const int K = static_cast<int>(keys_.size());
  if (K < 2) throw InputError("CCW16 needs at least two keyframes (got " + std::to_string(K) + ")");
  if (options_.samples < 8 * shape_.loop_count())
    throw InputError("CCW16: samples = " + std::to_string(options_.samples) + " is too few for " +
                     std::to_string(shape_.loop_count()) + " boundary loops");
  if (options_.quadrature < 1 || options_.quadrature > 64)
    throw InputError("CCW16: quadrature = " + std::to_string(options_.quadrature) + " nodes is outside [1, 64]");
  if (!(options_.max_piece > 0) || !std::isfinite(options_.max_piece))
    throw InputError("CCW16: max_piece must be positive (got " + num(options_.max_piece) + ")");
  validate(shape_);
  check_cage(shape_, cage_);
  size_ = bounding_box(shape_).diagonal();
  if (options_.variant == Ccw16Variant::BoundaryMetric && (cage_.hole_count() > 0 || !shape_.holes.empty()))
    throw InputError("CCW16 boundary-metric variant: the shape has " + std::to_string(shape_.holes.size()) +
                     " hole(s); CCW16's Hilbert transform (the harmonic conjugate of log|f_z| from the boundary) does "
                     "not apply to multiply-connected domains (use the log-derivatives variant to see it tear)");

  const int full = basis_size(cage_), m = cage_.vertex_count();
  for (int k = 0; k < K; ++k) {
    const Ccw16Keyframe& key = keys_[static_cast<size_t>(k)];
    if (!std::isfinite(key.time)) throw InputError(key_name(k, key.time) + ": time is not finite");
    if (k > 0 && !(key.time > keys_[static_cast<size_t>(k - 1)].time))
      throw InputError(key_name(k, key.time) + ": times must increase (the previous keyframe is at t = " +
                       num(keys_[static_cast<size_t>(k - 1)].time) + ")");
    if (key.map.phi.size() != full || key.map.psi.size() != full)
      throw InputError(key_name(k, key.time) + ": has " + std::to_string(key.map.phi.size()) + " φ and " +
                       std::to_string(key.map.psi.size()) + " ψ coefficients; the cage needs " + std::to_string(full));
    if (!key.map.phi.allFinite() || !key.map.psi.allFinite())
      throw InputError(key_name(k, key.time) + ": coefficients are not finite");
    // ψ_log = conj φ_log makes the keyframe's own period 2πi (φ_log − conj ψ_log) vanish.
    const double scale = std::max(1.0, key.map.phi.cwiseAbs().maxCoeff());
    for (int i = 0; i < cage_.hole_count(); ++i)
      if (std::abs(key.map.psi(m + i) - std::conj(key.map.phi(m + i))) > 1e-9 * scale)
        throw InputError(key_name(k, key.time) + ": ψ_log ≠ conj φ_log on hole " + std::to_string(i + 1) +
                         ": not a single-valued harmonic map");
  }
  phi_.resize(full, K);
  psi_.resize(full, K);
  for (int k = 0; k < K; ++k) {
    phi_.col(k) = keys_[static_cast<size_t>(k)].map.phi;
    psi_.col(k) = keys_[static_cast<size_t>(k)].map.psi;
  }

  // Local injectivity at the samples: f_z ≠ 0, |ν| < 1, and no zero of f_z inside Ω.
  const BoundarySamples G = sample_boundary(shape_, options_.samples);
  Eigen::MatrixXcd a, b;
  evaluate(G.points, a, b);
  const auto S = static_cast<Eigen::Index>(G.size());
  key_max_nu_.assign(static_cast<size_t>(K), 0.0);
  for (int k = 0; k < K; ++k) {
    const std::string name = key_name(k, keys_[static_cast<size_t>(k)].time);
    for (Eigen::Index i = 0; i < S; ++i) {
      const cd ai = a(i, k), bi = b(i, k);
      const auto si = static_cast<size_t>(i);
      if (!std::isfinite(std::abs(ai)) || !std::isfinite(std::abs(bi)) || std::abs(ai) == 0)
        throw InputError(name + ": f_z vanishes at boundary sample " + std::to_string(i) + " " + point(G.points[si]) +
                         " on the " + loop_name(G.loop[si]) + ": the map is not locally injective");
      const double nu = std::abs(bi) / std::abs(ai);
      if (!(nu < 1))
        throw InputError(name + ": |ν| = |f_zbar|/|f_z| = " + num(nu) + " ≥ 1 at boundary sample " + std::to_string(i) + " " +
                         point(G.points[si]) + " on the " + loop_name(G.loop[si]) + ": the map folds there");
      key_max_nu_[static_cast<size_t>(k)] = std::max(key_max_nu_[static_cast<size_t>(k)], nu);
    }
    // Argument principle (paper Theorem 2): Σ over loops of the change of arg f_z / 2π
    // (outer counter-clockwise, holes clockwise) counts the zeros of f_z inside Ω.
    double turns = 0;
    for (int l = 0; l < shape_.loop_count(); ++l) {
      const int b0 = G.loop_begin[static_cast<size_t>(l)], b1 = G.loop_begin[static_cast<size_t>(l + 1)];
      for (int i = b0; i < b1; ++i) {
        const int j = i + 1 < b1 ? i + 1 : b0;
        const double step = std::arg(a(j, k) / a(i, k));
        if (std::abs(step) > kPi / 2)
          throw InputError(name + ": arg f_z turns by " + num(step) + " rad between boundary samples near " +
                           point(G.points[static_cast<size_t>(i)]) + "; raise the sample count");
        turns += step;
      }
    }
    const long zeros = std::lround(turns / (2 * kPi));
    if (zeros != 0)
      throw InputError(name + ": f_z has " + std::to_string(zeros) +
                       " zero(s) inside the shape (argument principle): the map is not locally injective");
  }
  // λ_k = log(a_{k+1}/a_k) is single-valued only if the ratio does not wind around a hole.
  for (int k = 0; k + 1 < K; ++k)
    for (int l = 1; l < shape_.loop_count(); ++l) {
      const int b0 = G.loop_begin[static_cast<size_t>(l)], b1 = G.loop_begin[static_cast<size_t>(l + 1)];
      double turns = 0;
      for (int i = b0; i < b1; ++i) {
        const int j = i + 1 < b1 ? i + 1 : b0;
        turns += std::arg((a(j, k + 1) / a(j, k)) / (a(i, k + 1) / a(i, k)));
      }
      const long n = std::lround(turns / (2 * kPi));
      if (n != 0)
        throw InputError("CCW16 keyframes " + std::to_string(k) + " and " + std::to_string(k + 1) + ": f_z winds " +
                         std::to_string(n) + " more time(s) around " + loop_name(l) +
                         " in one than in the other: they are not in one homotopy class, log f_z cannot be blended");
    }

  // The anchor, its images and λ_k's branch there: continued from the anchor along the
  // outer samples, the mean of Im λ_k (the relative rotation) is brought into (−π, π].
  anchor_ = shape_.outer.front();
  Eigen::MatrixXcd aa, ba;
  const std::vector<cd> anchor_pt{anchor_};
  evaluate(anchor_pt, aa, ba);
  const VectorXcd C0 = evaluate_basis(cage_, anchor_pt, kBasisC).C.row(0).transpose();
  for (int k = 0; k < K; ++k)  // f = Σ C_j φ_j + conj(Σ C_j ψ_j) (paper Eq. 2)
    f_anchor_.push_back((C0.transpose() * phi_.col(k)).value() + std::conj((C0.transpose() * psi_.col(k)).value()));
  for (int k = 0; k + 1 < K; ++k) {
    const cd r0 = aa(0, k + 1) / aa(0, k);
    cd lam = std::log(r0), r_prev = r0;
    double sum = 0;
    const int b1 = G.loop_begin[1];
    for (int i = 0; i < b1; ++i) {
      const cd r = a(i, k + 1) / a(i, k);
      lam += std::log(r / r_prev);
      r_prev = r;
      sum += lam.imag();
    }
    const double mean = sum / b1;
    const double turn = -std::round(mean / (2 * kPi));
    lambda_anchor_.push_back(std::log(r0) + cd(0, 2 * kPi * turn));
    lambda_mean_arg_.push_back(mean + 2 * kPi * turn);
  }
  if (options_.variant == Ccw16Variant::BoundaryMetric) prepare_boundary_fit(G, a, b);
}

void Ccw16Interpolation::prepare_boundary_fit(const BoundarySamples& G, const Eigen::MatrixXcd& a, const Eigen::MatrixXcd& b) {
  const int K = static_cast<int>(keys_.size());
  const auto S = static_cast<Eigen::Index>(G.size());
  // The keyframes' metrics at G (paper Eq. 5), and the mean of arg a_k along ∂Ω (unwrapped
  // from the principal value at sample 0: a_k has no zero in Ω, so arg a_k is continuous on
  // the outer loop, the only loop here).
  key_metrics_.assign(static_cast<size_t>(K), std::vector<Metric>(static_cast<size_t>(S)));
  key_mean_arg_.assign(static_cast<size_t>(K), 0.0);
  for (int k = 0; k < K; ++k) {
    double arg = std::arg(a(0, k)), sum = 0;
    for (Eigen::Index i = 0; i < S; ++i) {
      key_metrics_[static_cast<size_t>(k)][static_cast<size_t>(i)] = pullback_metric(a(i, k), b(i, k));
      if (i > 0) arg += std::arg(a(i, k) / a(i - 1, k));
      sum += arg;
    }
    key_mean_arg_[static_cast<size_t>(k)] = sum / static_cast<double>(S);
  }

  const BasisRows rows = evaluate_basis(cage_, G.points, kBasisC | kBasisD);
  C_G_ = rows.C;
  D_G_ = rows.D;
  const Eigen::Index m = C_G_.cols();
  // Re L at G is linear in (Re l, Im l): Re(C l) = Re C · Re l − Im C · Im l. Its one null
  // direction is l = i·1 (an imaginary constant); the last row, mean_G Im(C l), weighted
  // like the |G| rows together, pins it without touching the fit of Re L.
  Eigen::MatrixXd X(S + 1, 2 * m);
  X.topLeftCorner(S, m) = C_G_.real();
  X.topRightCorner(S, m) = -C_G_.imag();
  const double w = std::sqrt(static_cast<double>(S));
  X.row(S).head(m) = w * C_G_.imag().colwise().mean();
  X.row(S).tail(m) = w * C_G_.real().colwise().mean();
  fit_L_.compute(X);
  fit_b_.compute(D_G_.rightCols(m - 1));
  if (fit_L_.rank() < 2 * m || fit_b_.rank() < m - 1)
    throw InputError("CCW16 boundary-metric variant: the least-squares Hilbert transform is rank deficient (rank " +
                     std::to_string(fit_L_.rank()) + " of " + std::to_string(2 * m) + ", " + std::to_string(fit_b_.rank()) +
                     " of " + std::to_string(m - 1) + "); raise the sample count");
}

Ccw16Interpolation::BoundaryFit Ccw16Interpolation::fit_boundary(int k, double s) const {
  const auto S = C_G_.rows(), m = C_G_.cols();
  const auto& M0 = key_metrics_[static_cast<size_t>(k)];
  const auto& M1 = key_metrics_[static_cast<size_t>(k) + 1];
  std::vector<Metric> Mt(static_cast<size_t>(S));
  std::vector<cd> A(static_cast<size_t>(S));
  std::vector<double> mod_a(static_cast<size_t>(S)), mod_b(static_cast<size_t>(S));
  Eigen::VectorXd rhs(S + 1);
  for (Eigen::Index i = 0; i < S; ++i) {
    const auto u = static_cast<size_t>(i);
    const Metric M = (1 - s) * M0[u] + s * M1[u];  // M_g = (1 − t) M⁰ + t M¹ (paper §4.1), as Interpolator::blended_metric
    // Eq. 5 inverted: S = |a|² + |b|², A = ab, eigenvalues σ1,2² = S ± 2|A|.
    const double Sm = 0.5 * (M(0) + M(2));
    const cd Ai(0.25 * (M(0) - M(2)), -0.5 * M(1));
    const double r = std::abs(Ai);
    const double s1 = std::sqrt(Sm + 2 * r), s2 = std::sqrt(std::max(0.0, Sm - 2 * r));
    Mt[u] = M;
    A[u] = Ai;
    mod_a[u] = 0.5 * (s1 + s2);
    mod_b[u] = 0.5 * (s1 - s2);
    rhs(i) = std::log(mod_a[u]);
  }
  // The rotation: the mean of Im L over G as the log blend has it (ccw16.h, step 3).
  rhs(S) = std::sqrt(static_cast<double>(S)) *
           (key_mean_arg_[static_cast<size_t>(k)] + s * lambda_mean_arg_[static_cast<size_t>(k)]);
  const Eigen::VectorXd x = fit_L_.solve(rhs);
  BoundaryFit fit;
  fit.l = x.head(m).cast<cd>() + cd(0, 1) * x.tail(m).cast<cd>();
  const VectorXcd L = C_G_ * fit.l;

  // Ψ' = A / f_z in phase, |b| from the metric in modulus; then holomorphic by least squares.
  VectorXcd bG(S);
  for (Eigen::Index i = 0; i < S; ++i) {
    const auto u = static_cast<size_t>(i);
    const double r = std::abs(A[u]);
    bG(i) = r > 0 ? mod_b[u] * (A[u] / r) * std::polar(1.0, -L(i).imag()) : cd(0);
  }
  fit.beta = VectorXcd::Zero(m);
  fit.beta.tail(m - 1) = fit_b_.solve(bG);
  const VectorXcd bfit = D_G_ * fit.beta;

  for (Eigen::Index i = 0; i < S; ++i) {
    const auto u = static_cast<size_t>(i);
    fit.log_modulus = std::max(fit.log_modulus, std::abs(L(i).real() - rhs(i)));
    fit.fzbar = std::max(fit.fzbar, std::abs(bfit(i) - bG(i)) / mod_a[u]);
    fit.metric = std::max(fit.metric, metric_norm(pullback_metric(std::exp(L(i)), bfit(i)) - Mt[u]) / metric_norm(Mt[u]));
  }
  return fit;
}

double Ccw16Interpolation::blend_parameter(int k, double t) const {
  const double t0 = keys_[static_cast<size_t>(k)].time, t1 = keys_[static_cast<size_t>(k + 1)].time;
  return std::clamp((t - t0) / (t1 - t0), 0.0, 1.0);
}

void Ccw16Interpolation::evaluate(std::span<const cd> points, Eigen::MatrixXcd& a, Eigen::MatrixXcd& b) const {
  const auto P = static_cast<Eigen::Index>(points.size());
  a.resize(P, phi_.cols());
  b.resize(P, phi_.cols());
  constexpr Eigen::Index chunk = 4096;  // bounds the basis rows held at once
  for (Eigen::Index c0 = 0; c0 < P; c0 += chunk) {
    const Eigen::Index n = std::min(chunk, P - c0);
    const BasisRows rows = evaluate_basis(cage_, points.subspan(static_cast<size_t>(c0), static_cast<size_t>(n)), kBasisD);
    a.middleRows(c0, n) = rows.D * phi_;
    b.middleRows(c0, n) = rows.D * psi_;
  }
}

int Ccw16Interpolation::segment(double t) const {
  const double lo = t_begin(), hi = t_end();
  const double eps = 1e-12 * (hi - lo);
  if (!std::isfinite(t) || t < lo - eps || t > hi + eps)
    throw InputError("CCW16: t = " + num(t) + " is outside the keyframes' range [" + num(lo) + ", " + num(hi) + "]");
  int k = 0;
  while (k + 2 < static_cast<int>(keys_.size()) && t >= keys_[static_cast<size_t>(k + 1)].time) ++k;
  return k;
}

std::vector<std::array<int, 2>> Ccw16Mesh::non_tree_edges() const {
  std::vector<std::array<int, 2>> out;
  for (const Edge& e : edges_)
    if (!e.tree) out.push_back({std::min(e.from, e.to), std::max(e.from, e.to)});
  return out;
}

Ccw16Mesh Ccw16Interpolation::prepare(const TriMesh& mesh) const {
  const int V = mesh.vertex_count(), N = cage_.hole_count();
  if (V == 0) throw InputError("CCW16: the mesh has no vertices");
  for (int v = 0; v < V; ++v)
    if (!std::isfinite(mesh.vertices[static_cast<size_t>(v)].real()) || !std::isfinite(mesh.vertices[static_cast<size_t>(v)].imag()))
      throw InputError("CCW16: mesh vertex " + std::to_string(v) + " is not finite");
  if (N > 0 && (mesh.boundary_loop.size() != static_cast<size_t>(V) || mesh.boundary_edges.empty()))
    throw InputError("CCW16: the mesh has no boundary loops; the hole periods need them (use hsi::triangulate)");

  Ccw16Mesh M;
  M.vertices_ = mesh.vertices;
  M.base_ = 0;
  for (int v = 1; v < V; ++v)
    if (std::abs(mesh.vertices[static_cast<size_t>(v)] - anchor_) < std::abs(mesh.vertices[static_cast<size_t>(M.base_)] - anchor_))
      M.base_ = v;
  const cd base = mesh.vertices[static_cast<size_t>(M.base_)];

  // Unique edges and adjacency.
  std::unordered_map<std::uint64_t, int> edge_of;
  std::vector<std::vector<std::pair<int, int>>> adj(static_cast<size_t>(V));
  auto key = [](int u, int v) { return (static_cast<std::uint64_t>(std::min(u, v)) << 32) | static_cast<std::uint32_t>(std::max(u, v)); };
  for (size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int u = mesh.triangles[f][static_cast<size_t>(c)], v = mesh.triangles[f][static_cast<size_t>((c + 1) % 3)];
      if (u < 0 || u >= V || v < 0 || v >= V || u == v)
        throw InputError("CCW16: mesh triangle " + std::to_string(f) + " has a bad vertex index");
      if (edge_of.emplace(key(u, v), static_cast<int>(M.edges_.size())).second) {
        const int e = static_cast<int>(M.edges_.size());
        M.edges_.push_back({std::min(u, v), std::max(u, v), false, 0, 0});
        adj[static_cast<size_t>(u)].push_back({v, e});
        adj[static_cast<size_t>(v)].push_back({u, e});
      }
    }

  // Cut rays from each hole point away from the base vertex; the tree avoids them first.
  std::vector<cd> dir;
  for (const cd& rho : cage_.hole_points) dir.push_back((rho - base) / std::abs(rho - base));
  auto crossings = [&](int u, int v, int i) {
    return ray_crossing(cage_.hole_points[static_cast<size_t>(i)], dir[static_cast<size_t>(i)],
                        mesh.vertices[static_cast<size_t>(u)], mesh.vertices[static_cast<size_t>(v)]);
  };
  auto crosses_any = [&](int u, int v) {
    for (int i = 0; i < N; ++i)
      if (crossings(u, v, i) != 0) return true;
    return false;
  };
  M.parent_.assign(static_cast<size_t>(V), -1);
  M.parent_edge_.assign(static_cast<size_t>(V), -1);
  std::vector<char> seen(static_cast<size_t>(V), 0);
  seen[static_cast<size_t>(M.base_)] = 1;
  M.order_ = {M.base_};
  for (int pass = 0; pass < 2 && static_cast<int>(M.order_.size()) < V; ++pass) {
    std::deque<int> queue(M.order_.begin(), M.order_.end());
    while (!queue.empty()) {
      const int u = queue.front();
      queue.pop_front();
      for (const auto& [v, e] : adj[static_cast<size_t>(u)]) {
        if (seen[static_cast<size_t>(v)] || (pass == 0 && crosses_any(u, v))) continue;
        seen[static_cast<size_t>(v)] = 1;
        M.parent_[static_cast<size_t>(v)] = u;
        M.parent_edge_[static_cast<size_t>(v)] = e;
        M.edges_[static_cast<size_t>(e)].from = u;
        M.edges_[static_cast<size_t>(e)].to = v;
        M.edges_[static_cast<size_t>(e)].tree = true;
        M.order_.push_back(v);
        queue.push_back(v);
      }
    }
  }
  if (static_cast<int>(M.order_.size()) < V)
    for (int v = 0; v < V; ++v)
      if (!seen[static_cast<size_t>(v)])
        throw InputError("CCW16: mesh vertex " + std::to_string(v) + " is not connected to the base vertex " +
                         std::to_string(M.base_));

  // How often each vertex's tree path crosses each cut, then each non-tree edge's loop winding.
  std::vector<int> cut_count(static_cast<size_t>(V) * static_cast<size_t>(N), 0);
  for (size_t o = 1; o < M.order_.size(); ++o) {
    const int v = M.order_[o], p = M.parent_[static_cast<size_t>(v)];
    for (int i = 0; i < N; ++i)
      cut_count[static_cast<size_t>(v * N + i)] = cut_count[static_cast<size_t>(p * N + i)] + crossings(p, v, i);
  }
  for (const Ccw16Mesh::Edge& e : M.edges_)
    if (!e.tree)
      for (int i = 0; i < N; ++i)
        M.winding_.push_back(cut_count[static_cast<size_t>(e.from * N + i)] + crossings(e.from, e.to, i) -
                             cut_count[static_cast<size_t>(e.to * N + i)]);

  // Hole boundaries, oriented counter-clockwise around their hole point.
  M.hole_edges_.assign(static_cast<size_t>(N), {});
  std::vector<double> turning(static_cast<size_t>(N), 0.0);
  for (const auto& [u, v] : mesh.boundary_edges) {
    if (u < 0 || u >= V || v < 0 || v >= V) throw InputError("CCW16: a mesh boundary edge has a bad vertex index");
    const int loop = mesh.boundary_loop[static_cast<size_t>(u)];
    if (loop < 1 || loop > N) continue;
    const auto it = edge_of.find(key(u, v));
    if (it == edge_of.end()) throw InputError("CCW16: mesh boundary edge (" + std::to_string(u) + ", " + std::to_string(v) + ") is no triangle's edge");
    const Ccw16Mesh::Edge& e = M.edges_[static_cast<size_t>(it->second)];
    M.hole_edges_[static_cast<size_t>(loop - 1)].push_back({it->second, e.from == u ? 1 : -1});
    const cd rho = cage_.hole_points[static_cast<size_t>(loop - 1)];
    turning[static_cast<size_t>(loop - 1)] +=
        std::arg((mesh.vertices[static_cast<size_t>(v)] - rho) / (mesh.vertices[static_cast<size_t>(u)] - rho));
  }
  for (int i = 0; i < N; ++i) {
    const long w = std::lround(turning[static_cast<size_t>(i)] / (2 * kPi));
    if (w != 1 && w != -1)
      throw InputError("CCW16: the mesh's boundary edges on " + loop_name(i + 1) + " do not go once around it");
    if (w == -1)
      for (auto& [e, sign] : M.hole_edges_[static_cast<size_t>(i)]) sign = -sign;
  }

  // Gauss nodes: on every edge (from → to), then on the piece anchor → base vertex.
  std::vector<double> gx, gw;
  gauss_legendre(options_.quadrature, gx, gw);
  const double h = options_.max_piece * size_;
  std::vector<cd> nodes;
  for (Ccw16Mesh::Edge& e : M.edges_) {
    e.node_begin = static_cast<int>(nodes.size());
    add_nodes(mesh.vertices[static_cast<size_t>(e.from)], mesh.vertices[static_cast<size_t>(e.to)], h, gx, gw, nodes, M.node_dz_);
    e.node_end = static_cast<int>(nodes.size());
  }
  M.anchor_begin_ = static_cast<int>(nodes.size());
  add_nodes(anchor_, base, h, gx, gw, nodes, M.node_dz_);
  M.anchor_end_ = static_cast<int>(nodes.size());

  // Derivatives at vertices, nodes and the anchor (the last point).
  std::vector<cd> pts = mesh.vertices;
  pts.insert(pts.end(), nodes.begin(), nodes.end());
  pts.push_back(anchor_);
  if (options_.variant == Ccw16Variant::BoundaryMetric) {
    // The frame's a(t), b(t) come from fitted coefficients: keep the basis rows.
    const auto np = static_cast<Eigen::Index>(pts.size()), m = static_cast<Eigen::Index>(phi_.rows());
    M.C_.resize(np, m);
    M.D_.resize(np, m);
    constexpr Eigen::Index chunk = 4096;
    for (Eigen::Index c0 = 0; c0 < np; c0 += chunk) {
      const Eigen::Index n = std::min(chunk, np - c0);
      const BasisRows rows =
          evaluate_basis(cage_, std::span<const cd>(pts).subspan(static_cast<size_t>(c0), static_cast<size_t>(n)), kBasisC | kBasisD);
      M.C_.middleRows(c0, n) = rows.C;
      M.D_.middleRows(c0, n) = rows.D;
    }
    M.a_ = M.D_ * phi_;
    M.b_ = M.D_ * psi_;
  } else {
    evaluate(pts, M.a_, M.b_);
  }
  const int K = static_cast<int>(keys_.size());
  const auto P = static_cast<Eigen::Index>(pts.size());
  const Eigen::Index anchor_point = P - 1;

  // λ_k continued from the anchor: to the base vertex, down the tree, and onto the nodes of
  // every non-tree edge from its first vertex.
  M.lambda_.resize(P, K - 1);
  for (int k = 0; k + 1 < K; ++k) {
    auto ratio = [&](Eigen::Index p) { return M.a_(p, k + 1) / M.a_(p, k); };
    auto step = [&](Eigen::Index from, Eigen::Index to) { M.lambda_(to, k) = M.lambda_(from, k) + std::log(ratio(to) / ratio(from)); };
    auto walk = [&](Eigen::Index from, int n0, int n1, Eigen::Index to) {
      Eigen::Index prev = from;
      for (int n = n0; n < n1; ++n) {
        step(prev, V + n);
        prev = V + n;
      }
      if (to >= 0) step(prev, to);
    };
    M.lambda_(anchor_point, k) = lambda_anchor_[static_cast<size_t>(k)];
    walk(anchor_point, M.anchor_begin_, M.anchor_end_, M.base_);
    for (size_t o = 1; o < M.order_.size(); ++o) {
      const int v = M.order_[o];
      const Ccw16Mesh::Edge& e = M.edges_[static_cast<size_t>(M.parent_edge_[static_cast<size_t>(v)])];
      walk(e.from, e.node_begin, e.node_end, v);
    }
    for (const Ccw16Mesh::Edge& e : M.edges_)
      if (!e.tree) walk(e.from, e.node_begin, e.node_end, -1);
  }
  return M;
}

Ccw16Frame Ccw16Interpolation::frame(double t, const TriMesh& mesh) const { return frame(t, prepare(mesh)); }

Ccw16Frame Ccw16Interpolation::frame(double t, const Ccw16Mesh& M) const {
  const int k = segment(t);
  const double s = blend_parameter(k, t);
  const int V = M.vertex_count(), N = cage_.hole_count();
  const auto P = M.a_.rows();
  const bool boundary_metric = options_.variant == Ccw16Variant::BoundaryMetric;
  if (M.lambda_.cols() != static_cast<Eigen::Index>(keys_.size()) - 1 || P == 0 || M.a_.cols() != phi_.cols() ||
      (boundary_metric && M.C_.rows() != P))
    throw InputError("CCW16: the mesh was prepared by another interpolation");

  Ccw16Frame F;
  F.t = t;
  std::vector<cd> A(static_cast<size_t>(P)), B(static_cast<size_t>(P));
  if (boundary_metric) {
    // a(t) = exp(Σ C_j l_j), b(t) = Σ D_j β_j, fitted to the blended boundary metric.
    const BoundaryFit fit = fit_boundary(k, s);
    const VectorXcd L = M.C_ * fit.l, b = M.D_ * fit.beta;
    for (Eigen::Index p = 0; p < P; ++p) {
      A[static_cast<size_t>(p)] = std::exp(L(p));
      B[static_cast<size_t>(p)] = b(p);
    }
    F.fit_log_modulus = fit.log_modulus;
    F.fit_fzbar = fit.fzbar;
    F.fit_metric = fit.metric;
  } else {
    // a(t) = a_k exp(s λ_k), b(t) = ((1 − s) ν_k + s ν_{k+1}) a(t), pointwise.
    for (Eigen::Index p = 0; p < P; ++p) {
      const cd a = M.a_(p, k) * std::exp(s * M.lambda_(p, k));
      const cd nu = (1 - s) * (M.b_(p, k) / M.a_(p, k)) + s * (M.b_(p, k + 1) / M.a_(p, k + 1));
      A[static_cast<size_t>(p)] = a;
      B[static_cast<size_t>(p)] = nu * a;
    }
  }
  auto integral = [&](int n0, int n1) {
    cd ia = 0, ib = 0;
    for (int n = n0; n < n1; ++n) {
      ia += A[static_cast<size_t>(V + n)] * M.node_dz_[static_cast<size_t>(n)];
      ib += B[static_cast<size_t>(V + n)] * M.node_dz_[static_cast<size_t>(n)];
    }
    return ia + std::conj(ib);  // ∫ a dz + conj(b dz)
  };
  std::vector<cd> I(M.edges_.size());
  for (size_t e = 0; e < M.edges_.size(); ++e) I[e] = integral(M.edges_[e].node_begin, M.edges_[e].node_end);

  F.positions.assign(static_cast<size_t>(V), cd{});
  const cd f_anchor = (1 - s) * f_anchor_[static_cast<size_t>(k)] + s * f_anchor_[static_cast<size_t>(k + 1)];
  F.positions[static_cast<size_t>(M.base_)] = f_anchor + integral(M.anchor_begin_, M.anchor_end_);
  for (size_t o = 1; o < M.order_.size(); ++o) {
    const int v = M.order_[o];
    const int e = M.parent_edge_[static_cast<size_t>(v)];
    F.positions[static_cast<size_t>(v)] = F.positions[static_cast<size_t>(M.parent_[static_cast<size_t>(v)])] + I[static_cast<size_t>(e)];
  }

  for (int i = 0; i < N; ++i) {
    cd period = 0;
    for (const auto& [e, sign] : M.hole_edges_[static_cast<size_t>(i)]) period += static_cast<double>(sign) * I[static_cast<size_t>(e)];
    F.periods.push_back(period);
    F.hole_period.push_back(std::abs(period));
  }
  F.seam_jump.assign(static_cast<size_t>(N), 0.0);
  size_t nt = 0;
  for (size_t e = 0; e < M.edges_.size(); ++e) {
    const Ccw16Mesh::Edge& E = M.edges_[e];
    if (E.tree) continue;
    // Around the loop tree(base → from) + edge + tree(to → base): Σ_i n_i P_i.
    const cd mismatch = F.positions[static_cast<size_t>(E.from)] + I[e] - F.positions[static_cast<size_t>(E.to)];
    cd expected = 0;
    int holes_wound = 0, hole = -1;
    for (int i = 0; i < N; ++i) {
      const int n = M.winding_[nt * static_cast<size_t>(N) + static_cast<size_t>(i)];
      expected += static_cast<double>(n) * F.periods[static_cast<size_t>(i)];
      if (n != 0) {
        ++holes_wound;
        hole = (n == 1 || n == -1) ? i : -1;
      }
    }
    ++nt;
    F.closure_error = std::max(F.closure_error, std::abs(mismatch - expected));
    if (holes_wound == 1 && hole >= 0) F.seam_jump[static_cast<size_t>(hole)] = std::max(F.seam_jump[static_cast<size_t>(hole)], std::abs(mismatch));
  }

  Distortions d;
  for (int v = 0; v < V; ++v) {
    F.fz.push_back(A[static_cast<size_t>(v)]);
    F.fzbar.push_back(std::conj(B[static_cast<size_t>(v)]));
    d.add(A[static_cast<size_t>(v)], B[static_cast<size_t>(v)]);
  }
  F.max_kappa = d.kappa;
  F.max_isometric = d.iso;
  F.max_nu = d.nu;
  return F;
}

Ccw16Frame Ccw16Interpolation::integrate_path(double t, std::span<const cd> path) const {
  const int k = segment(t);
  const double s = blend_parameter(k, t);
  for (size_t i = 0; i < path.size(); ++i)
    if (!std::isfinite(path[i].real()) || !std::isfinite(path[i].imag()))
      throw InputError("CCW16: path point " + std::to_string(i) + " is not finite");

  // The polyline's points in order, the anchor first: nodes (dz ≠ 0) and path points (dz = 0).
  std::vector<double> gx, gw;
  gauss_legendre(options_.quadrature, gx, gw);
  std::vector<cd> pts{anchor_}, dz{0.0};
  std::vector<size_t> at;  // index of each path point in pts
  cd prev = anchor_;
  for (const cd& p : path) {
    add_nodes(prev, p, options_.max_piece * size_, gx, gw, pts, dz);
    at.push_back(pts.size());
    pts.push_back(p);
    dz.push_back(0.0);
    prev = p;
  }
  Ccw16Frame F;
  F.t = t;
  Eigen::MatrixXcd a, b;
  VectorXcd L_fit, b_fit;
  const bool boundary_metric = options_.variant == Ccw16Variant::BoundaryMetric;
  if (boundary_metric) {
    const BoundaryFit fit = fit_boundary(k, s);
    const BasisRows rows = evaluate_basis(cage_, pts, kBasisC | kBasisD);
    L_fit = rows.C * fit.l;
    b_fit = rows.D * fit.beta;
    F.fit_log_modulus = fit.log_modulus;
    F.fit_fzbar = fit.fzbar;
    F.fit_metric = fit.metric;
  } else {
    evaluate(pts, a, b);
  }

  cd pos = (1 - s) * f_anchor_[static_cast<size_t>(k)] + s * f_anchor_[static_cast<size_t>(k + 1)];
  cd lam = lambda_anchor_[static_cast<size_t>(k)];
  Distortions d;
  size_t next = 0;
  for (size_t p = 0; p < pts.size(); ++p) {
    const auto i = static_cast<Eigen::Index>(p);
    cd A, B;
    if (boundary_metric) {
      A = std::exp(L_fit(i));
      B = b_fit(i);
    } else {
      if (p > 0) lam += std::log((a(i, k + 1) / a(i, k)) / (a(i - 1, k + 1) / a(i - 1, k)));
      A = a(i, k) * std::exp(s * lam);
      B = ((1 - s) * (b(i, k) / a(i, k)) + s * (b(i, k + 1) / a(i, k + 1))) * A;
    }
    pos += A * dz[p] + std::conj(B * dz[p]);
    if (next < at.size() && at[next] == p) {
      F.positions.push_back(pos);
      F.fz.push_back(A);
      F.fzbar.push_back(std::conj(B));
      d.add(A, B);
      ++next;
    }
  }
  F.max_kappa = d.kappa;
  F.max_isometric = d.iso;
  F.max_nu = d.nu;
  return F;
}

}  // namespace hsi::baselines
