// The Newton machinery: the CPU core's energy, gradient and Hessian against finite
// differences and against a naive assembly, PSD-ness, the safe step, convergence.
#include <catch2/catch.hpp>

#include <Eigen/Eigenvalues>
#include <random>

#include "dense_kernels.h"
#include "hsi/newton.h"
#include "hsi/shape_setup.h"
#include "split_solve.h"
#include "test_shapes.h"
#include "test_targets.h"

using namespace hsi;

namespace {

struct Fixture {
  ShapeSetup setup;
  std::unique_ptr<NewtonCore> core;
  explicit Fixture(Shape s, int samples = 300, double ratio = 1.0)
      : setup(s, build_cage(s), samples, ratio), core(make_cpu_newton_core(setup.D_G, setup.H)) {}
  const MapSpace& space() const { return setup.metric_space; }
  Eigen::VectorXd perturbed_identity(unsigned seed, double amp) const {
    return test::perturbed(space().reduce(identity_map(setup.cage)).x, seed, amp);
  }
  // Target metrics: the pull-back metric of a map at every sample.
  std::vector<Metric> metrics_of(const Eigen::VectorXd& x) const { return test::metrics_of(setup, x); }
  double E(const Eigen::VectorXd& x) {
    core->set_coefficients(space().T() * x);
    return core->energy();
  }
  Eigen::VectorXd grad(const Eigen::VectorXd& x) {
    core->set_coefficients(space().T() * x);
    return space().T().transpose() * core->gradient();
  }
};

}  // namespace

TEST_CASE("core gradient matches finite differences of the energy", "[newton]") {
  Fixture fx(test::annulus());
  fx.core->set_targets(fx.metrics_of(fx.perturbed_identity(1, 0.02)));
  const Eigen::VectorXd x = fx.perturbed_identity(2, 0.02);
  const Eigen::VectorXd g = fx.grad(x);
  const double h = 1e-6;
  double worst = 0;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(x.size());
    dx(i) = h;
    worst = std::max(worst, std::abs(g(i) - (fx.E(x + dx) - fx.E(x - dx)) / (2 * h)));
  }
  INFO("max abs error " << worst << ", |g| = " << g.norm());
  CHECK(worst < 1e-6 * std::max(1.0, g.norm()));
}

TEST_CASE("core exact Hessian matches finite differences of the gradient", "[newton]") {
  Fixture fx(test::bar_with_holes(), 300, 1.0);  // H = G so the Hessian averages what the gradient does
  fx.core->set_targets(fx.metrics_of(fx.perturbed_identity(3, 0.01)));
  const Eigen::VectorXd x = fx.perturbed_identity(4, 0.01);
  fx.core->set_coefficients(fx.space().T() * x);
  const Eigen::MatrixXd Hx = fx.space().T().transpose() * fx.core->hessian(HessianProjection::PartProj, true) * fx.space().T();
  const double h = 1e-6;
  double worst = 0;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(x.size());
    dx(i) = h;
    const Eigen::VectorXd col = (fx.grad(x + dx) - fx.grad(x - dx)) / (2 * h);
    worst = std::max(worst, (Hx.col(i) - col).cwiseAbs().maxCoeff());
  }
  INFO("max abs error " << worst << ", |H| = " << Hx.norm());
  CHECK(worst < 1e-5 * std::max(1.0, Hx.cwiseAbs().maxCoeff()));
}

TEST_CASE("structured Hessian assembly equals the naive 4n x 4n sum", "[newton]") {
  Fixture fx(test::annulus(), 200, 0.5);
  fx.core->set_targets(fx.metrics_of(fx.perturbed_identity(5, 0.03)));
  const Eigen::VectorXd v = fx.space().T() * fx.perturbed_identity(6, 0.03);
  fx.core->set_coefficients(v);
  const int n = fx.core->n();
  const Eigen::VectorXcd phi = v.segment(0, n).cast<cd>() + cd(0, 1) * v.segment(n, n).cast<cd>();
  const Eigen::VectorXcd psi = v.segment(2 * n, n).cast<cd>() + cd(0, 1) * v.segment(3 * n, n).cast<cd>();
  const std::vector<Metric> g = fx.metrics_of(fx.perturbed_identity(5, 0.03));
  for (HessianProjection p : {HessianProjection::Delete, HessianProjection::FullProj, HessianProjection::PartProj}) {
    Eigen::MatrixXd naive = Eigen::MatrixXd::Zero(4 * n, 4 * n);
    for (int s : fx.setup.H) {
      const Eigen::RowVectorXcd D = fx.setup.D_G.row(s);
      Eigen::MatrixXd B = Eigen::MatrixXd::Zero(4, 4 * n);  // Eq. 13, block-diagonal for φ and ψ
      B.block(0, 0, 1, n) = D.real();
      B.block(0, n, 1, n) = -D.imag();
      B.block(1, 0, 1, n) = D.imag();
      B.block(1, n, 1, n) = D.real();
      B.block(2, 2 * n, 2, 2 * n) = B.block(0, 0, 2, 2 * n);
      const SampleDerivatives d = isometric_derivatives(g[static_cast<size_t>(s)], D * phi, D * psi, p);
      naive += B.transpose() * d.hess * B;
    }
    naive /= static_cast<double>(fx.setup.H.size());
    const Eigen::MatrixXd fast = fx.core->hessian(p);
    CHECK((fast - naive).cwiseAbs().maxCoeff() < 1e-10 * naive.cwiseAbs().maxCoeff());
  }
}

TEST_CASE("the Hessian over every sample, split over the threads, equals the naive sum (exact and projected)", "[newton]") {
  // 1,500 samples: several ranges of samples, each summed on its own and then added.
  Fixture fx(test::bar_with_holes(), 1500, 0.2);
  const Eigen::VectorXd x = fx.perturbed_identity(8, 0.02);
  fx.core->set_targets(fx.metrics_of(fx.perturbed_identity(7, 0.02)));
  const Eigen::VectorXd v = fx.space().T() * x;
  fx.core->set_coefficients(v);
  const int n = fx.core->n();
  const Eigen::VectorXcd phi = v.segment(0, n).cast<cd>() + cd(0, 1) * v.segment(n, n).cast<cd>();
  const Eigen::VectorXcd psi = v.segment(2 * n, n).cast<cd>() + cd(0, 1) * v.segment(3 * n, n).cast<cd>();
  const std::vector<Metric> g = fx.metrics_of(fx.perturbed_identity(7, 0.02));
  for (bool exact : {false, true}) {
    Eigen::MatrixXd naive = Eigen::MatrixXd::Zero(4 * n, 4 * n);
    const Eigen::Index G = fx.setup.D_G.rows();
    for (Eigen::Index s = 0; s < G; ++s) {
      const Eigen::RowVectorXcd D = fx.setup.D_G.row(s);
      Eigen::MatrixXd B = Eigen::MatrixXd::Zero(4, 4 * n);
      B.block(0, 0, 1, n) = D.real();
      B.block(0, n, 1, n) = -D.imag();
      B.block(1, 0, 1, n) = D.imag();
      B.block(1, n, 1, n) = D.real();
      B.block(2, 2 * n, 2, 2 * n) = B.block(0, 0, 2, 2 * n);
      const SampleDerivatives d = isometric_derivatives(g[static_cast<size_t>(s)], D * phi, D * psi, HessianProjection::PartProj, exact);
      naive += B.transpose() * d.hess * B;
    }
    naive /= static_cast<double>(G);
    const Eigen::MatrixXd fast = fx.core->hessian(HessianProjection::PartProj, exact, /*all_samples=*/true);
    INFO("exact " << exact);
    CHECK((fast - naive).cwiseAbs().maxCoeff() < 1e-10 * naive.cwiseAbs().maxCoeff());
    CHECK(fast == fast.transpose());
  }
}

TEST_CASE("hessian_times applies the Hessian without forming it (every projection, exact, subset and all samples)", "[newton]") {
  // A map and targets away from the identity, and a random vector: the product sample by
  // sample against the matrix hessian() forms, and against NewtonCore's default (which
  // forms it), for every choice the loop makes.
  Fixture fx(test::bar_with_holes(), 1500, 0.2);
  fx.core->set_targets(fx.metrics_of(fx.perturbed_identity(7, 0.05)));
  fx.core->set_coefficients(fx.space().T() * fx.perturbed_identity(8, 0.05));
  const int n = fx.core->n();
  std::mt19937 rng(9);
  std::normal_distribution<double> nd(0, 1);
  Eigen::VectorXd p(4 * n);
  for (Eigen::Index i = 0; i < p.size(); ++i) p(i) = nd(rng);
  for (HessianProjection proj : {HessianProjection::Delete, HessianProjection::FullProj, HessianProjection::PartProj})
    for (bool exact : {false, true})
      for (bool all : {false, true}) {
        INFO(to_string(proj) << (exact ? " exact" : "") << (all ? " over G" : " over H"));
        const Eigen::VectorXd ref = fx.core->hessian(proj, exact, all) * p;
        const Eigen::VectorXd hp = fx.core->hessian_times(proj, exact, all, p);
        REQUIRE(hp.size() == ref.size());
        CHECK((hp - ref).cwiseAbs().maxCoeff() <= 1e-12 * ref.cwiseAbs().maxCoeff());
        CHECK(fx.core->NewtonCore::hessian_times(proj, exact, all, p) == ref);
      }
  // The subset's and all of G's products differ (so the test above can tell them apart).
  CHECK((fx.core->hessian_times(HessianProjection::PartProj, true, false, p) -
         fx.core->hessian_times(HessianProjection::PartProj, true, true, p)).cwiseAbs().maxCoeff() > 1e-6);
  CHECK_THROWS_WITH(fx.core->hessian_times(HessianProjection::PartProj, true, true, Eigen::VectorXd::Ones(3)),
                    Catch::Contains("3 entries") && Catch::Contains(std::to_string(4 * n)));
}

TEST_CASE("the Newton system's Cholesky solve: both builds solve it, refuse an indefinite one, and add the ridge", "[newton]") {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  for (long m : {1L, 7L, 300L}) {
    Eigen::MatrixXd R(m, m);
    for (Eigen::Index i = 0; i < R.size(); ++i) R.data()[i] = u(rng);
    const Eigen::MatrixXd A = R * R.transpose() + Eigen::MatrixXd::Identity(m, m);
    Eigen::VectorXd b(m);
    for (Eigen::Index i = 0; i < m; ++i) b(i) = u(rng);
    Eigen::MatrixXd indefinite = A;
    indefinite(m / 2, m / 2) = -1;
    auto check = [&](bool (*solve)(const double*, long, double, const double*, double*), const char* name) {
      INFO(name << ", m = " << m);
      for (double ridge : {0.0, 0.5}) {
        Eigen::VectorXd x = Eigen::VectorXd::Zero(m);
        REQUIRE(solve(A.data(), m, ridge, b.data(), x.data()));
        const Eigen::VectorXd residual = (A + ridge * Eigen::MatrixXd::Identity(m, m)) * x - b;
        CHECK(residual.norm() <= 1e-10 * b.norm());
      }
      Eigen::VectorXd untouched = Eigen::VectorXd::Constant(m, 7);
      CHECK_FALSE(solve(indefinite.data(), m, 0, b.data(), untouched.data()));
      CHECK(untouched == Eigen::VectorXd::Constant(m, 7));
    };
    check(&detail::cholesky_solve_baseline, "baseline");
    check(&detail::cholesky_solve, detail::dense_kernels_name());
    if (detail::dense_kernels_have_avx2_fma()) check(&detail::cholesky_solve_avx2_fma, "avx2+fma");
  }
}

TEST_CASE("the Hessian's dense products: both builds (baseline, AVX2 + FMA) against a naive sum", "[newton]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const auto& [rows, m] : {std::pair<long, long>{7, 5}, {300, 40}, {1000, 152}}) {
    using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    RowMatrix C(rows, m), W(rows, 3 * m);
    for (Eigen::Index i = 0; i < C.size(); ++i) C.data()[i] = u(rng);
    for (Eigen::Index i = 0; i < W.size(); ++i) W.data()[i] = u(rng);
    Eigen::MatrixXd naive = Eigen::MatrixXd::Zero(m, 3 * m);
    for (long r = 0; r < rows; ++r)
      for (long i = 0; i < m; ++i)
        for (long j = 0; j < 3 * m; ++j) naive(i, j) += C(r, i) * W(r, j);
    const Eigen::MatrixXd start = Eigen::MatrixXd::Constant(m, 3 * m, 0.5);  // it adds to P
    auto check = [&](void (*kernel)(const double*, const double*, long, long, double*), const char* name) {
      Eigen::MatrixXd P = start;
      kernel(C.data(), W.data(), rows, m, P.data());
      INFO(name << ", " << rows << " rows, m = " << m);
      for (long j = 0; j < 3 * m; ++j)
        for (long i = 0; i < m; ++i) {
          const bool written = j >= m && j < 2 * m ? true : i >= j % m;  // the first and last blocks: lower triangles
          const double want = written ? naive(i, j) + 0.5 : 0.5;
          REQUIRE(std::abs(P(i, j) - want) <= 1e-12 * (1 + std::abs(want)));
        }
    };
    check(&detail::hessian_accumulate_baseline, "baseline");
    check(&detail::hessian_accumulate, detail::dense_kernels_name());
    if (detail::dense_kernels_have_avx2_fma()) check(&detail::hessian_accumulate_avx2_fma, "avx2+fma");
    else WARN("no AVX2 + FMA build or processor here: only the baseline build is tested");
  }
}

TEST_CASE("assembled projected Hessians are PSD on random states", "[newton]") {
  Fixture fx(test::bar_with_holes(), 400, 0.2);
  for (unsigned seed = 10; seed < 16; ++seed) {
    fx.core->set_targets(fx.metrics_of(fx.perturbed_identity(seed, 0.05)));
    fx.core->set_coefficients(fx.space().T() * fx.perturbed_identity(seed + 100, 0.05));
    for (HessianProjection p : {HessianProjection::Delete, HessianProjection::FullProj, HessianProjection::PartProj}) {
      const Eigen::MatrixXd H = fx.core->hessian(p);
      const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H).eigenvalues();
      INFO(to_string(p) << ": eigenvalues in [" << ev.minCoeff() << ", " << ev.maxCoeff() << "]");
      CHECK(ev.minCoeff() >= -1e-10 * ev.maxCoeff());
    }
  }
}

TEST_CASE("the reduced Hessian is positive definite (Cholesky succeeds) on every asset", "[newton][assets]") {
  for (const auto& path : test::asset_scenes()) {
    INFO(path.filename().string());
    const Scene scene = load_scene(path);
    const auto setup = make_shape_setup(scene, 2000, 0.2);
    auto core = make_cpu_newton_core(setup->D_G, setup->H);
    core->set_coefficients(setup->metric_space.T() * setup->metric_space.reduce(identity_map(setup->cage)).x);
    const Eigen::MatrixXd Hr =
        setup->metric_space.T().transpose() * core->hessian(HessianProjection::PartProj) * setup->metric_space.T();
    CHECK(Eigen::LLT<Eigen::MatrixXd>(Hr).info() == Eigen::Success);
  }
}

TEST_CASE("max safe step is where a sample first reaches |f_z| = |f_zbar|", "[newton]") {
  Fixture fx(test::annulus());
  const Eigen::VectorXd x = fx.perturbed_identity(20, 0.01);
  fx.core->set_coefficients(fx.space().T() * x);
  std::mt19937 rng(21);
  std::normal_distribution<double> g(0, 1);
  Eigen::VectorXd d(x.size());
  for (Eigen::Index i = 0; i < d.size(); ++i) d(i) = g(rng);
  fx.core->set_direction(fx.space().T() * d);
  const double s = fx.core->max_safe_step();
  REQUIRE(std::isfinite(s));
  auto min_gap = [&](double t) {
    const MapValues v = evaluate_map(evaluate_basis(fx.setup.cage, fx.setup.G.points, kBasisD), fx.space().expand(x + t * d));
    return (v.f_z.cwiseAbs() - v.fzbar_conj.cwiseAbs()).minCoeff();
  };
  CHECK(min_gap(0.999 * s) > 0);
  CHECK(std::abs(min_gap(s)) < 1e-8);
  CHECK(std::isfinite(fx.core->energy_at(0.99 * s)));
  CHECK(std::isinf(fx.core->energy_at(1.01 * s)));
}

TEST_CASE("Newton recovers a map from its own metric (energy 2, same map up to rigid motion)", "[newton]") {
  for (const Shape& s : {test::annulus(), test::bar_with_holes()}) {
    Fixture fx(s, 1000, 1.0);
    const Eigen::VectorXd x_star = fx.perturbed_identity(30, 0.03);
    REQUIRE(fx.setup.certifier.certify(fx.space().expand(x_star)).certified);
    fx.core->set_targets(fx.metrics_of(x_star));
    const Eigen::VectorXd x0 = fx.space().reduce(identity_map(fx.setup.cage)).x;
    NewtonOptions o;
    o.tolerance = 1e-12;
    const NewtonResult r = newton_solve(*fx.core, fx.space(), &fx.setup.certifier, nullptr, x0, o);
    INFO(r.message << ", iterations " << r.iterations << ", energy " << r.energy);
    CHECK(r.converged);
    CHECK(r.certified);
    CHECK(r.iterations <= 25);
    CHECK(r.energy == Approx(2.0).epsilon(1e-9));
    // The metric fixes the map up to a rigid motion. The coefficients themselves are
    // only weakly identifiable (near-null directions of the Cauchy basis), so compare
    // maps, not coefficients: a least-squares rigid fit at interior points.
    const auto pts = test::interior_points(s, 300);
    const VectorXcd fa = evaluate_map(fx.setup.cage, fx.space().expand(r.x), pts).f;
    const VectorXcd fb = evaluate_map(fx.setup.cage, fx.space().expand(x_star), pts).f;
    const cd ma = fa.mean(), mb = fb.mean();
    const cd dot = ((fa.array() - ma) * (fb.array() - mb).conjugate()).sum();
    const cd R = dot / std::abs(dot);
    CHECK(((fa.array() - ma) - R * (fb.array() - mb)).abs().maxCoeff() < 1e-5 * bounding_box(s).diagonal());
    // Quadratic convergence: the last steps are full Newton steps.
    CHECK(r.log.back().step == 1.0);
  }
}

TEST_CASE("Newton refuses to start from a folded map", "[newton]") {
  Fixture fx(test::annulus());
  HarmonicMap m = identity_map(fx.setup.cage);
  // f = w + 1.5 conj(w): orientation-reversing, |f_zbar| > |f_z| everywhere.
  m = affine_map(fx.setup.cage, 1.0, 1.5, 0.0);
  const Eigen::VectorXd x0 = fx.space().reduce(m).x;
  const NewtonResult r = newton_solve(*fx.core, fx.space(), &fx.setup.certifier, nullptr, x0, {});
  CHECK(r.iterations == 0);
  CHECK_FALSE(r.converged);
  CHECK_THAT(r.message, Catch::Matchers::Contains("folds") || Catch::Matchers::Contains("not certified"));
}

// NewtonStepper::decrement then direction() (the loop's exact systems) against solve():
// the decrement to round-off, then the same direction, trial energies and point.
TEST_CASE("the host stepper's split solve gives solve()'s system", "[newton]") {
  for (const Shape& s : {test::annulus(), test::bar_with_holes()}) {
    const ShapeSetup setup(s, build_cage(s), 1000, 0.3);
    const MapSpace& space = setup.metric_space;
    const Eigen::VectorXd id = space.reduce(identity_map(setup.cage)).x;
    Fixture fx(s, 1000, 0.3);
    const Eigen::VectorXd x_star = fx.perturbed_identity(30, 0.03);
    const std::vector<Metric> targets = fx.metrics_of(x_star);
    auto make = [&] {
      test::CoreStepper m;
      m.core = make_cpu_newton_core(setup.D_G, setup.H);
      m.core->set_targets(targets);
      m.stepper = make_host_stepper(*m.core, space, &setup.certifier, nullptr);
      return m;
    };
    // Near the map the targets come from (5 % of the way to the identity): the exact
    // system is definite there.
    const test::SplitCounts c = test::check_split_solve(make, x_star + 0.05 * (id - x_star));
    CHECK(c.factored >= 3);
    CHECK(c.split == c.factored);  // the host stepper splits every solve but a kept factor's
  }
}
