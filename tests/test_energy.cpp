// The per-sample isometric energy (paper Eq. 5, 10, 15–21): metric against JᵀJ,
// gradient and Hessian against finite differences, PSD projections, invariances.
#include <catch2/catch.hpp>

#include <Eigen/Eigenvalues>
#include <random>

#include "hsi/energy.h"

using namespace hsi;

namespace {
// Real Jacobian of the map with f_z = a, conj(f_zbar) = b: J = [[Re(a + c), Im(c − a)], [Im(a + c), Re(a − c)]], c = f_zbar.
Eigen::Matrix2d jacobian(cd a, cd b) {
  const cd c = std::conj(b);
  Eigen::Matrix2d J;
  // f(z) ≈ a z + c conj(z): ∂f/∂x = a + c, ∂f/∂y = i(a − c).
  const cd fx = a + c, fy = cd(0, 1) * (a - c);
  J << fx.real(), fy.real(), fx.imag(), fy.imag();
  return J;
}
struct Case {
  Metric g;
  cd a, b;
};
std::vector<Case> random_cases(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Case> out;
  while (static_cast<int>(out.size()) < count) {
    const cd a(1 + 0.5 * u(rng), 0.5 * u(rng)), b(0.4 * u(rng), 0.4 * u(rng));
    const cd ga(1 + 0.5 * u(rng), 0.5 * u(rng)), gb(0.4 * u(rng), 0.4 * u(rng));
    if (std::abs(b) >= 0.9 * std::abs(a) || std::abs(gb) >= 0.9 * std::abs(ga)) continue;
    out.push_back({pullback_metric(ga, gb), a, b});
  }
  return out;
}
Eigen::Vector4d vec(cd a, cd b) { return {a.real(), a.imag(), b.real(), b.imag()}; }
}  // namespace

TEST_CASE("pull-back metric (Eq. 5) equals JᵀJ", "[energy]") {
  for (const Case& c : random_cases(50, 1)) {
    const Eigen::Matrix2d M = jacobian(c.a, c.b).transpose() * jacobian(c.a, c.b);
    const Metric m = pullback_metric(c.a, c.b);
    CHECK(m(0) == Approx(M(0, 0)).margin(1e-14));
    CHECK(m(1) == Approx(M(0, 1)).margin(1e-14));
    CHECK(m(2) == Approx(M(1, 1)).margin(1e-14));
  }
}

TEST_CASE("energy (Eq. 10) is the symmetric Dirichlet energy of h∘g⁻¹; minimum 2 at g = h", "[energy]") {
  for (const Case& c : random_cases(50, 2)) {
    const Metric h = pullback_metric(c.a, c.b);
    Eigen::Matrix2d G, Hm;
    G << c.g(0), c.g(1), c.g(1), c.g(2);
    Hm << h(0), h(1), h(1), h(2);
    const double expect = 0.5 * ((G.inverse() * Hm).trace() + (G * Hm.inverse()).trace());  // Eq. 7
    CHECK(isometric_energy(c.g, c.a, c.b) == Approx(expect).epsilon(1e-12));
    CHECK(isometric_energy(h, c.a, c.b) == Approx(2.0).epsilon(1e-12));
    CHECK(isometric_energy(c.g, c.a, c.b) >= 2.0 - 1e-12);
  }
  // Folded or degenerate: infinite.
  CHECK(std::isinf(isometric_energy(Metric(1, 0, 1), 0.5, 0.7)));
  CHECK(std::isinf(isometric_energy(Metric(1, 0, 1), 0.5, 0.5)));
}

TEST_CASE("energy is invariant under rotations of the image", "[energy]") {
  for (const Case& c : random_cases(20, 3)) {
    const cd r = std::polar(1.0, 1.234);
    CHECK(isometric_energy(c.g, r * c.a, std::conj(r) * c.b) == Approx(isometric_energy(c.g, c.a, c.b)).epsilon(1e-13));
  }
}

TEST_CASE("per-sample gradient and exact Hessian match finite differences", "[energy]") {
  const double h = 1e-6;
  for (const Case& c : random_cases(40, 4)) {
    const SampleDerivatives d = isometric_derivatives(c.g, c.a, c.b, HessianProjection::PartProj, true);
    const Eigen::Vector4d v = vec(c.a, c.b);
    auto e = [&](const Eigen::Vector4d& x) { return isometric_energy(c.g, cd(x(0), x(1)), cd(x(2), x(3))); };
    auto grad = [&](const Eigen::Vector4d& x) {
      return isometric_derivatives(c.g, cd(x(0), x(1)), cd(x(2), x(3)), HessianProjection::PartProj, true).grad;
    };
    for (int i = 0; i < 4; ++i) {
      Eigen::Vector4d dx = Eigen::Vector4d::Zero();
      dx(i) = h;
      CHECK(d.grad(i) == Approx((e(v + dx) - e(v - dx)) / (2 * h)).margin(1e-7));
      const Eigen::Vector4d col = (grad(v + dx) - grad(v - dx)) / (2 * h);
      for (int j = 0; j < 4; ++j) CHECK(d.hess(j, i) == Approx(col(j)).margin(1e-6 * std::max(1.0, d.hess.norm())));
    }
  }
}

TEST_CASE("projected Hessians are PSD; PartProj projects K1 like a numerical eigensolver", "[energy]") {
  for (const Case& c : random_cases(200, 5)) {
    for (HessianProjection p : {HessianProjection::Delete, HessianProjection::FullProj, HessianProjection::PartProj}) {
      const SampleDerivatives d = isometric_derivatives(c.g, c.a, c.b, p);
      const double lmin = Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(d.hess).eigenvalues().minCoeff();
      CHECK(lmin >= -1e-10 * std::max(1.0, d.hess.norm()));
    }
  }
  std::mt19937 rng(6);
  std::normal_distribution<double> n(0, 1);
  for (int t = 0; t < 200; ++t) {
    const Eigen::Vector3d alpha(n(rng), n(rng), n(rng));
    // K1 = Σ α_i F_i; its PSD projection by eigen-decomposition.
    const Eigen::Matrix4d K1 = project_K1(alpha) + Eigen::Matrix4d::Zero();
    Eigen::Matrix4d full;
    full << alpha(0) + alpha(2), 0, alpha(0) - alpha(2), -alpha(1), 0, alpha(0) + alpha(2), -alpha(1), -alpha(0) + alpha(2),
        alpha(0) - alpha(2), -alpha(1), alpha(0) + alpha(2), 0, -alpha(1), -alpha(0) + alpha(2), 0, alpha(0) + alpha(2);
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(full);
    const Eigen::Matrix4d proj = es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).asDiagonal() * es.eigenvectors().transpose();
    CHECK((K1 - proj).norm() < 1e-12 * std::max(1.0, full.norm()));
  }
}

TEST_CASE("projection names parse", "[energy]") {
  CHECK(parse_projection("partproj") == HessianProjection::PartProj);
  CHECK(std::string(to_string(HessianProjection::FullProj)) == "fullproj");
  CHECK_THROWS_AS(parse_projection("nope"), std::runtime_error);
}
