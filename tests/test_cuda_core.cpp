// The CUDA Newton core against the CPU reference: its per-sample math (compiled for
// the host, no GPU needed), then energy, gradient, Hessians, safe step and line-search
// energies on every bundled asset, and a warm-started interpolation sequence. Tests that
// need a GPU skip with a warning where there is none, so CI without one passes.
#include <catch2/catch.hpp>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>

#include <cuda_runtime.h>

#include <array>
#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <thread>

#include "hsi/cuda/certifier.h"
#include "hsi/cuda/mesh_evaluator.h"
#include "cuda_test.h"
#include "hsi/cuda/newton_core.h"
#include "device.h"
#include "dense_cholesky.h"
#include "device_certifier.h"
#include "newton_kernels.h"
#include "sample_math.cuh"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/newton.h"
#include "hsi/shape_setup.h"
#include "frame_compare.h"
#include "split_solve.h"
#include "test_shapes.h"
#include "test_targets.h"

using namespace hsi;
namespace sm = hsi::cuda::sample;

namespace {

constexpr HessianProjection kProjections[] = {HessianProjection::Delete, HessianProjection::FullProj, HessianProjection::PartProj};

sm::Projection to_sample(HessianProjection p) {
  switch (p) {
    case HessianProjection::Delete: return sm::Projection::Delete;
    case HessianProjection::FullProj: return sm::Projection::FullProj;
    case HessianProjection::PartProj: return sm::Projection::PartProj;
  }
  return sm::Projection::PartProj;
}

// A scene's keyframe times and maps, as an Interpolator takes them.
struct SceneKeys {
  std::vector<double> times;
  std::vector<HarmonicMap> maps;
};
SceneKeys scene_keys(const Scene& scene) {
  SceneKeys keys;
  for (const Keyframe& k : scene.keyframes) {
    REQUIRE(k.coefficients.has_value());
    keys.times.push_back(k.time);
    keys.maps.push_back(*k.coefficients);
  }
  return keys;
}

double rel_diff(double got, double want) { return std::abs(got - want) / std::max(std::abs(want), 1e-300); }
double rel_diff(const Eigen::MatrixXd& got, const Eigen::MatrixXd& want) {
  return (got - want).cwiseAbs().maxCoeff() / std::max(want.cwiseAbs().maxCoeff(), 1e-300);
}

// Random sample states near the identity and targets of all sizes (so that the
// projections have negative eigenvalues to clip).
struct SampleCase {
  double g[3];
  cd a, b;
};
std::vector<SampleCase> random_sample_cases(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), scale(0.25, 4.0);
  std::vector<SampleCase> out;
  while (static_cast<int>(out.size()) < count) {
    const cd a(1 + 0.5 * u(rng), 0.5 * u(rng)), b(0.4 * u(rng), 0.4 * u(rng));
    const cd ga(1 + 0.5 * u(rng), 0.5 * u(rng)), gb(0.4 * u(rng), 0.4 * u(rng));
    if (std::abs(b) >= 0.9 * std::abs(a) || std::abs(gb) >= 0.9 * std::abs(ga)) continue;
    const Metric m = scale(rng) * pullback_metric(ga, gb);
    out.push_back({{m(0), m(1), m(2)}, a, b});
  }
  return out;
}

// A scene's setup and the two cores over the same samples.
struct AssetCores {
  Scene scene;
  std::unique_ptr<ShapeSetup> setup;
  std::unique_ptr<NewtonCore> cpu, gpu;
  explicit AssetCores(const std::filesystem::path& path) : scene(load_scene(path)), setup(make_shape_setup(scene, 2000, 0.2)) {
    cpu = make_cpu_newton_core(setup->D_G, setup->H);
    gpu = hsi::cuda::make_newton_core(setup->D_G, setup->H);
  }
  const MapSpace& space() const { return setup->metric_space; }
  // The identity plus Gaussian noise, halved until no sample of G folds.
  Eigen::VectorXd perturbed_identity(unsigned seed, double amp) {
    const Eigen::VectorXd x0 = space().reduce(identity_map(setup->cage)).x;
    for (; amp > 1e-8; amp /= 2) {
      const Eigen::VectorXd x = test::perturbed(x0, seed, amp);
      cpu->set_targets(std::vector<Metric>(setup->G.size(), Metric(1, 0, 1)));
      cpu->set_coefficients(space().T() * x);
      if (std::isfinite(cpu->energy())) return x;
    }
    return x0;
  }
  std::vector<Metric> metrics_of(const Eigen::VectorXd& x) const { return test::metrics_of(*setup, x); }
};

}  // namespace

// ---------------------------------------------------------------------------------
// The per-sample math of the kernels, compiled for the host: no GPU needed.

TEST_CASE("CUDA per-sample math matches the CPU energy, gradient and projected Hessians", "[cuda][host]") {
  double worst_e = 0, worst_g = 0, worst_h = 0;
  for (const SampleCase& c : random_sample_cases(400, 11)) {
    const Metric g(c.g[0], c.g[1], c.g[2]);
    const double e = sm::isometric_energy(c.g, c.a.real(), c.a.imag(), c.b.real(), c.b.imag());
    worst_e = std::max(worst_e, rel_diff(e, isometric_energy(g, c.a, c.b)));
    for (int mode = 0; mode < 4; ++mode) {  // the three projections, then exact
      const bool exact = mode == 3;
      const HessianProjection p = kProjections[exact ? 2 : mode];
      const SampleDerivatives want = isometric_derivatives(g, c.a, c.b, p, exact);
      const sm::Derivatives got = sm::isometric_derivatives(c.g, c.a.real(), c.a.imag(), c.b.real(), c.b.imag(), to_sample(p), exact, true);
      Eigen::Vector4d grad;
      Eigen::Matrix4d hess;
      for (int r = 0; r < 4; ++r) {
        grad(r) = got.grad[r];
        for (int k = 0; k < 4; ++k) hess(r, k) = got.hess.m[r][k];
      }
      worst_g = std::max(worst_g, (grad - want.grad).cwiseAbs().maxCoeff() / want.grad.cwiseAbs().maxCoeff());
      INFO(to_string(p) << (exact ? " (exact)" : ""));
      worst_h = std::max(worst_h, rel_diff(hess, want.hess));
    }
  }
  INFO("worst relative differences: energy " << worst_e << ", gradient " << worst_g << ", Hessian " << worst_h);
  CHECK(worst_e < 1e-13);
  CHECK(worst_g < 1e-12);
  CHECK(worst_h < 1e-11);
}

TEST_CASE("CUDA per-sample math: folded samples, clipped projections, Jacobi eigenvalues", "[cuda][host]") {
  // Folded or degenerate: +inf energy and zero derivatives, as on the CPU.
  const double g[3] = {1, 0, 1};
  CHECK(std::isinf(sm::isometric_energy(g, 0.5, 0, 0.6, 0)));
  CHECK(std::isinf(sm::isometric_energy(g, 0.5, 0, 0.5, 0)));
  const double bad_g[3] = {1, 2, 1};
  CHECK(std::isinf(sm::isometric_energy(bad_g, 1, 0, 0, 0)));
  const sm::Derivatives d = sm::isometric_derivatives(g, 0.5, 0, 0.6, 0, sm::Projection::PartProj, false, true);
  CHECK(std::isinf(d.e));
  CHECK(d.grad[0] == 0);
  CHECK(d.hess.m[1][1] == 0);
  // The PartProj cases of Eq. 21 (all of K1 kept, clipped, zero) against the CPU.
  for (const Eigen::Vector3d& alpha : {Eigen::Vector3d(2, 0.5, 1), Eigen::Vector3d(1, 3, 0.5), Eigen::Vector3d(-1, 0.1, -2)}) {
    const double al[3] = {alpha(0), alpha(1), alpha(2)};
    const sm::Mat4 P = sm::project_K1(al);
    const Eigen::Matrix4d want = project_K1(alpha);
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) CHECK(P.m[r][c] == Approx(want(r, c)).margin(1e-14));
  }
  // Jacobi against Eigen on random symmetric matrices.
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 1);
  for (int t = 0; t < 50; ++t) {
    Eigen::Matrix4d A;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c <= r; ++c) A(r, c) = A(c, r) = n(rng) * (t % 5 == 0 ? 1e-6 : 1.0);
    sm::Mat4 M, V;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) M.m[r][c] = A(r, c);
    double w[4];
    sm::symmetric_eigen4(M, w, V);
    Eigen::Vector4d lam(w[0], w[1], w[2], w[3]);
    Eigen::Matrix4d Vm;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) Vm(r, c) = V.m[r][c];
    CHECK((Vm * lam.asDiagonal() * Vm.transpose() - A).cwiseAbs().maxCoeff() < 1e-14 * A.cwiseAbs().maxCoeff());
    CHECK((Vm.transpose() * Vm - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff() < 1e-14);
    std::sort(lam.data(), lam.data() + 4);
    const Eigen::Vector4d want = Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(A).eigenvalues();
    CHECK((lam - want).cwiseAbs().maxCoeff() < 1e-14 * want.cwiseAbs().maxCoeff());
  }
}

TEST_CASE("CUDA per-sample safe step is the first root of |a + s da| = |b + s db|", "[cuda][host]") {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  int finite = 0;
  for (int t = 0; t < 200; ++t) {
    const cd a(1 + 0.2 * n(rng), 0.2 * n(rng)), b(0.2 * n(rng), 0.2 * n(rng)), da(n(rng), n(rng)), db(n(rng), n(rng));
    const double s = sm::first_fold_step(a.real(), a.imag(), b.real(), b.imag(), da.real(), da.imag(), db.real(), db.imag());
    auto gap = [&](double u) { return std::abs(a + u * da) - std::abs(b + u * db); };
    REQUIRE(s > 0);
    if (std::isinf(s)) {
      for (double u : {0.5, 1.0, 10.0, 1e3}) CHECK(gap(u) > 0);
      continue;
    }
    ++finite;
    CHECK(std::abs(gap(s)) < 1e-10 * (std::abs(a) + s * std::abs(da)));
    for (double f : {0.25, 0.5, 0.9, 0.999}) CHECK(gap(f * s) > 0);
  }
  CHECK(finite > 50);
}

TEST_CASE("CUDA core refuses inconsistent input before touching the device", "[cuda][host]") {
  const MatrixXcd D = MatrixXcd::Ones(10, 3);
  CHECK_THROWS_AS(hsi::cuda::make_newton_core(D, {0, 10}), InputError);
  CHECK_THROWS_AS(hsi::cuda::make_newton_core(D, {-1}), InputError);
  CHECK_THROWS_AS(hsi::cuda::make_newton_core(D, {}), InputError);
  CHECK_THROWS_AS(hsi::cuda::make_newton_core(MatrixXcd(0, 3), {0}), InputError);
  std::string why;
  const bool ok = hsi::cuda::device_available(&why);  // never throws, always says something
  CHECK(!why.empty());
  INFO("device_available: " << ok << ", " << why);
  SUCCEED();
}

// ---------------------------------------------------------------------------------
// On the GPU.

TEST_CASE("CUDA core matches the CPU core on every asset", "[cuda]") {
  HSI_REQUIRE_GPU();
  double worst_e = 0, worst_g = 0, worst_h = 0, worst_s = 0;  // reported with HSI_TEST_REPORT=1
  for (const auto& path : test::asset_scenes()) {
    INFO(path.filename().string());
    AssetCores ac(path);
    NewtonCore& cpu = *ac.cpu;
    NewtonCore& gpu = *ac.gpu;
    REQUIRE(gpu.n() == cpu.n());
    CHECK(std::string(gpu.name()) == "cuda");
    const auto& T = ac.space().T();
    for (unsigned seed : {1u, 2u}) {
      INFO("seed " << seed);
      const std::vector<Metric> targets = ac.metrics_of(ac.perturbed_identity(seed, 0.02));
      const Eigen::VectorXd x = ac.perturbed_identity(seed + 100, 0.02);
      for (NewtonCore* c : {&cpu, &gpu}) {
        c->set_targets(targets);
        c->set_coefficients(T * x);
      }
      const double E = cpu.energy();
      REQUIRE(std::isfinite(E));
      worst_e = std::max(worst_e, rel_diff(gpu.energy(), E));
      CHECK(rel_diff(gpu.energy(), E) < 1e-10);
      const Eigen::VectorXd gc = cpu.gradient(), gg = gpu.gradient();
      REQUIRE(gg.size() == gc.size());
      worst_g = std::max(worst_g, (gg - gc).cwiseAbs().maxCoeff() / gc.cwiseAbs().maxCoeff());
      CHECK((gg - gc).cwiseAbs().maxCoeff() < 1e-10 * gc.cwiseAbs().maxCoeff());
      for (int mode = 0; mode < 4; ++mode) {
        const bool exact = mode == 3;
        const HessianProjection p = kProjections[exact ? 2 : mode];
        INFO(to_string(p) << (exact ? " (exact)" : ""));
        const Eigen::MatrixXd Hc = cpu.hessian(p, exact), Hg = gpu.hessian(p, exact);
        REQUIRE(Hg.rows() == Hc.rows());
        REQUIRE(Hg.cols() == Hc.cols());
        worst_h = std::max(worst_h, rel_diff(Hg, Hc));
        CHECK(rel_diff(Hg, Hc) < 1e-9);
        CHECK(Hg == Hg.transpose());
        // The Hessian without forming it (NewtonCore::hessian_times), over H and over G.
        std::mt19937 prng(seed + 11u * static_cast<unsigned>(mode));
        std::normal_distribution<double> pd(0, 1);
        Eigen::VectorXd pv(Hc.rows());
        for (Eigen::Index i = 0; i < pv.size(); ++i) pv(i) = pd(prng);
        for (bool all : {false, true}) {
          INFO((all ? "over G" : "over H"));
          const Eigen::VectorXd ref = cpu.hessian(p, exact, all) * pv;
          const Eigen::VectorXd hg = gpu.hessian_times(p, exact, all, pv);
          REQUIRE(hg.size() == ref.size());
          worst_h = std::max(worst_h, (hg - ref).cwiseAbs().maxCoeff() / ref.cwiseAbs().maxCoeff());
          CHECK((hg - ref).cwiseAbs().maxCoeff() < 1e-10 * ref.cwiseAbs().maxCoeff());
        }
        // A vector of the wrong size: an InputError naming both sizes, before any launch.
        CHECK_THROWS_WITH(gpu.hessian_times(p, exact, true, Eigen::VectorXd::Ones(3)),
                          Catch::Contains("3 entries") && Catch::Contains(std::to_string(Hc.rows())));
      }
      // The line-search pieces along a random direction.
      std::mt19937 rng(seed + 7);
      std::normal_distribution<double> nd(0, 0.05);
      Eigen::VectorXd d(x.size());
      for (Eigen::Index i = 0; i < d.size(); ++i) d(i) = nd(rng);
      for (NewtonCore* c : {&cpu, &gpu}) c->set_direction(T * d);
      const double sc = cpu.max_safe_step(), sg = gpu.max_safe_step();
      INFO("max safe step: cpu " << sc << ", cuda " << sg);
      if (std::isinf(sc)) CHECK(std::isinf(sg));
      else {
        worst_s = std::max(worst_s, rel_diff(sg, sc));
        CHECK(rel_diff(sg, sc) < 1e-10);
      }
      const double s_mid = std::isfinite(sc) ? 0.5 * sc : 0.5;
      CHECK(rel_diff(gpu.energy_at(s_mid), cpu.energy_at(s_mid)) < 1e-10);
      CHECK(rel_diff(gpu.energy_at(0.01 * s_mid), cpu.energy_at(0.01 * s_mid)) < 1e-10);
      CHECK(gpu.energy_at(0.0) == gpu.energy());
      if (std::isfinite(sc)) {
        CHECK(std::isinf(cpu.energy_at(1.01 * sc)));
        CHECK(std::isinf(gpu.energy_at(1.01 * sc)));
      }
    }
  }
  if (std::getenv("HSI_TEST_REPORT"))
    std::printf("CUDA vs CPU, worst relative differences over the assets: energy %.2e, gradient %.2e, Hessian %.2e, safe step %.2e\n",
                worst_e, worst_g, worst_h, worst_s);
}

TEST_CASE("CUDA core results are deterministic and its initial state is defined", "[cuda]") {
  HSI_REQUIRE_GPU();
  AssetCores ac(test::asset_scenes().front());
  NewtonCore& gpu = *ac.gpu;
  CHECK(std::isinf(gpu.energy()));  // a = b = 0 until coefficients are set
  gpu.set_coefficients(ac.space().T() * ac.perturbed_identity(4, 0.02));
  CHECK(std::isfinite(gpu.energy()));
  CHECK(gpu.energy() == gpu.energy());
  const Eigen::VectorXd g1 = gpu.gradient(), g2 = gpu.gradient();
  CHECK(g1 == g2);
  const Eigen::MatrixXd H1 = gpu.hessian(HessianProjection::PartProj), H2 = gpu.hessian(HessianProjection::PartProj);
  CHECK(H1 == H2);
  CHECK(std::isinf(gpu.max_safe_step()));  // zero direction until set
  CHECK_THROWS_AS(gpu.set_coefficients(Eigen::VectorXd::Zero(3)), InputError);
  CHECK_THROWS_AS(gpu.set_targets(std::vector<Metric>(3, Metric(1, 0, 1))), InputError);
  // The projected Hessian is PSD, as the CPU one is.
  const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H1).eigenvalues();
  CHECK(ev.minCoeff() >= -1e-10 * ev.maxCoeff());
}

// The launches that replaced cuBLAS GEMVs, copies and two-pass reductions in the device
// loop (issue #23: under load a frame costs about its count of small launches):
// tall_times_one with each option against Eigen, copy, and the one-launch reductions'
// counter, which must be back at 0 after every launch (else the next launch's last
// block is never found and its result never written).
TEST_CASE("the one-launch kernels: real products, copies, reductions run again and again", "[cuda][small]") {
  HSI_REQUIRE_GPU();
  namespace k = hsi::cuda::kernels;
  using hsi::cuda::DeviceArray;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  auto random = [&](Eigen::Index r, Eigen::Index c) {
    Eigen::MatrixXd m(r, c);
    for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = u(rng);
    return m;
  };
  auto up = [](const Eigen::MatrixXd& m) {
    DeviceArray<double> d(static_cast<size_t>(m.size()));
    REQUIRE(cudaMemcpy(d.get(), m.data(), d.bytes(), cudaMemcpyHostToDevice) == cudaSuccess);
    return d;
  };
  auto down = [](const DeviceArray<double>& d, Eigen::Index r) {
    Eigen::VectorXd v(r);
    REQUIRE(cudaMemcpy(v.data(), d.get(), static_cast<size_t>(r) * sizeof(double), cudaMemcpyDeviceToHost) == cudaSuccess);
    return v;
  };
  for (const auto& [rows, cols, rows2] : std::vector<std::array<int, 3>>{{1, 1, 1}, {31, 7, 65}, {304, 293, 304}, {700, 40, 33}}) {
    INFO(rows << " x " << cols << ", second " << rows2);
    const Eigen::MatrixXd A = random(rows, cols), A2 = random(rows2, cols), x0 = random(cols, 1), dx = random(cols, 1),
                          y0 = random(rows, 1);
    const Eigen::MatrixXd step = Eigen::MatrixXd::Constant(1, 1, 0.375);
    DeviceArray<double> dA = up(A), dA2 = up(A2), dx0 = up(x0), ddx = up(dx), dy0 = up(y0), dstep = up(step);
    DeviceArray<double> y(static_cast<size_t>(rows)), y2(static_cast<size_t>(rows2)), xc(static_cast<size_t>(cols));
    // Plain: y = A x0.
    REQUIRE(k::tall_times_one(rows, cols, dA.get(), dx0.get(), y.get(), nullptr) == cudaSuccess);
    REQUIRE(cudaDeviceSynchronize() == cudaSuccess);
    CHECK((down(y, rows) - A * x0).cwiseAbs().maxCoeff() <= 1e-13 * cols);
    // Every option: y = y0 + A x, y2 = A2 x, x = x0 + s dx copied out.
    k::TallOptions o;
    o.y0 = dy0.get();
    o.dx = ddx.get();
    o.step = dstep.get();
    o.x_copy = xc.get();
    o.second_A = dA2.get();
    o.second_rows = rows2;
    o.second_y = y2.get();
    REQUIRE(k::tall_times_one(rows, cols, dA.get(), dx0.get(), y.get(), nullptr, o) == cudaSuccess);
    REQUIRE(cudaDeviceSynchronize() == cudaSuccess);
    const Eigen::VectorXd x = x0 + 0.375 * dx;
    CHECK((down(xc, cols) - x).cwiseAbs().maxCoeff() <= 1e-15);  // x0 + s dx (a fused multiply-add or not)
    CHECK((down(y, rows) - (y0 + A * x)).cwiseAbs().maxCoeff() <= 1e-13 * cols);
    CHECK((down(y2, rows2) - A2 * x).cwiseAbs().maxCoeff() <= 1e-13 * cols);
    // The same call again: the same bits.
    const Eigen::VectorXd first = down(y, rows);
    REQUIRE(k::tall_times_one(rows, cols, dA.get(), dx0.get(), y.get(), nullptr, o) == cudaSuccess);
    REQUIRE(cudaDeviceSynchronize() == cudaSuccess);
    CHECK(down(y, rows) == first);
  }
  {  // Four copies of different lengths in one launch, a fifth refused.
    const Eigen::MatrixXd a = random(5, 1), b = random(3000, 1), c = random(1, 1), d = random(300, 1);
    DeviceArray<double> da = up(a), db = up(b), dc = up(c), dd = up(d);
    DeviceArray<double> oa(5), ob(3000), oc(1), od(300);
    k::CopyList list;
    list.entry[0] = {da.get(), oa.get(), 5};
    list.entry[1] = {db.get(), ob.get(), 3000};
    list.entry[2] = {dc.get(), oc.get(), 1};
    list.entry[3] = {dd.get(), od.get(), 300};
    REQUIRE(k::copy(list, 4, nullptr) == cudaSuccess);
    REQUIRE(cudaDeviceSynchronize() == cudaSuccess);
    CHECK(down(oa, 5) == a);
    CHECK(down(ob, 3000) == b);
    CHECK(down(oc, 1) == c);
    CHECK(down(od, 300) == d);
    CHECK(k::copy(list, 5, nullptr) == cudaErrorInvalidValue);
  }
  // The reductions through the core's per-call interface (one counter per core): many
  // energies and safe steps in a row, each equal to the CPU core's, at |G| = 2,000 (8
  // blocks) on two assets.
  for (const auto& path : {test::asset_scenes().front(), test::asset_scenes().back()}) {
    AssetCores ac(path);
    for (unsigned seed = 0; seed < 6; ++seed) {
      INFO(path.filename().string() << ", seed " << seed);
      // (perturbed_identity sets the CPU core's targets and coefficients: all three first)
      const Eigen::VectorXd x = ac.perturbed_identity(seed, 0.02), dv = 0.1 * ac.perturbed_identity(seed + 100, 0.02);
      const std::vector<Metric> targets = ac.metrics_of(ac.perturbed_identity(seed + 50, 0.01));
      for (NewtonCore* c : {ac.cpu.get(), ac.gpu.get()}) {
        c->set_targets(targets);
        c->set_coefficients(ac.space().T() * x);
        c->set_direction(ac.space().T() * dv);
      }
      const double E = ac.cpu->energy(), sc = ac.cpu->max_safe_step(), s = std::isfinite(sc) ? 0.5 * sc : 0.5;
      const double Es = ac.cpu->energy_at(s);
      const double E1 = ac.gpu->energy(), Es1 = ac.gpu->energy_at(s), sg1 = ac.gpu->max_safe_step();
      CHECK(rel_diff(E1, E) < 1e-10);
      CHECK(rel_diff(Es1, Es) < 1e-10);
      if (std::isinf(sc)) CHECK(std::isinf(sg1));
      else CHECK(rel_diff(sg1, sc) < 1e-10);
      for (int rep = 0; rep < 3; ++rep) {  // again and again: the same bits
        CHECK(ac.gpu->energy() == E1);
        CHECK(ac.gpu->energy_at(s) == Es1);
        CHECK(ac.gpu->max_safe_step() == sg1);
      }
    }
  }
}

namespace {
// Interpolates `frames` frames of a bundled scene with the CPU core and with the CUDA
// core running whole solves on the device, and compares them frame by frame.
// Both with the same exact_samples (the default, Auto, differs by core: Subset on the
// CPU, All on CUDA).
void compare_sequences(const std::filesystem::path& path, int frames, int samples, ExactSamples exact) {
  INFO(path.filename().string() << ", " << frames << " frames, |G| = " << samples << ", exact systems over " << to_string(exact));
  const Scene scene = load_scene(path);
  const auto setup = make_shape_setup(scene, samples, 0.2);
  const auto [times, maps] = scene_keys(scene);
  InterpolationOptions o;
  o.exact_samples = exact;
  Interpolator cpu(*setup, times, maps, o);
  Interpolator gpu(*setup, times, maps, o, hsi::cuda::make_newton_core(*setup));
  REQUIRE(std::string(gpu.core().name()) == "cuda");
  const auto fc = cpu.sequence(frames), fg = gpu.sequence(frames);
  REQUIRE(fc.size() == fg.size());
  const auto pts = test::interior_points(setup->shape, 200);
  const BasisRows rows = evaluate_basis(setup->cage, pts, kBasisC);
  int same_iterations = 0;
  double worst = 0;
  for (size_t i = 0; i < fc.size(); ++i) {
    INFO("frame " << i << ", t = " << fc[i].t << ": cpu " << fc[i].message << " (" << fc[i].iterations << " its), cuda "
                  << fg[i].message << " (" << fg[i].iterations << " its)");
    CHECK(fg[i].certified == fc[i].certified);
    CHECK(fg[i].certified);
    // Coarse sequences (few frames) have frames that stop at the iteration limit: the
    // GPU must stop where the CPU does.
    CHECK(fg[i].converged == fc[i].converged);
    CHECK(std::abs(fg[i].iterations - fc[i].iterations) <= 1);
    same_iterations += fg[i].iterations == fc[i].iterations;
    // Both stop within the tolerance of the minimum (relative 5e-8: 1e-7 at E = 2), not
    // at one point: where a threshold decision (a stopping test, whether the exact system
    // factors) fell the other way by round-off the two paths part, and on a shape with
    // soft modes (blob, H100: energies 2e-8 apart) the maps then differ by up to ~1e-4
    // of the size. Same path: the same map to round-off.
    const InterpolationOptions defaults;
    CHECK(std::abs(fg[i].energy - fc[i].energy) <= 2 * defaults.tolerance * fc[i].energy);
    const double dist = (evaluate_map(rows, fg[i].map).f - evaluate_map(rows, fc[i].map).f).cwiseAbs().maxCoeff();
    worst = std::max(worst, dist / setup->size);
    CHECK(dist < 1e-3 * setup->size);
    // The certificate's bounds follow its subdivision, which moves with the map: maps 4.5e-5
    // of the size apart (blob) gave bounds 3e-4 apart; the same map gives the same bounds.
    CHECK(fg[i].certificate.sigma2_min == Approx(fc[i].certificate.sigma2_min).epsilon(1e-3));
    CHECK(fg[i].certificate.k_max == Approx(fc[i].certificate.k_max).epsilon(1e-3));
  }
  std::printf("[cuda] %s: %d frames, exact systems over %s, equal iteration counts in %d, largest map difference %.2e of the size\n",
              path.filename().string().c_str(), frames, to_string(exact), same_iterations, worst);
  // The loop's decisions at a threshold (the stopping tests at the tolerance, whether
  // the exact system factors) can fall either way by round-off: on the H100, blob took
  // one iteration more or less in 4 of 40 frames (maps 1.5e-7 of the size apart). Each
  // frame is held above (|Δ iterations| ≤ 1, same flags, maps close); most must match.
  CHECK(same_iterations >= frames - frames / 5);
}
}  // namespace

// The paper's |G| = 10,000 and r = 20%: few iterations per frame. With few samples
// some frames need tens of slow iterations, and where the stopping test (a relative
// decrease below the tolerance) then falls is decided by round-off: no frame-by-frame match.
TEST_CASE("a 500-frame sequence solved on the GPU matches the CPU one frame by frame", "[cuda][sequence]") {
  HSI_REQUIRE_GPU();
  for (const auto& p : test::asset_scenes())
    if (p.filename() == "two_holes.json")
      for (const ExactSamples e : {ExactSamples::Subset, ExactSamples::All}) compare_sequences(p, 500, 10000, e);
}

TEST_CASE("sequences solved on the GPU match the CPU on every bundled scene", "[cuda][sequence]") {
  HSI_REQUIRE_GPU();
  for (const auto& p : test::asset_scenes())
    for (const ExactSamples e : {ExactSamples::Subset, ExactSamples::All}) compare_sequences(p, 40, 10000, e);
}

namespace {

// An asset's keyframe maps, then each keyframe with its vertex coefficients perturbed by
// Gaussian noise at each amplitude (relative to its largest |φ|; seeded), then an affine
// map with |f_zbar| > |f_z|, which reverses orientation: maps on both sides of the fold
// boundary for the certificate tests.
std::vector<HarmonicMap> certificate_test_maps(const AssetCores& ac, std::initializer_list<double> amplitudes, unsigned seed) {
  std::vector<HarmonicMap> maps;
  for (const Keyframe& k : ac.scene.keyframes)
    if (k.coefficients) maps.push_back(*k.coefficients);
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  const size_t keys = maps.size();
  for (size_t k = 0; k < keys; ++k)
    for (double amp : amplitudes) {
      HarmonicMap m = maps[k];
      const double scale = amp * m.phi.cwiseAbs().maxCoeff();
      for (Eigen::Index j = 0; j < m.phi.size() - ac.setup->cage.hole_count(); ++j) {
        m.phi(j) += scale * cd(g(rng), g(rng));
        m.psi(j) += scale * cd(g(rng), g(rng));
      }
      maps.push_back(m);
    }
  maps.push_back(affine_map(ac.setup->cage, 0.5, 1.0, 0));
  return maps;
}

}  // namespace

TEST_CASE("the GPU certificate agrees with the CPU certificate", "[cuda][certify]") {
  HSI_REQUIRE_GPU();
  int certified = 0, refused = 0;
  for (const auto& path : test::asset_scenes()) {
    INFO(path.filename().string());
    AssetCores ac(path);
    hsi::cuda::Certifier gpu(*ac.setup);
    // Random coefficient perturbations of the keyframes, swept across the fold
    // boundary (small ones certify, large ones fold), plus an orientation reversal.
    const std::vector<HarmonicMap> maps = certificate_test_maps(ac, {1e-3, 1e-2, 3e-2, 1e-1, 3e-1}, 11);
    for (size_t i = 0; i < maps.size(); ++i) {
      INFO("map " << i);
      const CertificateResult c = ac.setup->certifier.certify(maps[i]);
      const CertificateResult d = gpu.certify(maps[i]);
      CHECK(d.certified == c.certified);
      CHECK(d.reason == c.reason);
      CHECK(d.fail_loop == c.fail_loop);
      CHECK(d.fail_edge == c.fail_edge);
      CHECK(d.winding == c.winding);
      CHECK(d.segments == c.segments);
      CHECK(std::abs(d.subdivisions - c.subdivisions) <= 2 + c.subdivisions / 100);
      CHECK(d.observed_sigma2_min == Approx(c.observed_sigma2_min).epsilon(1e-9).margin(1e-12));
      if (c.certified) {
        CHECK(d.sigma2_min == Approx(c.sigma2_min).epsilon(1e-9));
        CHECK(d.sigma1_max == Approx(c.sigma1_max).epsilon(1e-9));
        CHECK(d.k_max == Approx(c.k_max).epsilon(1e-9));
      }
      // The line search's early-stopping form gives the same verdict.
      CertificateOptions fast;
      fast.stop_at_first_failure = true;
      CHECK(gpu.certify(maps[i], fast).certified == c.certified);
      (c.certified ? certified : refused)++;
    }
  }
  std::printf("[cuda] certificate: %d maps certified, %d refused, identical verdicts\n", certified, refused);
  CHECK(certified > 0);
  CHECK(refused > 0);
}

// A lockstep batch's certificates (issue #23): several maps of one setup certified in the
// launches one map takes (DeviceCertifier with a capacity) give each map's own verdict.
TEST_CASE("the GPU certificate of a batch of maps gives each map's verdict", "[cuda][certify][lockstep]") {
  HSI_REQUIRE_GPU();
  int maps_checked = 0, same_bits = 0, refused = 0;
  const auto scenes = test::asset_scenes();
  for (size_t si = 0; si < std::min<size_t>(3, scenes.size()); ++si) {
    INFO(scenes[si].filename().string());
    AssetCores ac(scenes[si]);
    // Certified, near the fold boundary and folded perturbations, and a reversal.
    const std::vector<HarmonicMap> maps = certificate_test_maps(ac, {1e-3, 3e-2, 3e-1}, 5);
    const int count = static_cast<int>(maps.size());
    hsi::cuda::Stream stream;
    hsi::cuda::BlasHandle blas(stream);
    hsi::cuda::DeviceCertifier one(*ac.setup, stream, blas);
    hsi::cuda::DeviceCertifier batch(*ac.setup, stream, blas, count + 2);  // room to spare: fewer maps than capacity
    REQUIRE(batch.capacity() == count + 2);
    const int M = batch.coefficient_count();
    std::vector<double2> coef(2 * static_cast<size_t>(M) * static_cast<size_t>(count));
    for (int s = 0; s < count; ++s) {
      REQUIRE(maps[size_t(s)].phi.size() == M);
      for (int j = 0; j < M; ++j) {
        const cd phi = maps[size_t(s)].phi(j), psi = maps[size_t(s)].psi(j);
        coef[size_t(s) * 2 * size_t(M) + size_t(j)] = make_double2(phi.real(), phi.imag());
        coef[size_t(s) * 2 * size_t(M) + size_t(M + j)] = make_double2(psi.real(), psi.imag());
      }
    }
    hsi::cuda::DeviceArray<double2> dcoef(coef.size());
    REQUIRE(cudaMemcpy(dcoef.get(), coef.data(), dcoef.bytes(), cudaMemcpyHostToDevice) == cudaSuccess);
    for (int launch = 0; launch < 2; ++launch) {  // again: the per-map counters were left at 0
      batch.enqueue(dcoef.get(), CertificateOptions{}, count);
      const std::vector<CertificateResult> all = batch.fetch_all(count);
      REQUIRE(all.size() == maps.size());
      for (int s = 0; s < count; ++s) {
        INFO("map " << s << ", launch " << launch);
        const CertificateResult a = one.certify(maps[size_t(s)]), &b = all[size_t(s)];
        CHECK(b.certified == a.certified);
        CHECK(b.reason == a.reason);
        CHECK(b.fail_loop == a.fail_loop);
        CHECK(b.fail_edge == a.fail_edge);
        CHECK(b.winding == a.winding);
        CHECK(b.segments == a.segments);
        CHECK(b.subdivisions == a.subdivisions);
        CHECK(b.observed_sigma1_max == a.observed_sigma1_max);  // from the values alone: the same product
        CHECK(b.observed_sigma2_min == a.observed_sigma2_min);
        if (a.certified) {
          CHECK(b.sigma2_min == Approx(a.sigma2_min).epsilon(1e-13));
          CHECK(b.sigma1_max == Approx(a.sigma1_max).epsilon(1e-13));
          CHECK(b.k_max == Approx(a.k_max).epsilon(1e-13));
          same_bits += b.sigma2_min == a.sigma2_min && b.sigma1_max == a.sigma1_max && b.k_max == a.k_max;
        } else {
          ++refused;
        }
        ++maps_checked;
      }
    }
    CHECK_THROWS_WITH(batch.enqueue(dcoef.get(), CertificateOptions{}, count + 3), Catch::Contains("maps for a certifier of"));
    CHECK_THROWS_WITH(batch.fetch_all(0), Catch::Contains("maps for a certifier of"));
    CHECK_THROWS_WITH(hsi::cuda::DeviceCertifier(*ac.setup, stream, blas, 0), Catch::Contains("a batch of 0 maps"));
  }
  std::printf("[cuda] batched certificate: %d maps against one at a time, %d refused, %d certified with the same bounds bit for bit\n",
              maps_checked, refused, same_bits);
  CHECK(refused > 0);
  CHECK(maps_checked > refused);
}

// The setup core certifies maps for its setup's certifier on the device (an
// Interpolator's keyframes, issue #23), as the device certifier does; for any other
// certifier it leaves the work to the host.
TEST_CASE("a setup core certifies maps on the device for its setup's certifier alone", "[cuda][certify][small]") {
  HSI_REQUIRE_GPU();
  for (const auto& path : test::asset_scenes()) {
    INFO(path.filename().string());
    const Scene scene = load_scene(path);
    const auto setup = make_shape_setup(scene, 2000, 0.2);
    auto core = hsi::cuda::make_newton_core(*setup);
    hsi::cuda::Certifier device(*setup);
    const auto [times, maps] = scene_keys(scene);
    std::vector<HarmonicMap> tried = maps;
    tried.push_back(affine_map(setup->cage, 0.5, 1.0, 0));  // reverses orientation: refused
    for (size_t i = 0; i < tried.size(); ++i) {
      INFO("map " << i);
      const std::optional<CertificateResult> d = core->certify_map(setup->certifier, tried[i]);
      REQUIRE(d.has_value());
      const CertificateResult want = device.certify(tried[i]);
      CHECK(d->certified == want.certified);
      CHECK(d->certified == (i < maps.size()));
      CHECK(d->reason == want.reason);
      CHECK(d->segments == want.segments);
      CHECK(d->subdivisions == want.subdivisions);
      CHECK(d->sigma1_max == want.sigma1_max);
      CHECK(d->sigma2_min == want.sigma2_min);
      CHECK(d->observed_isometric_max == want.observed_isometric_max);
      CHECK(d->certified == setup->certifier.certify(tried[i]).certified);
    }
    // Another certifier of the same shape: not the core's to answer for.
    const auto other = make_shape_setup(scene, 2000, 0.2);
    CHECK_FALSE(core->certify_map(other->certifier, maps[0]).has_value());
    // A core made from rows alone has no certifier.
    CHECK_FALSE(hsi::cuda::make_newton_core(setup->D_G, setup->H)->certify_map(setup->certifier, maps[0]).has_value());
    // Lent: the same answer.
    CHECK(hsi::borrow_core(*core)->certify_map(setup->certifier, maps[0]).has_value());
  }
}

TEST_CASE("the GPU certificate finds a zero of f_z inside and a fold between breakpoints", "[cuda][certify]") {
  HSI_REQUIRE_GPU();
  // As in test_certificate.cpp: Φ(w) ≈ (w − w0)²/2 has f_z = 0 at w0 inside Ω while
  // |f_zbar| = 0 < |f_z| on ∂Ω, so only the argument principle can refuse it.
  for (const auto& [shape, w0] : {std::pair<Shape, cd>{test::disc(1.0, 128), cd(0.2, -0.1)},
                                  std::pair<Shape, cd>{test::annulus(1.0, 0.4, 128), cd(0.7, 0.0)}}) {
    const Cage cage = build_cage(shape);
    const BoundarySamples samples = sample_boundary(shape, 2000);
    const Certifier cpu(shape, cage, samples);
    hsi::cuda::Certifier gpu(shape, cage, samples);
    HarmonicMap m{VectorXcd::Zero(basis_size(cage)), VectorXcd::Zero(basis_size(cage))};
    int j = 0;
    for (const Loop& l : cage.loops)
      for (const cd& z : l) m.phi(j++) = (z - w0) * (z - w0) / 2.0;
    const CertificateResult r = gpu.certify(m);
    CHECK_FALSE(r.certified);
    CHECK(r.winding == 1);
    CHECK(r.reason == cpu.certify(m).reason);
  }
  // A sharply peaked cage basis function folds a short arc between breakpoints.
  const Shape s = test::disc(1.0, 64);
  Cage cage;
  cage.loops.push_back(test::circle(0, 1.02, 64));
  for (cd& z : cage.loops[0]) z *= std::polar(1.0, std::numbers::pi / 64);
  const BoundarySamples dense = sample_boundary(s, 50000);
  const double peak_val = evaluate_basis(cage, dense.points, kBasisD).D.col(5).cwiseAbs().maxCoeff();
  HarmonicMap m = identity_map(cage);
  m.psi(5) = 1.01 / peak_val;
  const BoundarySamples g = sample_boundary(s, 32);
  const CertificateResult c = Certifier(s, cage, g).certify(m);
  const CertificateResult d = hsi::cuda::Certifier(s, cage, g).certify(m);
  CHECK_FALSE(c.certified);
  CHECK_FALSE(d.certified);
  CHECK(d.fail_edge == c.fail_edge);
  CHECK(std::abs(d.fail_point - c.fail_point) < 1e-12);
}

// Small enough for compute-sanitizer: the device loop on a few frames.
// decrement() then direction() (the loop's exact systems: the forward substitution alone,
// then the back one and the direction) against solve() on the device stepper.
TEST_CASE("the device stepper's split solve gives solve()'s system", "[cuda][small]") {
  HSI_REQUIRE_GPU();
  for (const auto& p : test::asset_scenes()) {
    if (p.filename() != "annulus.json" && p.filename() != "bar_holes.json") continue;
    INFO(p.filename().string());
    AssetCores a(p);
    const Eigen::VectorXd id = a.space().reduce(identity_map(a.setup->cage)).x;
    const Eigen::VectorXd x_star = a.perturbed_identity(30, 0.03);
    const std::vector<Metric> targets = a.metrics_of(x_star);
    auto make = [&] {
      test::CoreStepper m;
      m.core = hsi::cuda::make_newton_core(*a.setup);
      m.core->set_targets(targets);
      m.stepper = m.core->make_stepper(a.space(), &a.setup->certifier, nullptr);
      REQUIRE(m.stepper);
      return m;
    };
    // Near the map the targets come from: the exact systems are definite there.
    const test::SplitCounts c = test::check_split_solve(make, x_star + 0.05 * (id - x_star));
    CHECK(c.factored >= 3);
    // Split wherever the triangular solves are the cluster kernel (sm_90 and up; not with
    // HSI_CUDA_SPLIT_SOLVE=0 or HSI_CUDA_SOLVE=cusolver).
    if (hsi::cuda::split_solve_enabled() && !hsi::cuda::cusolver_solve_forced() && hsi::cuda::kernels::cholesky_solve_in_cluster(200))
      CHECK(c.split == c.factored);
  }
}

// The device stepper's calls that save a wait (NewtonStepper::start_deferred,
// certify_ahead; x() after a solve): each must give what its waiting form gives, and a
// certificate asked ahead must never answer for another direction's step.
TEST_CASE("the device stepper's deferred start, certificate asked ahead and x() give what the waiting calls give", "[cuda][small]") {
  HSI_REQUIRE_GPU();
  for (const auto& p : test::asset_scenes()) {
    if (p.filename() != "annulus.json") continue;
    AssetCores a(p);
    const Eigen::VectorXd id = a.space().reduce(identity_map(a.setup->cage)).x;
    const Eigen::VectorXd x_star = a.perturbed_identity(30, 0.03);
    const Eigen::VectorXd x0 = x_star + 0.05 * (id - x_star);
    auto core = hsi::cuda::make_newton_core(*a.setup);
    core->set_targets(a.metrics_of(x_star));
    auto make = [&] {
      auto st = core->make_stepper(a.space(), &a.setup->certifier, nullptr);
      REQUIRE(st);
      return st;
    };
    HessianChoice exact;
    exact.exact = true;
    exact.free_rotation = true;
    HessianChoice projected;
    projected.free_rotation = true;
    projected.projection = HessianProjection::FullProj;

    // The energy at the start, deferred past a solve, and x() after the solve.
    auto w = make();
    const double e0 = w->start(x0);
    w->linearize(projected);
    const NewtonSystem ws = w->solve(0);
    REQUIRE(ws.factored);
    auto d = make();
    d->start_deferred(x0);
    d->linearize(projected);
    const NewtonSystem ds = d->solve(0);
    CHECK(d->start_energy() == e0);
    CHECK(ds.slope == ws.slope);
    CHECK(d->x() == x0);

    // A certificate asked ahead of the trial energies is the one asked after them.
    const double step = std::min(1.0, 0.5 * ws.max_safe_step);
    double e_w = 0, e_d = 0;
    w->trial_energies(std::span<const double>(&step, 1), std::span<double>(&e_w, 1));
    const CertificateResult cw = w->certify(step, false);
    d->certify_ahead(step);
    d->trial_energies(std::span<const double>(&step, 1), std::span<double>(&e_d, 1));
    CHECK(e_d == e_w);
    const CertificateResult cd = d->certify(step, false);
    CHECK(cd.certified == cw.certified);
    CHECK(cd.min_margin == cw.min_margin);
    CHECK(cd.sigma1_max == cw.sigma1_max);
    w->accept(step);
    d->accept(step);
    CHECK(d->x() == w->x());

    // Asked ahead along the projected system's direction, then a new direction (the
    // exact system): certify(step) must look at the new direction's point, not answer
    // with the old one's (the same step value, a different map).
    d->linearize(projected);
    REQUIRE(d->solve(0).factored);
    const CertificateResult along_old = d->certify(step, false);
    d->certify_ahead(step);  // along the projected direction: along_old's point
    w->linearize(exact);
    d->linearize(exact);
    const NewtonSystem we = w->solve(1e-15), de = d->solve(1e-15);
    REQUIRE(we.factored == de.factored);
    if (!we.factored) continue;
    const CertificateResult cw2 = w->certify(step, false);
    const CertificateResult cd2 = d->certify(step, false);
    CHECK(cd2.certified == cw2.certified);
    CHECK(cd2.min_margin == cw2.min_margin);
    CHECK(cd2.min_margin != along_old.min_margin);  // (the two points differ: the check above can fail)
  }
}

TEST_CASE("a short sequence solved on the GPU matches the CPU", "[cuda][small]") {
  HSI_REQUIRE_GPU();
  for (const auto& p : test::asset_scenes())
    if (p.filename() == "annulus.json")
      for (const ExactSamples e : {ExactSamples::Subset, ExactSamples::All}) compare_sequences(p, 6, 4000, e);
}

// The CUDA core keeps the keyframes' metric sets on the device and blends them there
// (NewtonCore::blend_targets); the energy it then gives must be the host blend's.
TEST_CASE("the CUDA core's target blend matches the host blend, linear and exponential", "[cuda][small]") {
  HSI_REQUIRE_GPU();
  const Scene scene = load_scene(test::asset_scenes().front());
  const auto setup = make_shape_setup(scene, 3000, 0.2);
  const size_t G = setup->G.points.size();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<std::vector<Metric>> keys(3, std::vector<Metric>(G)), logs(3, std::vector<Metric>(G));
  for (size_t j = 0; j < 3; ++j)
    for (size_t i = 0; i < G; ++i) {
      keys[j][i] = Metric(1 + u(rng), 0.5 * u(rng), 1 + u(rng));
      logs[j][i] = Metric(u(rng), u(rng), u(rng));
    }
  const auto gpu = hsi::cuda::make_newton_core(*setup);
  const auto cpu = make_cpu_newton_core(setup->D_G, setup->H);
  const Eigen::VectorXd v = setup->metric_space.T() * setup->metric_space.reduce(identity_map(setup->cage)).x;
  gpu->set_coefficients(v);
  cpu->set_coefficients(v);
  const std::uint64_t tg = gpu->set_target_keys(keys, logs), tc = cpu->set_target_keys(keys, logs);
  for (const bool exponential : {false, true}) {
    const std::vector<double> w = exponential ? std::vector<double>{-0.2, 0.7, 0.5} : std::vector<double>{0.3, 0, 0.7};
    REQUIRE(gpu->blend_targets(tg, w, exponential));
    REQUIRE(cpu->blend_targets(tc, w, exponential));
    CHECK(gpu->energy() == Approx(cpu->energy()).epsilon(1e-13));
    CHECK((gpu->gradient() - cpu->gradient()).norm() <= 1e-12 * cpu->gradient().norm());
  }
  CHECK_FALSE(gpu->blend_targets(tc, std::vector<double>{1, 0, 0}, false));  // the CPU core's token
  CHECK_THROWS_AS(gpu->blend_targets(tg, std::vector<double>{1, 0}, false), InputError);
}

// The device stepper replays each call as a CUDA graph (device.h GraphCache): a value a
// graph baked in at capture that should change between calls (a step, a ridge, a
// pointer) would give other frames than launching the same work directly
// (HSI_CUDA_GRAPHS=0). Frames and authored keyframes must be the same bit for bit, on a
// scene whose loop frees the rotation and uses the exact system, and in authoring (the
// quadratic term's path).
TEST_CASE("the device loop replayed as CUDA graphs gives the frames of direct launches", "[cuda][small]") {
  HSI_REQUIRE_GPU();
  for (const auto& p : test::asset_scenes()) {
    if (p.filename() != "annulus.json" && p.filename() != "bar_holes.json") continue;
    INFO(p.filename().string());
    Scene scene = load_scene(p);
    const auto setup = make_shape_setup(scene, 4000, 0.2);
    auto make = [&](bool graphs) {  // device.h graphs_enabled
      REQUIRE(setenv("HSI_CUDA_GRAPHS", graphs ? "1" : "0", 1) == 0);
      auto core = hsi::cuda::make_newton_core(*setup);
      REQUIRE(unsetenv("HSI_CUDA_GRAPHS") == 0);
      return core;
    };
    const auto [times, maps] = scene_keys(scene);
    Interpolator with(*setup, times, maps, {}, make(true)), without(*setup, times, maps, {}, make(false));
    const auto a = with.sequence(30), b = without.sequence(30);
    REQUIRE(a.size() == b.size());
    int exact_frames = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      test::require_same(a[i], b[i]);
      exact_frames += a[i].iterations > 1;
    }
    CHECK(exact_frames > 0);  // frames past their first iteration: the exact system's path
    // Authoring: the second keyframe from its targets, on each core.
    if (scene.keyframes.size() >= 2 && !scene.handles.empty() && !scene.keyframes[1].targets.empty()) {
      KeyframeOptions o;
      auto author = [&](bool graphs) {
        o.make_core = [&, graphs](const ShapeSetup&) { return make(graphs); };
        return author_keyframe(*setup, scene.handles, scene.keyframes[1].targets, maps[0], o);
      };
      const KeyframeResult ka = author(true), kb = author(false);
      CHECK(ka.map.phi == kb.map.phi);
      CHECK(ka.map.psi == kb.map.psi);
      CHECK(ka.iterations == kb.iterations);
      CHECK(ka.certified == kb.certified);
    }
  }
}

// Captures on many threads at once, beside other threads that make and free cores (the
// allocations, frees and handle destructions that synchronise the device): with 16
// workers on the H100 (bench_stress, bench_batch) such calls invalidated captures in
// flight and the process crashed, so graphs were opt-in. capture_guard keeps those calls
// out of every capture: no capture may fail, and every thread's frames are the frames of
// direct launches, bit for bit.
TEST_CASE("CUDA graphs captured on many threads beside allocations and frees", "[cuda][small]") {
  HSI_REQUIRE_GPU();
  const Scene scene = load_scene(test::asset_scenes().front());
  const auto setup = make_shape_setup(scene, 4000, 0.2);
  const auto [times, maps] = scene_keys(scene);
  auto make = [&](bool graphs) {
    static std::mutex env;  // setenv is not thread-safe; graphs_enabled reads it as a core is made
    std::lock_guard<std::mutex> lock(env);
    REQUIRE(setenv("HSI_CUDA_GRAPHS", graphs ? "1" : "0", 1) == 0);
    auto core = hsi::cuda::make_newton_core(*setup);
    REQUIRE(unsetenv("HSI_CUDA_GRAPHS") == 0);
    return core;
  };
  std::vector<FrameResult> reference;
  {
    Interpolator direct(*setup, times, maps, {}, make(false));
    reference = direct.sequence(24);
  }
  const long failures_before = hsi::cuda::capture_failures().load();
  constexpr int kSolvers = 6, kChurners = 2;
  std::vector<std::vector<FrameResult>> got(kSolvers);
  std::vector<std::string> errors(kSolvers + kChurners);
  std::atomic<int> solving{kSolvers};
  std::vector<std::thread> threads;
  for (int w = 0; w < kSolvers; ++w)
    threads.emplace_back([&, w] {
      try {
        for (int round = 0; round < 2; ++round) {  // a second core per thread: captures again
          Interpolator with(*setup, times, maps, {}, make(true));
          got[static_cast<size_t>(w)] = with.sequence(24);
        }
      } catch (const std::exception& e) {
        errors[static_cast<size_t>(w)] = e.what();
      }
      --solving;
    });
  for (int c = 0; c < kChurners; ++c)
    threads.emplace_back([&, c] {
      try {
        while (solving.load() > 0) {  // make and drop cores: cudaMalloc, cudaFree, handles, streams
          auto core = make(c % 2 == 0);
          core.reset();
        }
      } catch (const std::exception& e) {
        errors[static_cast<size_t>(kSolvers + c)] = e.what();
      }
    });
  for (std::thread& t : threads) t.join();
  for (const std::string& e : errors) CHECK(e.empty());
  CHECK(hsi::cuda::capture_failures().load() == failures_before);
  for (int w = 0; w < kSolvers; ++w) {
    INFO("thread " << w);
    REQUIRE(got[static_cast<size_t>(w)].size() == reference.size());
    for (size_t i = 0; i < reference.size(); ++i) test::require_same(got[static_cast<size_t>(w)][i], reference[i]);
  }
}

// capture_guard is not recursive: an OutsideCaptures nested in one this thread holds
// (a graph key's first run holds one while it enqueues, and may make buffers) must not
// wait for itself. Needs no GPU. Without the nesting rule the helper thread would hang.
TEST_CASE("capture guard: nested device-wide calls on one thread do not deadlock", "[cuda]") {
  auto done = std::make_shared<std::atomic<bool>>(false);
  std::thread([done] {
    hsi::cuda::OutsideCaptures outer;
    { hsi::cuda::OutsideCaptures inner; }
    CHECK(hsi::cuda::guard_held() == hsi::cuda::GuardHeld::Exclusive);  // the outer one still holds it
    *done = true;
  }).detach();
  for (int i = 0; i < 200 && !*done; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  REQUIRE(done->load());
  // Released: another thread takes it at once.
  std::thread([] {
    hsi::cuda::OutsideCaptures again;
    CHECK(hsi::cuda::guard_held() == hsi::cuda::GuardHeld::Exclusive);
  }).join();
  CHECK(hsi::cuda::guard_held() == hsi::cuda::GuardHeld::None);
}

// cuBLAS and cuSOLVER are not linked (cuda/src/lazy_libraries.cpp): every process with
// the backend paid ~250 MB for them at start. Calls go through entry points that open
// the libraries on first use; this one needs no GPU.
#include <cublas_v2.h>
#include <cusolverDn.h>

TEST_CASE("cuda: cuBLAS and cuSOLVER entry points open their libraries on first use", "[cuda]") {
  CHECK(std::string(cublasGetStatusName(CUBLAS_STATUS_SUCCESS)) == "CUBLAS_STATUS_SUCCESS");
  CHECK(std::string(cublasGetStatusString(CUBLAS_STATUS_NOT_INITIALIZED)).size() > 5);
  // Without a device the handle cannot be made, but the call reaches cuSOLVER and reports it.
  cusolverDnHandle_t h = nullptr;
  const cusolverStatus_t s = cusolverDnCreate(&h);
  if (s == CUSOLVER_STATUS_SUCCESS) cusolverDnDestroy(h);
  CHECK((s == CUSOLVER_STATUS_SUCCESS || s == CUSOLVER_STATUS_NOT_INITIALIZED || s == CUSOLVER_STATUS_ALLOC_FAILED ||
         s == CUSOLVER_STATUS_INTERNAL_ERROR || s == CUSOLVER_STATUS_ARCH_MISMATCH));
}

// A batch makes one core per worker and shape; D at G and the certifier's rows at the
// breakpoints (tens of MB per shape) are uploaded once per setup and GPU and shared.
TEST_CASE("cores made for one setup share its rows on the device; frames the same, the rows kept while any core holds them",
          "[cuda][small]") {
  HSI_REQUIRE_GPU();
  const Scene scene = load_scene(test::asset_scenes().front());
  const auto setup = make_shape_setup(scene, 10000, 0.2);
  const auto [times, maps] = scene_keys(scene);
  auto free_bytes = [] {
    size_t free = 0, total = 0;
    REQUIRE(cudaMemGetInfo(&free, &total) == cudaSuccess);
    return free;
  };
  const Eigen::Index S = setup->certifier.breakpoint_D().rows(), M = setup->certifier.breakpoint_D().cols();
  const double shared = static_cast<double>(setup->D_G.size()) * 16 + static_cast<double>(setup->H.size()) * (4 + 16.0 * static_cast<double>(setup->D_G.cols())) +
                        static_cast<double>(2 * S * M) * (16 + 8) + static_cast<double>(S * M) * 8;
  const size_t f0 = free_bytes();
  auto a = hsi::cuda::make_newton_core(*setup);
  const size_t f1 = free_bytes();
  auto b = hsi::cuda::make_newton_core(*setup);
  const size_t f2 = free_bytes();
  const double first = static_cast<double>(f0) - static_cast<double>(f1), second = static_cast<double>(f1) - static_cast<double>(f2);
  INFO("first core " << first / 1e6 << " MB, second " << second / 1e6 << " MB, shared rows " << shared / 1e6 << " MB");
  CHECK(first - second >= 0.8 * shared);
  std::vector<FrameResult> fa, fb;
  {
    Interpolator ia(*setup, times, maps, {}, hsi::borrow_core(*a));
    fa = ia.sequence(8);
  }
  a.reset();  // b still holds the rows
  {
    Interpolator ib(*setup, times, maps, {}, hsi::borrow_core(*b));
    fb = ib.sequence(8);
  }
  REQUIRE(fa.size() == fb.size());
  for (size_t i = 0; i < fa.size(); ++i) test::require_same(fb[i], fa[i]);
  // A core made from copies of D and H (not the setup's) has its own rows.
  const MatrixXcd D = setup->D_G;
  const std::vector<int> H = setup->H;
  const size_t g0 = free_bytes();
  auto own = hsi::cuda::make_newton_core(D, H);
  CHECK(static_cast<double>(g0) - static_cast<double>(free_bytes()) >= 0.8 * static_cast<double>(D.size()) * 16);
}

// The setup core runs every call of a solve once while it is made (first frame fast,
// issue #23) and must still start from the documented state.
TEST_CASE("a setup core is warmed up when made and starts from the defined state", "[cuda][small]") {
  HSI_REQUIRE_GPU();
  const Scene scene = load_scene(test::asset_scenes().front());
  const auto setup = make_shape_setup(scene, 2000, 0.2);
  const auto gpu = hsi::cuda::make_newton_core(*setup);
  CHECK(std::isinf(gpu->energy()));         // a = b = 0 until coefficients are set
  CHECK(std::isinf(gpu->max_safe_step()));  // zero direction until set
  const auto cpu = make_cpu_newton_core(setup->D_G, setup->H);
  const Eigen::VectorXd v = setup->metric_space.T() * setup->metric_space.reduce(identity_map(setup->cage)).x;
  gpu->set_coefficients(v);
  cpu->set_coefficients(v);
  CHECK(gpu->energy() == Approx(cpu->energy()).epsilon(1e-12));
}

// f at a mesh's vertices from rows cached on the GPU against the direct CPU evaluation.
TEST_CASE("the CUDA mesh evaluator equals the direct evaluation on every asset", "[cuda][mesh_eval][small]") {
  HSI_REQUIRE_GPU();
  auto gap = [](const VectorXcd& got, const VectorXcd& want) {
    REQUIRE(got.size() == want.size());
    return (got - want).cwiseAbs().maxCoeff() / std::max(want.cwiseAbs().maxCoeff(), 1e-300);
  };
  for (const auto& path : test::asset_scenes()) {
    const Scene scene = load_scene(path);
    const Cage cage = scene.cage ? *scene.cage : build_cage(scene.shape, scene.cage_options);
    const std::vector<cd> pts = test::interior_points(scene.shape, 1500 + 77);
    INFO(path.filename().string());
    const BasisRows rows = evaluate_basis(cage, pts, kBasisC | kBasisD);
    for (bool derivatives : {false, true}) {
      hsi::cuda::MeshEvaluator e(cage, pts, {.derivatives = derivatives});
      CHECK(e.size() == pts.size());
      MapValues got;
      for (unsigned seed : {1u, 2u}) {
        std::mt19937 rng(seed);
        std::normal_distribution<double> g(0, 0.05);
        HarmonicMap map = affine_map(cage, cd(0.9, 0.4), cd(0.2, 0.1), cd(-1, 3));
        for (Eigen::Index j = 0; j < map.phi.size(); ++j) {
          map.phi(j) += cd(g(rng), g(rng));
          map.psi(j) += cd(g(rng), g(rng));
        }
        const MapValues want = evaluate_map(rows, map);
        e.evaluate(map, got);
        CHECK(gap(got.f, want.f) < 1e-12);
        if (derivatives) {
          CHECK(gap(got.f_z, want.f_z) < 1e-12);
          CHECK(gap(got.fzbar_conj, want.fzbar_conj) < 1e-12);
        } else {
          CHECK(got.f_z.size() == 0);
        }
        // The values left on the device are the same ones.
        e.enqueue(map);
        e.synchronize();
        VectorXcd on_device(static_cast<Eigen::Index>(pts.size()));
        REQUIRE(cudaMemcpy(on_device.data(), e.device_values(), pts.size() * sizeof(cd), cudaMemcpyDeviceToHost) == cudaSuccess);
        CHECK(on_device == got.f);
      }
      HarmonicMap wrong = identity_map(cage);
      wrong.psi.conservativeResize(wrong.psi.size() + 1);
      CHECK_THROWS_AS(e.evaluate(wrong, got), InputError);

      // Made from the CPU evaluator's rows (uploaded, not evaluated again): the same values
      // bit for bit as the one that evaluated them.
      const auto cpu = make_cpu_mesh_evaluator(cage, pts, {.derivatives = derivatives});
      hsi::cuda::MeshEvaluator copied(*cpu, {.derivatives = derivatives});
      CHECK(copied.size() == pts.size());
      const HarmonicMap map = affine_map(cage, cd(0.7, -0.2), cd(0.1, 0.05), cd(2, -1));
      MapValues a, b;
      e.evaluate(map, a);
      copied.evaluate(map, b);
      CHECK(a.f == b.f);
      if (derivatives) {
        CHECK(a.f_z == b.f_z);
        CHECK(a.fzbar_conj == b.fzbar_conj);
      }
      CHECK_THROWS_AS(copied.evaluate(wrong, got), InputError);
    }
    // Derivatives asked of rows made without them, and a source that keeps no host rows.
    const auto plain = make_cpu_mesh_evaluator(cage, pts);
    CHECK_THROWS_WITH(hsi::cuda::MeshEvaluator(*plain, {.derivatives = true}), Catch::Contains("derivatives"));
    hsi::cuda::MeshEvaluator on_device(cage, pts);
    const hsi::MeshEvaluator& as_source = on_device;  // (not the deleted copy)
    CHECK_THROWS_WITH(hsi::cuda::MeshEvaluator(as_source), Catch::Contains("keeps no rows on the host"));
  }
}
