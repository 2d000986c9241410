// Dense certification on the GPU (compute/dense_certify.h) against the CPU
// certificate (hsi::Certifier, the reference): the same verdict, failing loop, edge
// and point, winding, segment and subdivision counts, and bounds within 1e-9, on every
// bundled scene's keyframes, on interpolated frames, and on the folded-map corpus of
// test_certificate.cpp (orientation reversal, a zero of f_z inside, a fold between
// breakpoints, random maps across the fold boundary); both ways of computing the
// breakpoint values (the precomputed basis matrix, and from the cage per map). Runs on lavapipe where there is
// no GPU, with the validation layer on: any validation message fails the test.
// Without a Vulkan device the tests WARN and pass unless HSI_REQUIRE_VULKAN=1.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>

#include "hsi/certificate.h"
#include "hsi/compute/dense_certify.h"
#include "hsi/compute/vulkan_context.h"
#include "hsi/harmonic_map.h"
#include "hsi/interpolation.h"
#include "test_shapes.h"
#include "vulkan_test.h"

using namespace hsi;

namespace {

// test::with_vulkan, for a device that can run the dense certificate (shaderFloat64);
// on one without, the certifier must refuse with VulkanError, and the test is skipped.
template <class Body>
void with_vulkan(Body&& body) {
  test::with_vulkan([&](compute::Context& ctx) {
    if (!ctx.info().float64) {
      CHECK_THROWS_AS(compute::DenseCertifier(ctx, test::disc(), build_cage(test::disc()), sample_boundary(test::disc(), 64)),
                      compute::VulkanError);
      WARN("skipping: " << ctx.info().name << " has no shaderFloat64");
      return;
    }
    body(ctx);
  });
}

// Forces the per-map values from the cage (mode 0) instead of the basis matrix.
compute::DenseCertifyOptions direct_options() {
  compute::DenseCertifyOptions o;
  o.max_basis_bytes = 0;
  return o;
}

constexpr double kBoundTol = 1e-9;  // the stated tolerance of the bounds (relative to σ1 max)

// How far apart the two certificates are, over a run of maps.
struct Agreement {
  int maps = 0, certified = 0, rejected = 0, verdict_mismatch = 0, location_mismatch = 0, subdivision_mismatch = 0;
  double worst_bound = 0;  // max relative difference of the bounds
  std::string summary() const {
    std::ostringstream s;
    s << maps << " maps (" << certified << " certified, " << rejected << " rejected): " << verdict_mismatch
      << " verdict and " << location_mismatch << " failure-location mismatches, " << subdivision_mismatch
      << " with other subdivision counts, worst relative bound difference " << worst_bound;
    return s.str();
  }
};

double rel_diff(double gpu, double cpu, double scale) {
  if (gpu == cpu) return 0;  // also equal infinities
  return std::abs(gpu - cpu) / std::max({scale, std::abs(cpu), 1e-300});
}

// Checks that the GPU result is the CPU's: verdict, location, winding, counts, and
// bounds to kBoundTol; certified bounds never less conservative than the CPU's.
void check_agree(const CertificateResult& cpu, const CertificateResult& gpu, Agreement& a) {
  INFO("CPU: " << (cpu.certified ? "certified" : cpu.reason) << "\nGPU: " << (gpu.certified ? "certified" : gpu.reason));
  ++a.maps;
  (cpu.certified ? a.certified : a.rejected)++;
  a.verdict_mismatch += gpu.certified != cpu.certified;
  CHECK(gpu.certified == cpu.certified);
  const bool same_place = gpu.fail_loop == cpu.fail_loop && gpu.fail_edge == cpu.fail_edge &&
                          std::abs(gpu.fail_point - cpu.fail_point) <= 1e-12 * (1 + std::abs(cpu.fail_point));
  a.location_mismatch += !same_place;
  CHECK(gpu.fail_loop == cpu.fail_loop);
  CHECK(gpu.fail_edge == cpu.fail_edge);
  CHECK(std::abs(gpu.fail_point - cpu.fail_point) <= 1e-12 * (1 + std::abs(cpu.fail_point)));
  CHECK(gpu.reason == cpu.reason);
  CHECK(gpu.winding == cpu.winding);
  CHECK(gpu.segments == cpu.segments);
  a.subdivision_mismatch += gpu.subdivisions != cpu.subdivisions;
  CHECK(gpu.subdivisions == cpu.subdivisions);

  const double scale = std::max(cpu.observed_sigma1_max, 1e-300);
  const double diffs[] = {rel_diff(gpu.min_margin, cpu.min_margin, scale),
                          rel_diff(gpu.sigma1_max, cpu.sigma1_max, scale),
                          rel_diff(gpu.sigma2_min, cpu.sigma2_min, scale),
                          rel_diff(gpu.k_max, cpu.k_max, 1.0),
                          rel_diff(gpu.observed_sigma1_max, cpu.observed_sigma1_max, scale),
                          rel_diff(gpu.observed_sigma2_min, cpu.observed_sigma2_min, scale),
                          rel_diff(gpu.observed_k_max, cpu.observed_k_max, 1.0)};
  double worst = 0;
  for (double d : diffs) worst = std::max(worst, d);
  a.worst_bound = std::max(a.worst_bound, worst);
  // σ1/σ2 = (1 + k)/(1 − k) amplifies k's difference by up to (1 + k)/(1 − k).
  if (cpu.certified) CHECK(rel_diff(gpu.conformal_max, cpu.conformal_max, 1.0) <= kBoundTol * cpu.conformal_max);
  INFO("margin " << cpu.min_margin << " / " << gpu.min_margin << ", sigma1 " << cpu.sigma1_max << " / "
                 << gpu.sigma1_max << ", sigma2 " << cpu.sigma2_min << " / " << gpu.sigma2_min << ", k " << cpu.k_max
                 << " / " << gpu.k_max);
  CHECK(worst <= kBoundTol);
  // Both carry rounding allowances (of different evaluations: the CPU's sums per cage
  // vertex, the GPU's per cage edge), so neither is the more conservative by
  // construction; each certified bound contains what the map does at the breakpoints.
  for (const CertificateResult* r : {&cpu, &gpu}) {
    if (!r->certified) continue;
    CHECK(r->sigma1_max >= r->observed_sigma1_max);
    CHECK(r->sigma2_min <= r->observed_sigma2_min);
    CHECK(r->min_margin <= r->observed_sigma2_min);
    CHECK(r->k_max >= r->observed_k_max);
  }
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

HarmonicMap blend(const HarmonicMap& a, const HarmonicMap& b, double t) {
  return {(1 - t) * a.phi + t * b.phi, (1 - t) * a.psi + t * b.psi};
}

}  // namespace

TEST_CASE("dense certificate agrees with the CPU on every bundled scene's keyframes", "[vulkan][certify][long]") {
  with_vulkan([](compute::Context& ctx) {
    Agreement agree;
    for (const auto& path : test::asset_scenes()) {
      const Scene scene = load_scene(path);
      const Cage cage = scene_cage(scene);
      const BoundarySamples samples = sample_boundary(scene.shape, scene.samples);
      const Certifier cpu(scene.shape, cage, samples);
      compute::DenseCertifier gpu(ctx, scene.shape, cage, samples);
      compute::DenseCertifier direct(ctx, scene.shape, cage, samples, direct_options());
      CHECK(gpu.uses_basis());
      CHECK_FALSE(direct.uses_basis());
      REQUIRE(gpu.breakpoint_count() == cpu.breakpoint_count());
      CHECK(gpu.segments().points == cpu.segments().points);
      std::vector<HarmonicMap> keys;
      for (const Keyframe& k : scene.keyframes)
        if (k.coefficients) keys.push_back(*k.coefficients);
      REQUIRE(!keys.empty());
      for (size_t k = 0; k < keys.size(); ++k) {
        INFO(path.stem().string() << " keyframe " << k);
        const CertificateResult c = cpu.certify(keys[k]), g = gpu.certify(keys[k]);
        CHECK(c.certified);  // bundled keyframes are certified
        check_agree(c, g, agree);
        {
          INFO("values from the cage (no basis matrix)");
          check_agree(c, direct.certify(keys[k]), agree);
        }
        // Naive coefficient blends between keyframes (not harmonic interpolation): often
        // folded, so both verdicts are exercised on real shapes.
        if (k + 1 < keys.size())
          for (double t : {0.5, 0.8}) {
            INFO("coefficient blend t = " << t);
            check_agree(cpu.certify(blend(keys[k], keys[k + 1], t)), gpu.certify(blend(keys[k], keys[k + 1], t)),
                        agree);
          }
      }
    }
    INFO(agree.summary());
    CHECK(agree.verdict_mismatch == 0);
    CHECK(agree.certified > 0);
    UNSCOPED_INFO("assets: " << agree.summary());
    CHECK(agree.maps > 0);
  });
}

TEST_CASE("dense certificate agrees with the CPU on interpolated frames", "[vulkan][certify]") {
  with_vulkan([](compute::Context& ctx) {
    Agreement agree;
    for (const char* name : {"annulus.json", "bar_holes.json"}) {
      const Scene scene = load_scene(std::filesystem::path(HSI_ASSETS_DIR) / name);
      const auto setup = make_shape_setup(scene, 2000);
      std::vector<double> times;
      std::vector<HarmonicMap> keys;
      for (const Keyframe& k : scene.keyframes) {
        times.push_back(k.time);
        keys.push_back(*k.coefficients);
      }
      Interpolator interp(*setup, times, keys);
      compute::DenseCertifier gpu(ctx, setup->shape, setup->cage, setup->G);
      const double t0 = times.front(), t1 = times.back();
      for (double s : {0.3, 0.55}) {
        const FrameResult f = interp.frame(t0 + s * (t1 - t0));
        INFO(name << " frame at s = " << s << ": " << f.message);
        REQUIRE(f.certified);
        const CertificateResult c = setup->certifier.certify(f.map), g = gpu.certify(f.map);
        check_agree(c, g, agree);
      }
    }
    UNSCOPED_INFO("interpolated frames: " << agree.summary());
    CHECK(agree.certified == agree.maps);
  });
}

TEST_CASE("dense certificate agrees with the CPU on the folded-map corpus", "[vulkan][certify]") {
  with_vulkan([](compute::Context& ctx) {
    Agreement agree;
    SECTION("an orientation-reversing map fails at the same place") {
      const Shape s = test::annulus();
      const Cage cage = build_cage(s);
      const BoundarySamples g = sample_boundary(s, 500);
      compute::DenseCertifier gpu(ctx, s, cage, g);
      const HarmonicMap m = affine_map(cage, 1.0, 1.2, 0.0);
      const CertificateResult c = Certifier(s, cage, g).certify(m), r = gpu.certify(m);
      CHECK_FALSE(r.certified);
      check_agree(c, r, agree);
      CHECK(r.reason.find("folds") != std::string::npos);
      // The failing segment says why: a real fold at a breakpoint.
      const auto& st = gpu.last_status();
      CHECK(std::count(st.begin(), st.end(), compute::SegmentStatus::kFolds) > 0);
    }
    SECTION("a zero of f_z inside fails by the argument principle on both") {
      for (const auto& [shape, w0] : {std::pair<Shape, cd>{test::disc(1.0, 128), cd(0.2, -0.1)},
                                      std::pair<Shape, cd>{test::annulus(1.0, 0.4, 128), cd(0.7, 0.0)}}) {
        const Cage cage = build_cage(shape);
        const BoundarySamples g = sample_boundary(shape, 2000);
        HarmonicMap m{VectorXcd::Zero(basis_size(cage)), VectorXcd::Zero(basis_size(cage))};
        int j = 0;
        for (const Loop& l : cage.loops)
          for (const cd& z : l) m.phi(j++) = (z - w0) * (z - w0) / 2.0;
        compute::DenseCertifier gpu(ctx, shape, cage, g);
        const CertificateResult c = Certifier(shape, cage, g).certify(m), r = gpu.certify(m);
        CHECK_FALSE(r.certified);
        CHECK(r.winding == 1);
        CHECK(r.reason.find("zero") != std::string::npos);
        check_agree(c, r, agree);
      }
    }
    SECTION("a fold on a tiny arc between breakpoints is caught at the same point") {
      const Shape s = test::disc(1.0, 64);
      Cage cage;
      cage.loops.push_back(test::circle(0, 1.02, 64));
      for (cd& z : cage.loops[0]) z *= std::polar(1.0, std::numbers::pi / 64);
      check_cage(s, cage);
      const int j = 5;
      const cd peak = cage.loops[0][j] / std::abs(cage.loops[0][j]);
      const BoundarySamples dense = sample_boundary(s, 50000);
      const double peak_val = evaluate_basis(cage, dense.points, kBasisD).D.col(j).cwiseAbs().maxCoeff();
      HarmonicMap m = identity_map(cage);
      m.psi(j) = 1.01 / peak_val;
      const BoundarySamples g = sample_boundary(s, 32);
      compute::DenseCertifier gpu(ctx, s, cage, g);
      const CertificateResult c = Certifier(s, cage, g).certify(m), r = gpu.certify(m);
      CHECK_FALSE(r.certified);
      CHECK(r.observed_sigma2_min > 0);  // every breakpoint looks fine
      CHECK(std::abs(r.fail_point - peak) < 0.1);
      check_agree(c, r, agree);
      // Slightly weaker: injective, certified by both after subdivision.
      m.psi(j) = 0.9 / peak_val;
      const CertificateResult c2 = Certifier(s, cage, g).certify(m), r2 = gpu.certify(m);
      CHECK(r2.certified);
      CHECK(r2.subdivisions > 0);
      check_agree(c2, r2, agree);
    }
    SECTION("random maps across the fold boundary: identical verdicts") {
      for (const Shape& s : {test::annulus(1.0, 0.4, 96), test::bar_with_holes()}) {
        const Cage cage = build_cage(s);
        const BoundarySamples g = sample_boundary(s, 400);
        const Certifier cpu(s, cage, g);
        compute::DenseCertifier gpu(ctx, s, cage, g);
        compute::DenseCertifier direct(ctx, s, cage, g, direct_options());
        for (unsigned seed = 0; seed < 24; ++seed) {
          const double amp = 0.02 + 0.03 * (seed % 12);
          const HarmonicMap m = random_perturbation(cage, 1000 + seed, amp);
          INFO("seed " << seed << " amp " << amp);
          const CertificateResult c = cpu.certify(m);
          check_agree(c, gpu.certify(m), agree);
          INFO("values from the cage (no basis matrix)");
          check_agree(c, direct.certify(m), agree);
        }
      }
      CHECK(agree.certified > 0);
      CHECK(agree.rejected > 0);
    }
    SECTION("small depth caps and piece budgets fail at the same piece") {
      const Shape s = test::bar_with_holes();
      const Cage cage = build_cage(s);
      const BoundarySamples g = sample_boundary(s, 8);  // coarse: subdivision is needed
      const Certifier cpu(s, cage, g);
      compute::DenseCertifier gpu(ctx, s, cage, g);
      const HarmonicMap m = random_perturbation(cage, 77, 0.15);
      for (const auto& [depth, pieces] : {std::pair{14, 4096L}, std::pair{3, 4096L}, std::pair{14, 5L}, std::pair{0, 1L}}) {
        CertificateOptions o;
        o.max_depth = depth;
        o.max_pieces_per_segment = pieces;
        INFO("max_depth " << depth << ", max_pieces " << pieces);
        check_agree(cpu.certify(m, o), gpu.certify(m, o), agree);
      }
      CHECK(agree.certified > 0);
      CHECK(agree.rejected > 0);
      CertificateOptions o;
      o.max_depth = 3;
      CHECK_FALSE(gpu.certify(m, o).certified);
      const auto& st = gpu.last_status();
      CHECK(std::count(st.begin(), st.end(), compute::SegmentStatus::kUndecided) > 0);
    }
    UNSCOPED_INFO("folded-map corpus: " << agree.summary());
    CHECK(agree.verdict_mismatch == 0);
  });
}

TEST_CASE("dense certificate: stop at first failure, refusals", "[vulkan][certify]") {
  with_vulkan([](compute::Context& ctx) {
    const Shape s = test::annulus(1.0, 0.4, 96);
    const Cage cage = build_cage(s);
    const BoundarySamples g = sample_boundary(s, 400);
    const Certifier cpu(s, cage, g);
    compute::DenseCertifier gpu(ctx, s, cage, g);

    SECTION("stop_at_first_failure keeps the verdict (the line search's mode)") {
      CertificateOptions fast;
      fast.stop_at_first_failure = true;
      int rejected = 0;
      for (unsigned seed = 0; seed < 12; ++seed) {
        const HarmonicMap m = random_perturbation(cage, 2000 + seed, 0.02 + 0.03 * seed);
        const CertificateResult c = cpu.certify(m), r = gpu.certify(m, fast);
        INFO("seed " << seed);
        CHECK(r.certified == c.certified);
        rejected += !r.certified;
        if (!r.certified) CHECK(r.fail_loop >= 0);
      }
      CHECK(rejected > 0);
    }
    SECTION("wrong sizes, too deep, non-finite") {
      CHECK_THROWS_AS(gpu.certify(HarmonicMap{VectorXcd::Zero(2), VectorXcd::Zero(2)}), InputError);
      CertificateOptions deep;
      deep.max_depth = compute::DenseCertifier::kMaxDepth + 1;
      CHECK_THROWS_AS(gpu.certify(identity_map(cage), deep), InputError);
      HarmonicMap m = identity_map(cage);
      m.psi(3) = cd(0, INFINITY);
      const CertificateResult r = gpu.certify(m);
      CHECK_FALSE(r.certified);
      CHECK(r.reason == cpu.certify(m).reason);
      // Still works after the refusals.
      CHECK(gpu.certify(identity_map(cage)).certified);
      // A cage that does not belong to the shape.
      CHECK_THROWS_AS(compute::DenseCertifier(ctx, test::bar_with_holes(), cage, sample_boundary(test::bar_with_holes(), 100)),
                      InputError);
    }
    SECTION("identity: certified with σ1 = σ2 = 1") {
      const CertificateResult r = gpu.certify(identity_map(cage));
      CHECK(r.certified);
      CHECK(r.sigma1_max == Approx(1).margin(1e-6));
      CHECK(r.sigma2_min == Approx(1).margin(1e-6));
      CHECK(r.sigma2_min <= 1);
      CHECK(r.sigma1_max >= 1);
    }
  });
}
