// The Vulkan compute backend against the CPU reference: dense evaluation of the
// harmonic map (f, f_z, conj f_zbar, distortion fields, inside mask) on every bundled
// asset. Runs for real on whatever Vulkan device the loader finds (lavapipe on a
// machine without a GPU) with the validation layer on; any validation message fails
// the test. Without any Vulkan device the tests WARN and pass, unless the
// environment sets HSI_REQUIRE_VULKAN=1 (CI does), which turns that into a failure.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <memory>

#include "hsi/compute/dense_eval.h"
#include "hsi/compute/vulkan_context.h"
#include "hsi/harmonic_map.h"
#include "test_shapes.h"
#include "vulkan_test.h"

using namespace hsi;

namespace {

using test::with_vulkan;

struct SceneMaps {
  std::string name;
  Shape shape;
  Cage cage;
  std::vector<HarmonicMap> maps;  // the stored keyframe coefficients, else one affine map
};

SceneMaps load_asset(const std::filesystem::path& path) {
  const Scene scene = load_scene(path);
  SceneMaps s{path.stem().string(), scene.shape, scene_cage(scene), {}};
  for (const Keyframe& k : scene.keyframes)
    if (k.coefficients) s.maps.push_back(*k.coefficients);
  if (s.maps.empty()) s.maps.push_back(affine_map(s.cage, {1.1, 0.3}, {0.2, -0.1}, {0.5, -0.2}));
  return s;
}

double max_abs(const VectorXcd& v) { return v.size() ? v.cwiseAbs().maxCoeff() : 0.0; }

// max_i |gpu_i − cpu_i| / max_i |cpu_i|: error relative to the field's magnitude.
double relative_error(const std::vector<cd>& gpu, const VectorXcd& cpu) {
  REQUIRE(static_cast<Eigen::Index>(gpu.size()) == cpu.size());
  double err = 0;
  for (size_t i = 0; i < gpu.size(); ++i) err = std::max(err, std::abs(gpu[i] - cpu(static_cast<Eigen::Index>(i))));
  return err / std::max(max_abs(cpu), 1e-300);
}

struct Fields {
  double sigma1, sigma2, distortion, dirichlet;
  int det_sign;
};
Fields fields_from(cd f_z, cd fzbar_conj) {
  const double a = std::abs(f_z), b = std::abs(fzbar_conj);
  const double s1 = a + b, s2 = a - b, det = std::norm(f_z) - std::norm(fzbar_conj);
  return {s1, s2, s1 / s2, 0.5 * (s1 * s1 + 1 / (s1 * s1) + s2 * s2 + 1 / (s2 * s2)), (det > 0) - (det < 0)};
}

bool close(double a, double b, double rel) { return std::abs(a - b) <= rel * std::max({std::abs(a), std::abs(b), 1e-300}); }

constexpr double kDoubleTol = 1e-9;  // the stated double-precision tolerance (relative)
constexpr double kFloatTol = 1e-3;   // the stated float-fallback tolerance (relative; ~3e-4 seen)

}  // namespace

TEST_CASE("Vulkan context: device, validation layer live, clear errors", "[vulkan]") {
  SECTION("device and RAII buffers") with_vulkan([](compute::Context& ctx) {
    INFO("device: " << ctx.info().name << " (" << ctx.info().type_name() << ")");
    CHECK(!ctx.info().name.empty());
    CHECK(ctx.validation_enabled());
    CHECK(ctx.info().api_version >= VK_API_VERSION_1_2);
    // A buffer whose size is not a multiple of anything still works through RAII.
    compute::Buffer b(ctx, 100, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, compute::MemoryUse::kUpload);
    const std::vector<uint8_t> bytes(100, 7);
    b.write(bytes.data(), 100);
    std::vector<uint8_t> back(100);
    b.read(back.data(), 100);
    CHECK(back == bytes);
    CHECK_THROWS_AS(b.write(bytes.data(), 100, 1), compute::VulkanError);
    compute::Buffer moved = std::move(b);
    CHECK(!b);
    CHECK(moved.size() == 100);
  });

  SECTION("the messenger records a real validation error") {
    compute::ContextOptions o;
    o.validation = true;
    std::unique_ptr<compute::Context> ctx;
    try {
      ctx = std::make_unique<compute::Context>(o);
    } catch (const compute::VulkanUnavailable& e) {
      if (test::env_set("HSI_REQUIRE_VULKAN")) FAIL(e.what());
      WARN("skipping: " << e.what());
      return;
    }
    // usage = 0 violates VUID-VkBufferCreateInfo-usage-requiredbitmask; harmless otherwise.
    VkBufferCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
    info.size = 64;
    info.usage = 0;
    VkBuffer raw = VK_NULL_HANDLE;
    if (vkCreateBuffer(ctx->device(), &info, nullptr, &raw) == VK_SUCCESS) vkDestroyBuffer(ctx->device(), raw, nullptr);
    CHECK(ctx->validation_log()->error_count() >= 1);
    CHECK(ctx->validation_log()->summary().find("usage") != std::string::npos);

    // Synchronization validation is on too: two writes without a barrier are a hazard.
    ctx->validation_log()->clear();
    compute::Buffer b(*ctx, 256, VK_BUFFER_USAGE_TRANSFER_DST_BIT, compute::MemoryUse::kDeviceLocal);
    ctx->submit_and_wait([&](VkCommandBuffer cmd) {
      vkCmdFillBuffer(cmd, b.handle(), 0, 256, 0u);
      vkCmdFillBuffer(cmd, b.handle(), 0, 256, 1u);
    });
    CHECK(ctx->validation_log()->summary().find("SYNC-HAZARD-WRITE-AFTER-WRITE") != std::string::npos);
  }

  SECTION("asking for a device that does not exist names the devices found") {
    try {
      const compute::Context probe;
    } catch (const compute::VulkanUnavailable& e) {
      if (test::env_set("HSI_REQUIRE_VULKAN")) FAIL(e.what());
      WARN("skipping: " << e.what());
      return;
    }
    compute::ContextOptions o;
    o.device_name = "no-such-device-hsi";
    try {
      compute::Context ctx(o);
      FAIL("a context was created for a device that does not exist");
    } catch (const compute::VulkanUnavailable& e) {
      CHECK(std::string(e.what()).find("no-such-device-hsi") != std::string::npos);
    }
  }
}

TEST_CASE("Vulkan dense evaluation matches the CPU map on every asset", "[vulkan]") {
  with_vulkan([](compute::Context& ctx) {
    compute::DenseEvaluator eval(ctx);
    INFO("device: " << ctx.info().name << ", double: " << eval.double_precision());
    REQUIRE(eval.double_precision());  // lavapipe and desktop GPUs have shaderFloat64
    for (const auto& path : test::asset_scenes()) {
      const SceneMaps s = load_asset(path);
      const std::vector<cd> points = test::interior_points(s.shape, 3000);
      for (size_t k = 0; k < s.maps.size(); ++k) {
        INFO(s.name << " map " << k);
        const HarmonicMap& map = s.maps[k];
        const MapValues cpu = evaluate_map(s.cage, map, points);
        const compute::DenseField gpu = eval.evaluate_points(s.cage, map, points);
        REQUIRE(gpu.size() == points.size());
        CHECK(gpu.inside.empty());
        const double ef = relative_error(gpu.f, cpu.f), ez = relative_error(gpu.f_z, cpu.f_z),
                     eb = relative_error(gpu.fzbar_conj, cpu.fzbar_conj);
        INFO("relative errors: f " << ef << ", f_z " << ez << ", conj f_zbar " << eb);
        CHECK(ef <= kDoubleTol);
        CHECK(ez <= kDoubleTol);
        CHECK(eb <= kDoubleTol * std::max(1.0, max_abs(cpu.f_z) / std::max(max_abs(cpu.fzbar_conj), 1e-300)));

        // The distortion fields: the shader's formulas on its own f_z (tight), and the
        // CPU's values (to the evaluation tolerance, where the map is well-conditioned).
        const double scale = max_abs(cpu.f_z) + max_abs(cpu.fzbar_conj);
        int worst_self = 0, worst_cpu = 0;
        for (size_t i = 0; i < points.size(); ++i) {
          const Fields self = fields_from(gpu.f_z[i], gpu.fzbar_conj[i]);
          const bool ok_self = close(gpu.sigma1[i], self.sigma1, 1e-14) && close(gpu.sigma2[i], self.sigma2, 1e-12) &&
                               close(gpu.distortion[i], self.distortion, 1e-12) &&
                               close(gpu.dirichlet[i], self.dirichlet, 1e-12) && gpu.det_sign[i] == self.det_sign;
          worst_self += !ok_self;
          const Fields ref = fields_from(cpu.f_z(static_cast<Eigen::Index>(i)), cpu.fzbar_conj(static_cast<Eigen::Index>(i)));
          if (std::abs(ref.sigma2) < 1e-3 * scale) continue;  // near a fold: σ2's relative error blows up
          const bool ok_cpu = std::abs(gpu.sigma1[i] - ref.sigma1) <= kDoubleTol * scale &&
                              std::abs(gpu.sigma2[i] - ref.sigma2) <= kDoubleTol * scale &&
                              close(gpu.distortion[i], ref.distortion, 1e-6) &&
                              close(gpu.dirichlet[i], ref.dirichlet, 1e-6) && gpu.det_sign[i] == ref.det_sign;
          worst_cpu += !ok_cpu;
        }
        CHECK(worst_self == 0);
        CHECK(worst_cpu == 0);
      }
    }
  });
}

TEST_CASE("Vulkan grid evaluation: agrees with points, CPU and the inside mask", "[vulkan]") {
  with_vulkan([](compute::Context& ctx) {
    compute::DenseEvaluator eval(ctx);
    for (const auto& path : test::asset_scenes()) {
      const SceneMaps s = load_asset(path);
      const HarmonicMap& map = s.maps.back();
      const compute::Grid grid = compute::Grid::covering(bounding_box(s.shape), 96);
      INFO(s.name << ": grid " << grid.width << " x " << grid.height);
      const compute::DenseField g = eval.evaluate_grid(s.cage, map, grid, &s.shape);
      REQUIRE(g.size() == grid.size());
      REQUIRE(g.inside.size() == grid.size());
      CHECK(g.width == grid.width);
      CHECK(g.height == grid.height);

      // The inside mask is point_in_shape, point for point.
      const std::vector<cd> pts = grid.points();
      int mask_mismatch = 0, inside_count = 0;
      std::vector<cd> inside_pts;
      std::vector<size_t> inside_idx;
      for (size_t k = 0; k < pts.size(); ++k) {
        const bool in = point_in_shape(s.shape, pts[k]);
        mask_mismatch += (g.inside[k] != 0) != in;
        inside_count += in;
        if (in) {
          inside_pts.push_back(pts[k]);
          inside_idx.push_back(k);
        }
      }
      CHECK(mask_mismatch == 0);
      CHECK(inside_count > 0);

      // Grid evaluation = point evaluation at the same coordinates (the same shader
      // arithmetic, so equal to rounding).
      const compute::DenseField p = eval.evaluate_points(s.cage, map, pts);
      double worst = 0;
      for (size_t k = 0; k < pts.size(); ++k) {
        const double sc = std::abs(p.f[k]) + std::abs(p.f_z[k]) + std::abs(p.fzbar_conj[k]);
        if (!std::isfinite(sc)) continue;  // exactly on the cage: singular either way
        const double d = std::abs(g.f[k] - p.f[k]) + std::abs(g.f_z[k] - p.f_z[k]) +
                         std::abs(g.fzbar_conj[k] - p.fzbar_conj[k]);
        worst = std::max(worst, d / std::max(sc, 1e-300));
        CHECK(g.det_sign[k] == p.det_sign[k]);
      }
      CHECK(worst <= 1e-13);

      // And the CPU at the grid points inside the shape.
      const MapValues cpu = evaluate_map(s.cage, map, inside_pts);
      std::vector<cd> gf, gz, gb;
      for (size_t k : inside_idx) {
        gf.push_back(g.f[k]);
        gz.push_back(g.f_z[k]);
        gb.push_back(g.fzbar_conj[k]);
      }
      CHECK(relative_error(gf, cpu.f) <= kDoubleTol);
      CHECK(relative_error(gz, cpu.f_z) <= kDoubleTol);
    }
  });
}

TEST_CASE("Vulkan dense evaluation: known maps, folds, passes, skipping, errors", "[vulkan]") {
  with_vulkan([](compute::Context& ctx) {
    const Shape shape = test::bar_with_holes();
    const Cage cage = build_cage(shape);
    const std::vector<cd> points = test::interior_points(shape, 5000, 11);

    SECTION("identity: f = w, f_z = 1, f_zbar = 0, no distortion") {
      compute::DenseEvaluator eval(ctx);
      const compute::DenseField d = eval.evaluate_points(cage, identity_map(cage), points);
      for (size_t i = 0; i < points.size(); ++i) {
        CHECK(std::abs(d.f[i] - points[i]) <= 1e-11);
        CHECK(std::abs(d.f_z[i] - 1.0) <= 1e-11);
        CHECK(std::abs(d.fzbar_conj[i]) <= 1e-11);
        CHECK(d.distortion[i] == Approx(1.0).epsilon(1e-10));
        CHECK(d.dirichlet[i] == Approx(2.0).epsilon(1e-10));
        CHECK(d.det_sign[i] == 1);
      }
    }

    SECTION("an orientation-reversing affine map has det J < 0 everywhere") {
      compute::DenseEvaluator eval(ctx);
      const cd a(0.3, 0.1), b(1.2, -0.4), c(2.0, 1.0);
      const compute::DenseField d = eval.evaluate_points(cage, affine_map(cage, a, b, c), points);
      for (size_t i = 0; i < points.size(); ++i) {
        CHECK(std::abs(d.f[i] - (a * points[i] + b * std::conj(points[i]) + c)) <= 1e-10);
        CHECK(d.det_sign[i] == -1);
        CHECK(d.sigma2[i] < 0);
      }
    }

    SECTION("many passes give the same result as one") {
      compute::DenseEvalOptions o;
      o.max_points_per_pass = 1000;
      compute::DenseEvaluator small(ctx, o), big(ctx);
      const HarmonicMap map = affine_map(cage, {0.9, 0.2}, {0.1, 0.05}, {0.0, 0.0});
      const compute::DenseField a = small.evaluate_points(cage, map, points), b = big.evaluate_points(cage, map, points);
      CHECK(small.last_stats().passes == 5);
      CHECK(big.last_stats().passes == 1);
      CHECK(a.f == b.f);
      CHECK(a.dirichlet == b.dirichlet);
      // A grid in passes too (the row-major index crosses pass boundaries mid-row).
      const compute::Grid grid = compute::Grid::covering(bounding_box(shape), 77);
      const compute::DenseField ga = small.evaluate_grid(cage, map, grid, &shape), gb = big.evaluate_grid(cage, map, grid, &shape);
      CHECK(ga.f == gb.f);
      CHECK(ga.inside == gb.inside);
    }

    SECTION("staged readback (the discrete-GPU path) gives the same result") {
      compute::DenseEvalOptions o;
      o.force_staging = true;
      o.max_points_per_pass = 2048;
      compute::DenseEvaluator staged(ctx, o), direct(ctx);
      const HarmonicMap map = affine_map(cage, {0.9, 0.2}, {0.1, 0.05}, {0.3, 0.0});
      const compute::DenseField a = staged.evaluate_points(cage, map, points), b = direct.evaluate_points(cage, map, points);
      CHECK(staged.last_stats().passes == 3);
      CHECK(a.f == b.f);
      CHECK(a.f_z == b.f_z);
      CHECK(a.fzbar_conj == b.fzbar_conj);
      CHECK(a.sigma1 == b.sigma1);
      CHECK(a.dirichlet == b.dirichlet);
      CHECK(a.det_sign == b.det_sign);
    }

    SECTION("skip_outside leaves points outside the shape unevaluated") {
      compute::DenseEvalOptions o;
      o.skip_outside = true;
      compute::DenseEvaluator skip(ctx, o), full(ctx);
      const HarmonicMap map = identity_map(cage);
      const compute::Grid grid = compute::Grid::covering(bounding_box(shape), 64);
      const compute::DenseField a = skip.evaluate_grid(cage, map, grid, &shape), b = full.evaluate_grid(cage, map, grid, &shape);
      REQUIRE(a.inside == b.inside);
      int outside = 0;
      for (size_t k = 0; k < a.size(); ++k) {
        if (a.inside[k]) {
          CHECK(a.f[k] == b.f[k]);
        } else {
          ++outside;
          CHECK(std::isnan(a.f[k].real()));
          CHECK(a.det_sign[k] == 0);
        }
      }
      CHECK(outside > 0);
    }

    SECTION("float fallback agrees to its stated tolerance on every asset") {
      compute::DenseEvalOptions o;
      o.precision = compute::Precision::kFloat;
      compute::DenseEvaluator eval(ctx, o);
      CHECK(!eval.double_precision());
      for (const auto& path : test::asset_scenes()) {
        const SceneMaps s = load_asset(path);
        const std::vector<cd> pts = test::interior_points(s.shape, 1000);
        const MapValues cpu = evaluate_map(s.cage, s.maps.back(), pts);
        const compute::DenseField gpu = eval.evaluate_points(s.cage, s.maps.back(), pts);
        CHECK(!gpu.double_precision);
        const double ef = relative_error(gpu.f, cpu.f), ez = relative_error(gpu.f_z, cpu.f_z);
        INFO(s.name << ": float relative errors f " << ef << ", f_z " << ez);
        CHECK(ef <= kFloatTol);
        CHECK(ez <= kFloatTol);
      }
    }

    SECTION("a map of the wrong size is refused with a clear message") {
      compute::DenseEvaluator eval(ctx);
      HarmonicMap bad = identity_map(cage);
      bad.phi.conservativeResize(bad.phi.size() - 1);
      try {
        eval.evaluate_points(cage, bad, points);
        FAIL("a map of the wrong size was accepted");
      } catch (const InputError& e) {
        const std::string msg = e.what();
        INFO(msg);
        CHECK(msg.find("coefficients") != std::string::npos);
        CHECK(msg.find(std::to_string(basis_size(cage))) != std::string::npos);
      }
      compute::Grid grid = compute::Grid::covering(bounding_box(shape), 8);
      grid.spacing = {0.0, 1.0};
      CHECK_THROWS_AS(eval.evaluate_grid(cage, identity_map(cage), grid), InputError);
      // The evaluator still works after a refusal.
      CHECK(eval.evaluate_points(cage, identity_map(cage), points).size() == points.size());
    }

    SECTION("no points: an empty field and no GPU work") {
      compute::DenseEvaluator eval(ctx);
      const compute::DenseField d = eval.evaluate_points(cage, identity_map(cage), {});
      CHECK(d.size() == 0);
      CHECK(eval.last_stats().passes == 0);
    }
  });
}

TEST_CASE("Vulkan grid mask: rows with many crossings and shapes with many holes fall back exactly", "[vulkan]") {
  with_vulkan([](compute::Context& ctx) {
    // A comb: 40 teeth, so a row through them crosses 80 edges (over the 64 a row
    // keeps); and a plate with 40 square holes (over the 32 loops of the row mask).
    Shape comb;
    comb.outer = {{0, 0}, {40, 0}};
    for (int t = 39; t >= 0; --t) {
      comb.outer.push_back({t + 1.0, 10.0});
      comb.outer.push_back({t + 0.5, 10.0});
      comb.outer.push_back({t + 0.5, 2.0});
      comb.outer.push_back({t + 0.0, 2.0 + 0.01 * t});
    }
    Shape plate;
    plate.outer = {{0, 0}, {41, 0}, {41, 3}, {0, 3}};
    for (int h = 0; h < 40; ++h) {
      const double x = h + 0.6;
      plate.holes.push_back({{x, 1}, {x, 2}, {x + 0.5, 2}, {x + 0.5, 1}});
    }
    for (const Shape* s : {&comb, &plate}) {
      const BoundingBox box = bounding_box(*s);
      Cage cage;
      const cd lo = box.lo - cd(5, 5), hi = box.hi + cd(5, 5);
      cage.loops = {{lo, {hi.real(), lo.imag()}, hi, {lo.real(), hi.imag()}}};
      const HarmonicMap map = identity_map(cage);
      compute::DenseEvaluator eval(ctx);
      const compute::Grid grid = compute::Grid::covering(box, 400, 97);
      const compute::DenseField g = eval.evaluate_grid(cage, map, grid, s);
      const std::vector<cd> pts = grid.points();
      int mismatch = 0, inside = 0;
      for (size_t k = 0; k < pts.size(); ++k) {
        const bool in = point_in_shape(*s, pts[k]);
        inside += in;
        mismatch += (g.inside[k] != 0) != in;
      }
      INFO(s->holes.size() << " holes, " << s->outer.size() << " outer vertices: " << inside << " inside");
      CHECK(inside > 1000);
      CHECK(mismatch == 0);
    }
  });
}
