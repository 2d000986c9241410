// Local injectivity certificate: Lipschitz bounds on boundary segments with adaptive
// subdivision, and the argument principle for f_z (math.md §6).
#include "hsi/certificate.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "row_parallel.h"

namespace hsi {

CertificateSegments certificate_segments(const Shape& shape, const BoundarySamples& s) {
  CertificateSegments g;
  for (int l = 0; l < shape.loop_count(); ++l) {
    const Loop& L = shape.loop(l);
    const int first = static_cast<int>(g.points.size());
    size_t k = static_cast<size_t>(s.loop_begin[static_cast<size_t>(l)]);
    const size_t end = static_cast<size_t>(s.loop_begin[static_cast<size_t>(l) + 1]);
    for (int e = 0; e < static_cast<int>(L.size()); ++e) {
      g.points.push_back(L[static_cast<size_t>(e)]);
      g.edge.push_back(e);
      for (; k < end && s.edge[k] == e; ++k) {
        if (std::abs(s.points[k] - g.points.back()) < 1e-14 * std::abs(g.points.back()) + 1e-300) continue;
        g.points.push_back(s.points[k]);
        g.edge.push_back(e);
      }
    }
    const int count = static_cast<int>(g.points.size()) - first;
    for (int i = 0; i < count; ++i) {
      g.next.push_back(first + (i + 1) % count);
      g.loop.push_back(l);
    }
  }
  return g;
}

Eigen::VectorXd certificate_jumps(const Cage& cage, const VectorXcd& c, Eigen::VectorXd* rounding) {
  const int m = cage.vertex_count();
  Eigen::VectorXd out(m);
  if (rounding) rounding->resize(m);
  // δ_j carries a relative error of a few ulps (one complex difference and one
  // complex division); their difference adds one more rounding.
  constexpr double u = std::numeric_limits<double>::epsilon() / 2;
  int off = 0;
  for (const Loop& z : cage.loops) {
    const size_t k = z.size();
    auto delta = [&](size_t j) {  // slope on the edge ending at vertex j
      const size_t jm = (j + k - 1) % k;
      return (c(off + static_cast<Eigen::Index>(j)) - c(off + static_cast<Eigen::Index>(jm))) / (z[j] - z[jm]);
    };
    for (size_t j = 0; j < k; ++j) {
      const cd d0 = delta(j), d1 = delta((j + 1) % k);
      const Eigen::Index i = off + static_cast<Eigen::Index>(j);
      out(i) = std::abs(d1 - d0);
      if (rounding) (*rounding)(i) = 16 * u * (std::abs(d0) + std::abs(d1)) + 4 * u * out(i);
    }
    off += static_cast<int>(k);
  }
  return out;
}

namespace {

constexpr double kU = kCertificateRoundoff;

}  // namespace

double distance_lower(cd z, cd p, cd q) {
  return segment_distance(z, p, q) - 16 * kU * (std::abs(z) + std::abs(p) + std::abs(q));
}

CertificateWeights certificate_weights(const Cage& cage, const CertificateSegments& seg) {
  const int m = cage.vertex_count(), N = cage.hole_count();
  const Eigen::Index S = static_cast<Eigen::Index>(seg.size());
  CertificateWeights g;
  g.W.resize(S, m);
  g.Wh.resize(S, N);
  g.WD.resize(S, m + N);
  g.WE.resize(S, m + N);
  g.touches.assign(static_cast<size_t>(S), 0);
  std::vector<cd> z;
  for (const Loop& l : cage.loops) z.insert(z.end(), l.begin(), l.end());
  const double inv2pi = 1 / (2 * std::numbers::pi);
#pragma omp parallel for schedule(static)
  for (Eigen::Index i = 0; i < S; ++i) {
    const cd p = seg.points[static_cast<size_t>(i)], q = seg.points[static_cast<size_t>(seg.next[static_cast<size_t>(i)])];
    for (int j = 0; j < m; ++j) {
      const double d = distance_lower(z[static_cast<size_t>(j)], p, q);
      g.W(i, j) = d > 0 ? 1 / (d * d) : 0;
      if (!(d > 0)) g.touches[static_cast<size_t>(i)] = 1;
    }
    for (int h = 0; h < N; ++h) {
      const double d = distance_lower(cage.hole_points[static_cast<size_t>(h)], p, q);
      g.Wh(i, h) = d > 0 ? 1 / (d * d * d) : 0;
      if (!(d > 0)) g.touches[static_cast<size_t>(i)] = 1;
    }
    // Per edge j → j+1 of each loop, once: |log(B_{j+1}/B_j)| and |B_j| (each vertex's two
    // edges share them; a log per edge rather than two per vertex).
    std::vector<double> edge_log, dist;
    int col = 0;
    for (const Loop& loop : cage.loops) {
      const size_t k = loop.size();
      edge_log.resize(k);
      dist.resize(k);
      for (size_t j = 0; j < k; ++j) {
        const size_t jp = (j + 1) % k;
        edge_log[j] = std::abs(std::log((loop[jp] - p) / (loop[j] - p)));
        dist[j] = std::abs(loop[j] - p);
      }
      for (size_t j = 0; j < k; ++j) {
        const size_t jm = (j + k - 1) % k, jp = (j + 1) % k;
        const double lm = edge_log[jm], l0 = edge_log[j];
        g.WD(i, col + static_cast<Eigen::Index>(j)) =
            inv2pi * ((1 + lm) / std::abs(loop[j] - loop[jm]) + (1 + l0) / std::abs(loop[jp] - loop[j]));
        g.WE(i, col + static_cast<Eigen::Index>(j)) = inv2pi * (dist[jp] + dist[jm]) / (dist[jm] * dist[j] * dist[jp]);
      }
      col += static_cast<int>(k);
    }
    for (int h = 0; h < N; ++h) {
      const double r = 1 / std::abs(p - cage.hole_points[static_cast<size_t>(h)]);
      g.WD(i, m + h) = r;
      g.WE(i, m + h) = r * r;
    }
  }
  return g;
}

struct Certifier::Impl {
  const Cage cage;
  int m = 0, N = 0;
  CertificateSegments seg;  // breakpoints; segment i joins breakpoint i to its successor in the loop
  MatrixXcd D, E;           // basis rows at the breakpoints (full columns)
  CertificateWeights weights;

  Impl(const Shape& shape, const Cage& c, const BoundarySamples& s)
      : cage(c), seg(certificate_segments(shape, s)), weights(certificate_weights(c, seg)) {
    m = cage.vertex_count();
    N = cage.hole_count();
    const BasisRows rows = evaluate_basis(cage, seg.points, kBasisD | kBasisE);
    D = rows.D;
    E = rows.E;
  }
};

Certifier::Certifier(const Shape& shape, const Cage& cage, const BoundarySamples& samples)
    : impl_(std::make_unique<Impl>(shape, cage, samples)) {}
Certifier::~Certifier() = default;
Certifier::Certifier(Certifier&&) noexcept = default;
Certifier& Certifier::operator=(Certifier&&) noexcept = default;
int Certifier::breakpoint_count() const { return static_cast<int>(impl_->seg.size()); }
const CertificateSegments& Certifier::segments() const { return impl_->seg; }
const MatrixXcd& Certifier::breakpoint_D() const { return impl_->D; }
const MatrixXcd& Certifier::breakpoint_E() const { return impl_->E; }
const CertificateWeights& Certifier::weights() const { return impl_->weights; }

namespace {

struct Values {
  cd a, b, a1, b1;     // f_z, conj f_zbar and their z-derivatives
  double ea, eb, ea1, eb1;  // bounds on the absolute rounding error of each
};

}  // namespace

CertificateResult Certifier::certify(const HarmonicMap& map, const CertificateOptions& opt) const {
  const Impl& I = *impl_;
  if (map.phi.size() != I.m + I.N || map.psi.size() != I.m + I.N)
    throw InputError("certificate: the map has " + std::to_string(map.phi.size()) + " coefficients; the cage needs " +
                     std::to_string(I.m + I.N));
  CertificateResult r;
  if (!map.phi.allFinite() || !map.psi.allFinite()) {
    r.reason = "the map's coefficients are not finite";
    return r;
  }
  Eigen::Matrix<cd, Eigen::Dynamic, 2> coef(I.m + I.N, 2);
  coef << map.phi, map.psi;
  const Eigen::Matrix<cd, Eigen::Dynamic, 2> ab = detail::rows_times(I.D, coef), ab1 = detail::rows_times(I.E, coef);
  const auto a = ab.col(0), b = ab.col(1), a1 = ab1.col(0), b1 = ab1.col(1);
  // Rounding: a computed value is within (2 M + 72) u of its weighted sum of magnitudes
  // (certificate_weights' WD, WE) of the exact one: 16 u per entry, the product and a
  // sum of M terms.
  const int M = I.m + I.N;
  const double value_err = (2.0 * M + 72) * kU;
  Eigen::MatrixXd abs_coef(M, 2);  // [|φ| |ψ|]: one pass over each weight matrix
  abs_coef << map.phi.cwiseAbs(), map.psi.cwiseAbs();
  const auto abs_phi = abs_coef.col(0), abs_psi = abs_coef.col(1);
  const Eigen::MatrixXd eD = value_err * detail::rows_times(I.weights.WD, abs_coef);
  const Eigen::MatrixXd eE = value_err * detail::rows_times(I.weights.WE, abs_coef);
  const auto ea = eD.col(0), eb = eD.col(1), ea1 = eE.col(0), eb1 = eE.col(1);
  // Lipschitz constants of f_zz and of (conj f_zbar)' per segment (bounds on the third
  // derivatives), from upper bounds of |S_j| and lower bounds of the distances, raised
  // by the rounding of the sums.
  const double inv2pi = 1 / (2 * std::numbers::pi);
  // The log columns contribute −φ_log/(w − ρ)² to f_zz and −ψ_log/(w − ρ)² to (conj f_zbar)'.
  const Eigen::MatrixXd logmag = abs_coef.bottomRows(I.N) * (1 + 4 * kU);
  Eigen::VectorXd err_phi, err_psi;
  const Eigen::VectorXd s_phi = certificate_jumps(I.cage, map.phi, &err_phi);
  const Eigen::VectorXd s_psi = certificate_jumps(I.cage, map.psi, &err_psi);
  Eigen::MatrixXd jumps(I.m, 2);  // upper bounds of |S_j| for φ and ψ
  jumps << s_phi + err_phi, s_psi + err_psi;
  jumps *= 1 + 2 * kU;
  const double lip_up = 1 + (2.0 * M + 32) * kU;
  const Eigen::MatrixXd L = lip_up * (inv2pi * detail::rows_times(I.weights.W, jumps) + 2 * detail::rows_times(I.weights.Wh, logmag));
  Eigen::VectorXd La = L.col(0), Lb = L.col(1);
  for (Eigen::Index i = 0; i < La.size(); ++i)
    if (I.weights.touches[static_cast<size_t>(i)]) La(i) = Lb(i) = std::numeric_limits<double>::infinity();

  const Eigen::Index S = static_cast<Eigen::Index>(I.seg.size());
  std::vector<SegmentCertificate> out(static_cast<size_t>(S));
  std::atomic<bool> stop{false};

  // f_z, conj f_zbar and their derivatives at one point, straight from the cage
  // (math.md §2), without forming basis rows: the subdivision's inner loop. The error
  // bounds sum the same weights as certificate_weights' WD and WE.
  const cd inv2pii = 1.0 / (2.0 * std::numbers::pi * cd(0, 1));
  auto values_at = [&](cd w) {
    Values v{0, 0, 0, 0, 0, 0, 0, 0};
    int col = 0;
    for (const Loop& loop : I.cage.loops) {
      const size_t k = loop.size();
      cd Bm = loop[k - 1] - w, B0 = loop[0] - w;
      cd Lm = std::log(B0 / Bm);  // log(B_j / B_{j−1}) for j = 0
      for (size_t j = 0; j < k; ++j) {
        const size_t jp = (j + 1) % k;
        const cd Bp = loop[jp] - w;
        const cd L0 = std::log(Bp / B0);
        const cd A0 = loop[j] - loop[(j + k - 1) % k], A1 = loop[jp] - loop[j];
        const cd D = inv2pii * (Lm / A0 - L0 / A1);
        const cd E = inv2pii * (Bp - Bm) / (Bm * B0 * Bp);
        const Eigen::Index c = col + static_cast<Eigen::Index>(j);
        v.a += D * map.phi(c);
        v.b += D * map.psi(c);
        v.a1 += E * map.phi(c);
        v.b1 += E * map.psi(c);
        const double wd = (1 + std::abs(Lm)) / std::abs(A0) + (1 + std::abs(L0)) / std::abs(A1);
        const double we = (std::abs(Bp) + std::abs(Bm)) / (std::abs(Bm) * std::abs(B0) * std::abs(Bp));
        v.ea += wd * abs_phi(c);
        v.eb += wd * abs_psi(c);
        v.ea1 += we * abs_phi(c);
        v.eb1 += we * abs_psi(c);
        Bm = B0;
        B0 = Bp;
        Lm = L0;
      }
      col += static_cast<int>(k);
    }
    v.ea *= inv2pi;
    v.eb *= inv2pi;
    v.ea1 *= inv2pi;
    v.eb1 *= inv2pi;
    for (int h = 0; h < I.N; ++h) {
      const cd d = w - I.cage.hole_points[static_cast<size_t>(h)];
      v.a += map.phi(I.m + h) / d;
      v.b += map.psi(I.m + h) / d;
      v.a1 -= map.phi(I.m + h) / (d * d);
      v.b1 -= map.psi(I.m + h) / (d * d);
      const double inv_d = 1 / std::abs(d);
      v.ea += abs_phi(I.m + h) * inv_d;
      v.eb += abs_psi(I.m + h) * inv_d;
      v.ea1 += abs_phi(I.m + h) * inv_d * inv_d;
      v.eb1 += abs_psi(I.m + h) * inv_d * inv_d;
    }
    v.ea *= value_err;
    v.eb *= value_err;
    v.ea1 *= value_err;
    v.eb1 *= value_err;
    return v;
  };

  // Proves (b) and the arg condition on [p, q] from values at its ends, subdividing
  // (new basis rows at midpoints; the parent's Lipschitz constants stay valid).
  auto prove = [&](auto&& self, cd p, cd q, const Values& vp, const Values& vq, double lipA, double lipB, int depth,
                   SegmentCertificate& o) -> void {
    // The bounds of math.md §6 with every rounding on the conservative side: the values'
    // error bounds, and an absolute allowance for the few operations here (as
    // certify.comp). So a piece passes only with room to spare for round-off: a map
    // whose margin is at the level of its own rounding is not certified.
    const double abs_ap = std::abs(vp.a), abs_aq = std::abs(vq.a), abs_bp = std::abs(vp.b), abs_bq = std::abs(vq.b);
    const double len = std::abs(q - p) * (1 + 4 * kU);
    const double fzz_max = (((std::abs(vp.a1) + vp.ea1) + (std::abs(vq.a1) + vq.ea1)) / 2 + lipA * len / 2) * (1 + 8 * kU);
    const double bz_max = (((std::abs(vp.b1) + vp.eb1) + (std::abs(vq.b1) + vq.eb1)) / 2 + lipB * len / 2) * (1 + 8 * kU);
    const double a_avg_lo = ((abs_ap - vp.ea) + (abs_aq - vq.ea)) / 2;
    const double a_avg_hi = ((abs_ap + vp.ea) + (abs_aq + vq.ea)) / 2;
    const double b_avg_hi = ((abs_bp + vp.eb) + (abs_bq + vq.eb)) / 2;
    const double tol = 8 * kU * (a_avg_hi + b_avg_hi + fzz_max * len + bz_max * len);
    const double a_lo = a_avg_lo - fzz_max * len / 2 - tol;  // bounds of |f_z|, |f_zbar| on σ
    const double a_hi = a_avg_hi + fzz_max * len / 2 + tol;
    const double b_hi = b_avg_hi + bz_max * len / 2 + tol;
    // The image of σ under f_z stays in the disc |w − f_z(p)| ≤ fzz_max·len, which must exclude 0
    // for the principal arg increment to be the true one.
    const bool arg_ok = fzz_max * len + vp.ea + tol < abs_ap;
    // A point where |f_zbar| ≥ |f_z| is a real fold: no subdivision can help.
    const bool folds_here = abs_bp >= abs_ap || abs_bq >= abs_aq;
    if (a_lo > b_hi && arg_ok) {
      o.pieces++;
      o.arg += std::arg(vq.a / vp.a);
      o.margin = std::min(o.margin, a_lo - b_hi);
      o.sigma1 = std::max(o.sigma1, a_hi + b_hi);
      o.sigma2 = std::min(o.sigma2, a_lo - b_hi);
      o.k = std::max(o.k, b_hi / a_lo * (1 + 2 * kU));
      return;
    }
    if (folds_here || depth >= opt.max_depth || o.pieces >= opt.max_pieces_per_segment ||
        stop.load(std::memory_order_relaxed)) {
      o.ok = false;
      o.pieces++;
      o.margin = std::min(o.margin, a_lo - b_hi);
      o.fail_point = (p + q) / 2.0;
      return;
    }
    const cd mid = (p + q) / 2.0;
    const Values vm = values_at(mid);
    self(self, p, mid, vp, vm, lipA, lipB, depth + 1, o);
    if (!o.ok) return;
    self(self, mid, q, vm, vq, lipA, lipB, depth + 1, o);
  };

#pragma omp parallel for schedule(dynamic, 64)
  for (Eigen::Index i = 0; i < S; ++i) {
    if (stop.load(std::memory_order_relaxed)) continue;
    const size_t u = static_cast<size_t>(i), v = static_cast<size_t>(I.seg.next[u]);
    const Values vp{a(i), b(i), a1(i), b1(i), ea(i), eb(i), ea1(i), eb1(i)};
    const Eigen::Index j = static_cast<Eigen::Index>(v);
    const Values vq{a(j), b(j), a1(j), b1(j), ea(j), eb(j), ea1(j), eb1(j)};
    SegmentCertificate& o = out[u];
    prove(prove, I.seg.points[u], I.seg.points[v], vp, vq, La(i), Lb(i), 0, o);
    if (!o.ok && opt.stop_at_first_failure) stop.store(true, std::memory_order_relaxed);
  }

  std::vector<double> abs_a(static_cast<size_t>(S)), abs_b(static_cast<size_t>(S));
  for (Eigen::Index i = 0; i < S; ++i) {
    abs_a[static_cast<size_t>(i)] = std::abs(a(i));
    abs_b[static_cast<size_t>(i)] = std::abs(b(i));
  }
  return reduce_certificate(I.seg, out, abs_a, abs_b);
}

namespace {
class CpuCertifier final : public MapCertifier {
 public:
  CpuCertifier(const Shape& shape, const Cage& cage, const BoundarySamples& samples) : certifier_(shape, cage, samples) {}
  const char* name() const override { return "cpu"; }
  CertificateResult certify(const HarmonicMap& map, const CertificateOptions& options = {}) override {
    return certifier_.certify(map, options);
  }

 private:
  Certifier certifier_;
};
}  // namespace

std::unique_ptr<MapCertifier> make_cpu_certifier(const Shape& shape, const Cage& cage, const BoundarySamples& samples) {
  return std::make_unique<CpuCertifier>(shape, cage, samples);
}

CertificateResult reduce_certificate(const CertificateSegments& seg, std::span<const SegmentCertificate> out,
                                     std::span<const double> abs_a, std::span<const double> abs_b) {
  const size_t S = seg.size();
  if (out.size() != S || abs_a.size() != S || abs_b.size() != S)
    throw InputError("certificate: " + std::to_string(out.size()) + " segment outcomes and " +
                     std::to_string(abs_a.size()) + " breakpoint values for " + std::to_string(S) + " segments");
  CertificateResult r;
  r.certified = true;
  double arg_total = 0;
  r.min_margin = std::numeric_limits<double>::infinity();
  r.sigma2_min = std::numeric_limits<double>::infinity();
  r.observed_sigma2_min = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < S; ++i) {
    const SegmentCertificate& o = out[i];
    r.segments++;
    r.subdivisions += std::max<long>(0, o.pieces - 1);
    if (!o.ok && r.certified) {
      r.certified = false;
      r.fail_loop = seg.loop[i];
      r.fail_edge = seg.edge[i];
      r.fail_point = o.fail_point;
    }
    arg_total += o.arg;
    r.min_margin = std::min(r.min_margin, o.margin);
    r.sigma1_max = std::max(r.sigma1_max, o.sigma1);
    r.sigma2_min = std::min(r.sigma2_min, o.sigma2);
    r.k_max = std::max(r.k_max, o.k);
    const double aa = abs_a[i], bb = abs_b[i];
    r.observed_sigma1_max = std::max(r.observed_sigma1_max, aa + bb);
    r.observed_sigma2_min = std::min(r.observed_sigma2_min, aa - bb);
    r.observed_k_max = std::max(r.observed_k_max, bb / aa);
    const double s1 = aa + bb, s2 = aa - bb;
    r.observed_isometric_max = std::max(r.observed_isometric_max, 0.5 * (s1 * s1 + 1 / (s1 * s1) + s2 * s2 + 1 / (s2 * s2)));
  }
  return finish_certificate(std::move(r), arg_total);
}

CertificateResult finish_certificate(CertificateResult r, double arg_total) {
  if (!r.certified) {
    std::ostringstream s;
    s.precision(6);
    s << "|f_z| > |f_zbar| could not be proved on " << loop_name(r.fail_loop) << " edge " << r.fail_edge << " near ("
      << r.fail_point.real() << ", " << r.fail_point.imag() << ")";
    if (r.observed_sigma2_min <= 0) s << "; the map folds there (|f_zbar| >= |f_z| at a sample)";
    r.reason = s.str();
    return r;
  }
  r.winding = static_cast<int>(std::lround(arg_total / (2 * std::numbers::pi)));
  if (r.winding != 0) {
    r.certified = false;
    r.reason = "f_z has " + std::to_string(r.winding) + " zero(s) inside the shape (argument principle): the map folds inside";
    return r;
  }
  r.conformal_max = (1 + r.k_max) / (1 - r.k_max);
  return r;
}

}  // namespace hsi
