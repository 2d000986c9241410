// The injectivity certificate (math.md §6): injective maps certify with bounds that
// hold; folding maps fail, including zeros of f_z inside and folds between samples;
// it never certifies a map that a dense brute-force check finds folded.
#include <catch2/catch.hpp>

#include <random>

#include "hsi/certificate.h"
#include "hsi/map_space.h"
#include "test_shapes.h"

using namespace hsi;
using Catch::Matchers::Contains;

namespace {

// Brute force: |f_zbar| < |f_z| at `count` boundary points, and no zero of f_z
// inside (winding of f_z along the dense boundary).
struct Dense {
  bool injective;
  double min_gap;
  int winding;
};
Dense dense_check(const Shape& shape, const Cage& cage, const HarmonicMap& m, int count) {
  const BoundarySamples s = sample_boundary(shape, count);
  const MapValues v = evaluate_map(evaluate_basis(cage, s.points, kBasisD), m);
  double gap = std::numeric_limits<double>::infinity(), arg = 0;
  for (int l = 0; l < shape.loop_count(); ++l)
    for (int i = s.loop_begin[static_cast<size_t>(l)]; i < s.loop_begin[static_cast<size_t>(l) + 1]; ++i) {
      const int j = i + 1 < s.loop_begin[static_cast<size_t>(l) + 1] ? i + 1 : s.loop_begin[static_cast<size_t>(l)];
      gap = std::min(gap, std::abs(v.f_z(i)) - std::abs(v.fzbar_conj(i)));
      arg += std::arg(v.f_z(j) / v.f_z(i));
    }
  const int w = static_cast<int>(std::lround(arg / (2 * std::numbers::pi)));
  return {gap > 0 && w == 0, gap, w};
}

HarmonicMap random_perturbation(const Cage& cage, unsigned seed, double amp) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, amp);
  HarmonicMap m = identity_map(cage);
  const int M = cage.vertex_count();
  for (Eigen::Index j = 0; j < m.phi.size(); ++j) {
    m.phi(j) += cd(g(rng), g(rng));
    m.psi(j) += cd(g(rng), g(rng));
  }
  for (int h = 0; h < cage.hole_count(); ++h) {
    m.phi(M + h) *= 0.1;
    m.psi(M + h) = std::conj(m.phi(M + h));
  }
  return m;
}

}  // namespace

TEST_CASE("identity and affine maps certify, with bounds that hold", "[certificate]") {
  for (const Shape& s : {test::annulus(), test::bar_with_holes(), test::disc()}) {
    const Cage cage = build_cage(s);
    const Certifier cert(s, cage, sample_boundary(s, 1000));
    const CertificateResult id = cert.certify(identity_map(cage));
    CHECK(id.certified);
    CHECK(id.winding == 0);
    CHECK(id.sigma1_max == Approx(1).margin(1e-6));
    CHECK(id.sigma2_min == Approx(1).margin(1e-6));
    const cd a = std::polar(1.3, 0.4), b = std::polar(0.5, -1.1);
    const CertificateResult af = cert.certify(affine_map(cage, a, b, cd(2, 3)));
    REQUIRE(af.certified);
    // True values: σ1 = |a| + |b|, σ2 = |a| − |b|, k = |b|/|a|; bounds must contain them.
    CHECK(af.sigma1_max >= std::abs(a) + std::abs(b) - 1e-9);
    CHECK(af.sigma2_min <= std::abs(a) - std::abs(b) + 1e-9);
    CHECK(af.k_max >= std::abs(b) / std::abs(a) - 1e-9);
    CHECK(af.sigma1_max == Approx(std::abs(a) + std::abs(b)).epsilon(1e-6));
    CHECK(af.k_max < 1);
  }
}

TEST_CASE("a margin at the level of round-off is not certified; a small clear one is", "[certificate]") {
  // f = z + b conj(z) with |b| = 1 − δ: locally injective for every δ > 0 in exact
  // arithmetic, σ2 = δ everywhere. A δ below what the double-precision evaluation of
  // f_z and f_zbar can resolve (sums over every cage column) proves nothing: the
  // certificate must not pass it, however the round-off falls. (Without its rounding
  // allowances it certified 8 of these 9 maps.)
  for (const Shape& s : {test::annulus(), test::bar_with_holes(), test::disc()}) {
    const Cage cage = build_cage(s);
    const Certifier cert(s, cage, sample_boundary(s, 1000));
    for (const double delta : {1e-13, 1e-14, 1e-15}) {
      INFO("delta " << delta);
      const CertificateResult r = cert.certify(affine_map(cage, 1.0, std::polar(1 - delta, 0.7), 0.0));
      CHECK_FALSE(r.certified);
      CHECK_THAT(r.reason, Contains("could not be proved"));
    }
    for (const double delta : {1e-3, 1e-6}) {
      INFO("delta " << delta);
      const CertificateResult r = cert.certify(affine_map(cage, 1.0, std::polar(1 - delta, 0.7), 0.0));
      REQUIRE(r.certified);
      CHECK(r.sigma2_min > 0);
      CHECK(r.sigma2_min <= delta);  // a lower bound of the true σ2 = δ
      CHECK(r.sigma2_min > 0.5 * delta);
      CHECK(r.k_max >= 1 - delta);
      CHECK(r.k_max < 1);
    }
  }
}

TEST_CASE("an orientation-reversing map fails and says where", "[certificate]") {
  const Shape s = test::annulus();
  const Cage cage = build_cage(s);
  const Certifier cert(s, cage, sample_boundary(s, 500));
  const CertificateResult r = cert.certify(affine_map(cage, 1.0, 1.2, 0.0));
  CHECK_FALSE(r.certified);
  CHECK(r.fail_loop >= 0);
  CHECK_THAT(r.reason, Contains("could not be proved") && Contains("folds"));
}

TEST_CASE("a zero of f_z inside the shape fails by the argument principle", "[certificate]") {
  // Φ(w) ≈ (w − w0)²/2: f_z ≈ w − w0 vanishes at w0 inside Ω, yet |f_zbar| = 0 < |f_z| on ∂Ω.
  for (const auto& [shape, w0] : {std::pair<Shape, cd>{test::disc(1.0, 128), cd(0.2, -0.1)},
                                  std::pair<Shape, cd>{test::annulus(1.0, 0.4, 128), cd(0.7, 0.0)}}) {
    const Cage cage = build_cage(shape);
    const Certifier cert(shape, cage, sample_boundary(shape, 2000));
    HarmonicMap m{VectorXcd::Zero(basis_size(cage)), VectorXcd::Zero(basis_size(cage))};
    int j = 0;
    for (const Loop& l : cage.loops)
      for (const cd& z : l) m.phi(j++) = (z - w0) * (z - w0) / 2.0;
    const CertificateResult r = cert.certify(m);
    CHECK_FALSE(r.certified);
    CHECK(r.winding == 1);
    CHECK_THAT(r.reason, Contains("zero"));
    CHECK(r.observed_sigma2_min > 0);  // the samples alone would not notice
  }
}

TEST_CASE("a fold on a tiny arc between samples fails, though every sample looks fine", "[certificate]") {
  // A user cage close to a disc makes D_j(w) sharply peaked near the boundary point
  // closest to cage vertex j; conj(f_zbar) = β D_j then exceeds |f_z| = 1 on a short
  // arc only. Samples are placed so that the arc falls between them.
  // 64-gon; cage vertices half a polygon step off the polygon's vertices, so the
  // peak lies midway between breakpoints (32 samples sit on odd polygon vertices).
  const Shape s = test::disc(1.0, 64);
  Cage cage;
  cage.loops.push_back(test::circle(0, 1.02, 64));
  for (cd& z : cage.loops[0]) z *= std::polar(1.0, std::numbers::pi / 64);
  check_cage(s, cage);
  const int j = 5;
  const cd peak = cage.loops[0][j] / std::abs(cage.loops[0][j]);  // ≈ boundary point nearest z_j
  // Scale β so that |β D_j| peaks at 1.01 on a dense boundary.
  const BoundarySamples dense = sample_boundary(s, 50000);
  const BasisRows rows = evaluate_basis(cage, dense.points, kBasisD);
  const double peak_val = rows.D.col(j).cwiseAbs().maxCoeff();
  HarmonicMap m = identity_map(cage);
  m.psi(j) = 1.01 / peak_val;
  const Dense truth = dense_check(s, cage, m, 50000);
  REQUIRE_FALSE(truth.injective);
  const BoundarySamples g = sample_boundary(s, 32);
  const BasisRows at_g = evaluate_basis(cage, g.points, kBasisD);
  const MapValues vg = evaluate_map(at_g, m);
  double worst_sample_gap = (vg.f_z.cwiseAbs() - vg.fzbar_conj.cwiseAbs()).minCoeff();
  // Polygon vertices are breakpoints too; check they miss the fold as well.
  const MapValues vv = evaluate_map(evaluate_basis(cage, s.outer, kBasisD), m);
  worst_sample_gap = std::min(worst_sample_gap, (vv.f_z.cwiseAbs() - vv.fzbar_conj.cwiseAbs()).minCoeff());
  INFO("peak near " << peak << ", smallest gap at breakpoints " << worst_sample_gap << ", dense " << truth.min_gap);
  REQUIRE(worst_sample_gap > 0);  // the samples alone would call it injective
  const Certifier cert(s, cage, g);
  const CertificateResult r = cert.certify(m);
  CHECK_FALSE(r.certified);
  CHECK(std::abs(r.fail_point - peak) < 0.1);
}

TEST_CASE("never certifies what a dense check finds folded (random maps near the fold boundary)", "[certificate]") {
  int certified = 0, dense_injective = 0, total = 0;
  for (const Shape& s : {test::annulus(1.0, 0.4, 96), test::bar_with_holes()}) {
    const Cage cage = build_cage(s);
    const Certifier cert(s, cage, sample_boundary(s, 400));
    for (unsigned seed = 0; seed < 24; ++seed) {
      // Amplitudes sweep across the fold boundary.
      const double amp = 0.02 + 0.03 * (seed % 12);
      const HarmonicMap m = random_perturbation(cage, 1000 + seed, amp);
      const CertificateResult r = cert.certify(m);
      const Dense d = dense_check(s, cage, m, 20000);
      ++total;
      certified += r.certified;
      dense_injective += d.injective;
      if (r.certified) {
        INFO("seed " << seed << " amp " << amp << ": certified but dense gap " << d.min_gap << " winding " << d.winding);
        CHECK(d.injective);
        CHECK(d.min_gap >= r.sigma2_min - 1e-12);  // the certified lower bound holds
      }
    }
  }
  INFO(certified << " certified, " << dense_injective << " injective by dense check, of " << total);
  CHECK(certified > 0);               // the sweep covers both sides of the fold boundary
  CHECK(dense_injective < total);
}

TEST_CASE("certificate refuses wrong sizes and non-finite maps", "[certificate]") {
  const Shape s = test::annulus();
  const Cage cage = build_cage(s);
  const Certifier cert(s, cage, sample_boundary(s, 200));
  CHECK_THROWS_AS(cert.certify(HarmonicMap{VectorXcd::Zero(2), VectorXcd::Zero(2)}), InputError);
  HarmonicMap m = identity_map(cage);
  m.phi(0) = cd(NAN, 0);
  CHECK_FALSE(cert.certify(m).certified);
}

TEST_CASE("subdivision evaluates the map like the basis does", "[certificate]") {
  // A map whose certificate needs subdivision (a strong but injective deformation)
  // gets the same verdict and bounds at a finer sampling, where little subdivision is needed.
  const Shape s = test::bar_with_holes();
  const Cage cage = build_cage(s);
  const HarmonicMap m = random_perturbation(cage, 77, 0.15);
  const Certifier coarse(s, cage, sample_boundary(s, 8)), fine(s, cage, sample_boundary(s, 20000));
  const CertificateResult a = coarse.certify(m), b = fine.certify(m);
  INFO("coarse: " << a.certified << " with " << a.subdivisions << " subdivisions; fine: " << b.certified << " with "
                  << b.subdivisions);
  REQUIRE(b.certified);
  CHECK(a.certified);
  CHECK(a.subdivisions > 0);
  CHECK(a.sigma1_max >= b.observed_sigma1_max - 1e-12);
  CHECK(a.sigma2_min <= b.observed_sigma2_min + 1e-12);
}

// What the CUDA core's device certificate now takes from the setup's certifier instead of
// evaluating again (DeviceCertifier(const Certifier&, ...)): the same rows and weights a
// fresh evaluation gives, in the layout its upload checks (S × M rows; W over the cage's
// m vertices beside Wh over its N holes).
TEST_CASE("the certifier's breakpoint rows and weights are those evaluated afresh, S x M", "[certificate]") {
  const Shape s = test::annulus(1.0, 0.4, 48);
  const Cage cage = build_cage(s);
  const BoundarySamples G = sample_boundary(s, 700);
  const Certifier c(s, cage, G);
  const CertificateSegments seg = certificate_segments(s, G);
  const Eigen::Index S = static_cast<Eigen::Index>(seg.size()), m = cage.vertex_count(), N = cage.hole_count();
  REQUIRE(c.breakpoint_count() == S);
  const BasisRows rows = evaluate_basis(cage, seg.points, kBasisD | kBasisE);
  CHECK(c.breakpoint_D() == rows.D);
  CHECK(c.breakpoint_E() == rows.E);
  CHECK(c.breakpoint_D().rows() == S);
  CHECK(c.breakpoint_D().cols() == m + N);
  const CertificateWeights w = certificate_weights(cage, seg);
  const CertificateWeights& cw = c.weights();
  CHECK(cw.W == w.W);
  CHECK(cw.Wh == w.Wh);
  CHECK(cw.WD == w.WD);
  CHECK(cw.WE == w.WE);
  CHECK(cw.touches == w.touches);
  CHECK((cw.W.rows() == S && cw.W.cols() == m));
  CHECK((cw.Wh.rows() == S && cw.Wh.cols() == N));
  CHECK((cw.WD.rows() == S && cw.WD.cols() == m + N && cw.WE.cols() == m + N));
}
