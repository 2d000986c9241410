// The GE baseline (engine/baselines, symmetric Dirichlet against blended metrics by
// projected Newton with SGK19's analytic eigensystem): the eigensystem against a closed-form
// Hessian and a numerical eigendecomposition, the mesh energy's derivatives against finite
// differences, keyframes reproduced, rigid and similarity motions kept, no flipped
// triangle under a large turn on a bundled asset, and bad input refused.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "baseline_meshes.h"
#include "hsi/baselines/arap.h"
#include "hsi/baselines/ge.h"
#include "hsi/keyframes.h"
#include "hsi/scene_sequence.h"

using namespace hsi;
using namespace hsi::baselines;
using namespace hsi::test::mesh;

namespace {

using Mat2 = Eigen::Matrix2d;
using Vec4 = Eigen::Vector4d;

Vec4 vec(const Mat2& F) { return {F(0, 0), F(1, 0), F(0, 1), F(1, 1)}; }

// Ψ(F) = ½(‖F‖² + ‖F⁻¹‖²) = ½ I2 (1 + J⁻²), I2 = ‖F‖², J = det F: written here independently.
double psi(const Vec4& f) {
  const double I2 = f.squaredNorm(), J = f[0] * f[3] - f[1] * f[2];
  return 0.5 * I2 * (1 + 1 / (J * J));
}
// Its Hessian by hand: with g = ∂J/∂f = (f3, −f2, −f1, f0) and K = ∂²J/∂f² (constant),
// H = (1 + J⁻²) I − 2J⁻³ (f gᵀ + g fᵀ) + 3 I2 J⁻⁴ g gᵀ − I2 J⁻³ K.
Eigen::Matrix4d psi_hessian(const Vec4& f) {
  const double I2 = f.squaredNorm(), J = f[0] * f[3] - f[1] * f[2];
  const Vec4 g(f[3], -f[2], -f[1], f[0]);
  Eigen::Matrix4d K = Eigen::Matrix4d::Zero();
  K(0, 3) = K(3, 0) = 1;
  K(1, 2) = K(2, 1) = -1;
  return (1 + 1 / (J * J)) * Eigen::Matrix4d::Identity() - 2 / (J * J * J) * (f * g.transpose() + g * f.transpose()) +
         3 * I2 / (J * J * J * J) * g * g.transpose() - I2 / (J * J * J) * K;
}

// A smooth, non-affine, orientation-preserving map of the bar (a shear, a bend and a bulge).
const auto wobble = [](cd z) { return std::polar(1.0, 0.4) * bend(z, 0.6) + 0.15 * cd(z.imag() * z.imag(), 0.2 * z.real()) + cd(0.3, -0.2); };

}  // namespace

TEST_CASE("GE eigensystem: eigenvalues, eigenvectors, gradient and Hessian of the symmetric Dirichlet energy", "[ge]") {
  std::mt19937 rng(24);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Mat2> Fs;
  Mat2 F;
  F << 1, 0, 0, 1;  // the minimum: twist eigenvalue exactly 0
  Fs.push_back(F);
  F << 0.6, -0.8, 0.8, 0.6;  // a rotation
  Fs.push_back(F);
  F << 2, 0, 0, 2;  // σ1 = σ2: flip and scalings coincide
  Fs.push_back(F);
  F << 0.3, 0.1, -0.05, 0.25;  // small singular values: twist eigenvalue negative
  Fs.push_back(F);
  F << 5, 0.2, 0, 0.1;  // strongly anisotropic
  Fs.push_back(F);
  while (Fs.size() < 40) {
    F << u(rng), u(rng), u(rng), u(rng);
    F *= std::exp(u(rng));
    if (F.determinant() > 1e-2) Fs.push_back(F);
  }
  for (const Mat2& Fi : Fs) {
    CAPTURE(Fi);
    const Vec4 f = vec(Fi);
    const SymmetricDirichletEigensystem e = symmetric_dirichlet_eigensystem(Fi);
    CHECK(e.psi == Approx(psi(f)).epsilon(1e-12));
    // Gradient against central differences of Ψ.
    const double h = 1e-6;
    for (int i = 0; i < 4; ++i) {
      Vec4 p = f, m = f;
      p[i] += h;
      m[i] -= h;
      CHECK(e.gradient[i] == Approx((psi(p) - psi(m)) / (2 * h)).epsilon(1e-6).margin(1e-6 * (1 + e.gradient.norm())));
    }
    // Eigenvectors orthonormal; the assembled Hessian against the closed form and against
    // central differences of the closed-form energy.
    CHECK((e.eigenvectors.transpose() * e.eigenvectors - Eigen::Matrix4d::Identity()).norm() < 1e-12);
    const Eigen::Matrix4d H = psi_hessian(f);
    CHECK((e.hessian(false) - H).norm() < 1e-9 * H.norm());
    Eigen::Matrix4d H_fd;
    const double k = 1e-5 * std::sqrt(Fi.determinant());  // below σ2 ≤ √det F, where Ψ changes fastest
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        Vec4 pp = f, pm = f, mp = f, mm = f;
        pp[i] += k, pp[j] += k;
        pm[i] += k, pm[j] -= k;
        mp[i] -= k, mp[j] += k;
        mm[i] -= k, mm[j] -= k;
        H_fd(i, j) = (psi(pp) - psi(pm) - psi(mp) + psi(mm)) / (4 * k * k);
      }
    CHECK((e.hessian(false) - H_fd).norm() < 1e-5 * H.norm());
    // The analytic eigenvalues against a numerical eigendecomposition of the closed form.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(H);
    Vec4 analytic = e.eigenvalues;
    std::sort(analytic.data(), analytic.data() + 4);
    for (int i = 0; i < 4; ++i) CHECK(analytic[i] == Approx(eig.eigenvalues()[i]).margin(1e-9 * H.norm()));
    // Each eigenvector is one: H q = λ q.
    for (int i = 0; i < 4; ++i)
      CHECK((H * e.eigenvectors.col(i) - e.eigenvalues[i] * e.eigenvectors.col(i)).norm() < 1e-9 * H.norm());
    // The projection: PSD, equal to the numerical projection (eigenvalues clamped at 0).
    const Eigen::Matrix4d P = e.hessian(true);
    const Eigen::Matrix4d P_num =
        eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
    CHECK((P - P_num).norm() < 1e-9 * H.norm());
  }
  // The twist is the only mode that can be negative; at small σ it is.
  F << 0.3, 0.1, -0.05, 0.25;
  CHECK(symmetric_dirichlet_eigensystem(F).eigenvalues[3] < 0);
  Mat2 bad;
  bad << 1, 0, 0, -1;
  CHECK_THAT(error_of([&] { (void)symmetric_dirichlet_eigensystem(bad); }), Catch::Contains("det F"));
}

TEST_CASE("GE energy: gradient and Hessian of the mesh energy against finite differences", "[ge]") {
  const TriMesh m = bar_mesh(60);
  const GeInterpolation ge(m, {{0, m.vertices}, {1, apply(m, wobble)}});
  // A point that is neither keyframe nor optimum: the rest mesh lightly perturbed.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  std::vector<cd> x = apply(m, [](cd z) { return 1.1 * z + 0.1 * z * z; });
  for (cd& p : x) p += cd(u(rng), u(rng));
  for (double t : {0.0, 0.37, 1.0}) {
    CAPTURE(t);
    const Eigen::VectorXd g = ge.gradient(t, x);
    const Eigen::MatrixXd H = Eigen::MatrixXd(ge.hessian(t, x, false));
    const double h = 1e-6;
    Eigen::VectorXd g_fd(g.size());
    Eigen::MatrixXd H_fd(H.rows(), H.cols());
    for (int j = 0; j < static_cast<int>(g.size()); ++j) {
      std::vector<cd> p = x, q = x;
      const size_t v = static_cast<size_t>(j / 2);
      const cd step = j % 2 ? cd(0, h) : cd(h, 0);
      p[v] += step;
      q[v] -= step;
      g_fd[j] = (ge.energy(t, p) - ge.energy(t, q)) / (2 * h);
      H_fd.col(j) = (ge.gradient(t, p) - ge.gradient(t, q)) / (2 * h);
    }
    CHECK((g - g_fd).norm() < 1e-6 * g.norm());
    CHECK((H - H_fd).norm() < 1e-6 * H.norm());
    CHECK((H - H.transpose()).norm() < 1e-12 * H.norm());
    // The projected Hessian is PSD.
    const Eigen::MatrixXd P = Eigen::MatrixXd(ge.hessian(t, x, true));
    const double min_projected = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(P).eigenvalues().minCoeff();
    CHECK(min_projected > -1e-10 * P.norm());
  }
  // The energy is +∞ at a flipped triangle and 2·area at a keyframe.
  double area = 0;
  for (const auto& t : m.triangles) area += signed_area(m.vertices, t);
  CHECK(ge.energy(0, m.vertices) == Approx(2 * area).epsilon(1e-12));
  CHECK(ge.energy(1, apply(m, wobble)) == Approx(2 * area).epsilon(1e-10));
  CHECK(std::isinf(ge.energy(0.5, apply(m, [](cd z) { return std::conj(z); }))));
}

TEST_CASE("GE reproduces its keyframes and keeps rigid and similarity motions", "[ge]") {
  const TriMesh m = bar_mesh(200);
  const double size = mesh_size(m);
  const std::vector<cd> k1 = apply(m, wobble), k2 = apply(m, [](cd z) { return 0.8 * std::polar(1.0, -0.5) * z + 1.0; });
  const GeInterpolation ge(m, {{0, m.vertices}, {1, k1}, {2.5, k2}}, {.tolerance = 1e-14});
  const std::vector<double> times{0, 0.25, 0.5, 0.75, 1, 1.5, 2, 2.5};
  int calls = 0;
  const std::vector<GeFrame> f = ge.sequence(times, [&](const GeFrame& g, int i, int n) {
    CHECK(i == calls++);
    CHECK(n == static_cast<int>(times.size()));
    CHECK(g.time == times[static_cast<size_t>(i)]);
  });
  REQUIRE(f.size() == times.size());
  CHECK(calls == static_cast<int>(times.size()));
  for (const GeFrame& g : f) {
    CAPTURE(g.time);
    CHECK(g.converged);
    CHECK(g.energy >= 2 - 1e-12);
    CHECK(mesh_distortion(m, g.positions).flipped == 0);
  }
  CHECK(f[0].iterations == 0);  // starts at keyframe 0 itself
  CHECK(max_distance(f[0].positions, m.vertices) < 1e-12 * size);
  CHECK(max_distance(f[4].positions, k1) < 1e-7 * size);
  CHECK(max_distance(f[7].positions, k2) < 1e-7 * size);
  CHECK(f[4].energy == Approx(2).epsilon(1e-9));
  CHECK(f[2].energy > 2 + 1e-6);  // an in-between does not realise the blended metric exactly

  // Rigid (a turn of 2.5 rad, under π: the short way) with a scale: the blended metric is
  // ((1−s) + s k²) I, so every frame is the similarity with that scale, turning linearly,
  // its centroid moving linearly.
  for (double k : {1.0, 1.7}) {
    CAPTURE(k);
    const double turn = 2.5;
    const cd c1(3, -1);
    const cd c0 = centroid(m, m.vertices);
    const GeInterpolation rigid(m, {{0, m.vertices}, {1, apply(m, [&](cd z) { return k * std::polar(1.0, turn) * (z - c0) + c1; })}},
                                {.tolerance = 1e-12});
    const std::vector<double> ts{0, 0.2, 0.5, 0.9, 1};
    const std::vector<GeFrame> r = rigid.sequence(ts);
    for (size_t i = 0; i < ts.size(); ++i) {
      CAPTURE(ts[i]);
      const double s = ts[i], scale = std::sqrt((1 - s) + s * k * k);
      const cd c = (1 - s) * c0 + s * c1;
      CHECK(max_distance(r[i].positions, apply(m, [&](cd z) { return scale * std::polar(1.0, s * turn) * (z - c0) + c; })) <
            1e-7 * size);
      CHECK(centroid(m, r[i].positions).real() == Approx(c.real()).margin(1e-9 * size));
    }
  }
}

TEST_CASE("GE refuses bad keyframes, options and starts with a message naming them", "[ge]") {
  const TriMesh m = bar_mesh(100);
  const std::vector<cd> rest = m.vertices;
  CHECK_THAT(error_of([&] { GeInterpolation(m, {{0, rest}}); }), Catch::Contains("at least 2 keyframes"));
  CHECK_THAT(error_of([&] { GeInterpolation(m, {{0, rest}, {0, rest}}); }), Catch::Contains("keyframe 1") && Catch::Contains("increase"));
  const std::vector<cd> mirror = apply(m, [](cd z) { return std::conj(z); });
  CHECK_THAT(error_of([&] { GeInterpolation(m, {{0, rest}, {1, mirror}}); }),
             Catch::Contains("GE keyframe 1") && Catch::Contains("flipped"));
  CHECK_THAT(error_of([&] { GeInterpolation(m, {{0, rest}, {1, rest}}, {.safe_fraction = 1.5}); }), Catch::Contains("safe_fraction"));
  const GeInterpolation ok(m, {{0, rest}, {1, rest}});
  CHECK_THAT(error_of([&] { (void)ok.frame(0.5, mirror); }), Catch::Contains("GE start") && Catch::Contains("flipped"));
  CHECK_THAT(error_of([&] { (void)ok.frame(std::nan(""), rest); }), Catch::Contains("NaN"));
  CHECK_THAT(error_of([&] { (void)ok.frame(0.5, std::vector<cd>(3)); }), Catch::Contains("positions"));
}

TEST_CASE("GE frames flip no triangle under a large turn on a bundled asset's mesh", "[ge][assets]") {
  // The arm (a body with a hole and a long thin limb): keyframe 1 bends it by 0.55 rad per
  // unit of length, turns it by 2.6 rad and shears the result (g + 0.3 ḡ: κ = 1.3/0.7, in
  // a direction that turns along the bend), so its triangles turn by about 1.3 to 3.9 rad
  // from the rest pose.
  Scene scene = load_scene(std::string(HSI_ASSETS_DIR) + "/arm.json");
  const TriMesh m = triangulate(scene.shape, {.max_edge = edge_for_vertex_count(scene.shape, 600)});
  const double size = mesh_size(m);
  const cd c = centroid(m, m.vertices);
  const std::vector<cd> k1 = apply(m, [&](cd z) {
    const cd g = std::polar(1.0, 2.6) * bend(z - c, 0.55);
    return g + 0.3 * std::conj(g) + c;
  });
  REQUIRE(mesh_distortion(m, k1).flipped == 0);
  const GeInterpolation ge(m, {{0, m.vertices}, {1, k1}});
  std::vector<double> times;
  for (int i = 0; i <= 8; ++i) times.push_back(i / 8.0);
  const std::vector<GeFrame> f = ge.sequence(times);
  int flipped = 0, iterations = 0;
  for (const GeFrame& g : f) {
    CAPTURE(g.time);
    for (cd p : g.positions) REQUIRE((std::isfinite(p.real()) && std::isfinite(p.imag())));
    flipped += mesh_distortion(m, g.positions).flipped;
    CHECK(g.converged);
    CHECK(std::isfinite(g.energy));
    iterations += g.iterations;
  }
  CHECK(flipped == 0);
  CHECK(max_distance(f.back().positions, k1) < 1e-3 * size);  // to the solve's tolerance (5e-8 of E)
  std::printf("GE arm (%d vertices): %d frames, %.1f Newton iterations per frame, max energy %.4f\n", m.vertex_count(),
              static_cast<int>(f.size()), iterations / static_cast<double>(f.size()),
              std::max_element(f.begin(), f.end(), [](const GeFrame& a, const GeFrame& b) { return a.energy < b.energy; })->energy);

  // The scene's own keyframes (certified harmonic maps at the mesh's vertices).
  const auto setup = scene_setup(scene);
  solve_scene_keyframes(scene, *setup);
  std::vector<MeshKeyframe> kf;
  for (const Keyframe& k : scene.keyframes) kf.push_back({k.time, map_points(setup->cage, *k.coefficients, m.vertices)});
  for (const MeshKeyframe& k : kf) REQUIRE(mesh_distortion(m, k.positions).flipped == 0);
  const GeInterpolation scene_ge(m, kf);
  std::vector<double> st;
  for (int i = 0; i <= 4 * (static_cast<int>(kf.size()) - 1); ++i) st.push_back(kf.front().time + i * (kf.back().time - kf.front().time) / (4.0 * (static_cast<double>(kf.size()) - 1)));
  flipped = 0;
  iterations = 0;
  for (const GeFrame& g : scene_ge.sequence(st)) {
    flipped += mesh_distortion(m, g.positions).flipped;
    iterations += g.iterations;
    CHECK(g.converged);
  }
  CHECK(flipped == 0);
  std::printf("GE arm scene keyframes: %d frames, %.1f Newton iterations per frame\n", static_cast<int>(st.size()),
              iterations / static_cast<double>(st.size()));
}
