// GPU playback of baked sequences (shaders/hsib_playback.glsl under Vulkan, on
// lavapipe without a GPU): the shader's positions of a blend of two frames match the
// C runtime's, for several instances of a mesh, and so do its singular values
// (hsib_singular_values, from derivative rows); the data layout (hsib_gpu_rows,
// hsib_gpu_derivative_rows, hsib_gpu_uniforms) reproduces the runtime by hand.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "hsi/baked_runtime.h"
#include "hsi/compute/hsib_playback.h"
#include "vulkan_test.h"

namespace {

struct Golden {
  hsib_sequence* s = nullptr;
  hsib_binding* b = nullptr;
  hsib_binding* bd = nullptr;  // the same vertices with derivative rows
  std::vector<float> xy;
  Golden() {
    // A version 1 file from the old baker (tests/golden/README.md): three frames of the annulus.
    const std::string path = std::string(HSI_TESTS_DIR) + "/golden/annulus_v1.hsib";
    char error[256];
    REQUIRE(hsib_open_file(path.c_str(), &s, error, sizeof error) == HSIB_OK);
    hsib_info info;
    hsib_get_info(s, &info);
    const int n = 40;  // grid points of the bounding box inside the cage
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) {
        const double x = info.bbox[0] + (info.bbox[2] - info.bbox[0]) * i / n, y = info.bbox[1] + (info.bbox[3] - info.bbox[1]) * j / n;
        if (hsib_point_region(s, x, y) != HSIB_REGION_OUTSIDE) {
          xy.push_back(static_cast<float>(x));
          xy.push_back(static_cast<float>(y));
        }
      }
    REQUIRE(xy.size() > 400);
    REQUIRE(hsib_bind(s, xy.data(), xy.size() / 2, 0, &b, error, sizeof error) == HSIB_OK);
    REQUIRE(hsib_bind_flags(s, xy.data(), xy.size() / 2, 0, nullptr, HSIB_BIND_DERIVATIVES, &bd, error, sizeof error) == HSIB_OK);
  }
  ~Golden() {
    hsib_unbind(bd);
    hsib_unbind(b);
    hsib_close(s);
  }
};

}  // namespace

TEST_CASE("GPU playback data reproduce the runtime by hand", "[hsib_gpu]") {
  Golden g;
  const hsib_blend blend{0, 1, 0.3f, 0};
  hsib_info info;
  hsib_get_info(g.s, &info);
  const uint32_t R = info.row_length, T = hsib_gpu_texels_per_vertex(g.s);
  CHECK(T == (R + 3) / 4);
  const uint32_t width = 7;  // any width: texel v*T + q, line after line
  std::vector<float> texels(hsib_gpu_rows_floats(g.b, width), -1.0f);
  REQUIRE(texels.size() % (4 * width) == 0);
  REQUIRE(hsib_gpu_rows(g.b, width, texels.data()) == HSIB_OK);
  std::vector<float> u(4 * (2 + R));
  REQUIRE(hsib_gpu_uniforms(g.s, &blend, u.data()) == HSIB_OK);
  CHECK(u[4] == 0.3f);
  CHECK(u[5] == static_cast<float>(R));
  std::vector<float> want(g.xy.size());
  REQUIRE(hsib_evaluate_blend(g.b, &blend, want.data(), 0) == HSIB_OK);
  std::vector<float> row(R);
  for (size_t v = 0; v < g.xy.size() / 2; v += 13) {
    REQUIRE(hsib_basis_row(g.s, g.xy[2 * v], g.xy[2 * v + 1], row.data()) == HSIB_OK);
    double a[4] = {0, 0, 0, 0};
    for (uint32_t k = 0; k < 4 * T; ++k) {
      const float r = texels[4 * (v * T) + k];
      if (k < R) CHECK(r == row[k]);
      else CHECK(r == 0.0f);  // padding
      if (k < R)
        for (int c = 0; c < 4; ++c) a[c] += double(r) * u[8 + 4 * k + c];
    }
    const double x = (1 - 0.3) * (a[0] + u[0]) + 0.3 * (a[2] + u[2]), y = (1 - 0.3) * (a[1] + u[1]) + 0.3 * (a[3] + u[3]);
    CHECK(std::abs(x - want[2 * v]) < 1e-5);
    CHECK(std::abs(y - want[2 * v + 1]) < 1e-5);
  }
  const hsib_blend bad{0, 9, 0.5f, 0};
  CHECK(hsib_gpu_uniforms(g.s, &bad, u.data()) == HSIB_ERROR_ARGUMENT);
}

TEST_CASE("GPU playback (Vulkan) matches the C runtime", "[vulkan][hsib_gpu]") {
  Golden g;
  hsi::test::with_vulkan([&](const hsi::compute::Context& ctx) {
    const uint32_t instances = 3;
    hsi::compute::HsibPlayback gpu(ctx, g.b, instances);
    for (const hsib_blend blend : {hsib_blend{0, 0, 0.0f, 0}, hsib_blend{1, 2, 0.25f, 0}, hsib_blend{0, 2, 0.9f, 0}}) {
      INFO("frames " << blend.frame0 << ", " << blend.frame1 << " at s = " << blend.s);
      gpu.set_blend(blend);
      gpu.run();
      const std::vector<float> got = gpu.positions();
      std::vector<float> want(g.xy.size());
      REQUIRE(hsib_evaluate_blend(g.b, &blend, want.data(), 0) == HSIB_OK);
      REQUIRE(got.size() == instances * want.size());
      double worst = 0;
      for (uint32_t i = 0; i < instances; ++i)
        for (size_t k = 0; k < want.size(); ++k) worst = std::max(worst, double(std::abs(got[i * want.size() + k] - want[k])));
      // float arithmetic in both, summed in another order: a few float ulps of the shape's size (about 2)
      CHECK(worst < 2e-5);
    }
    CHECK_THROWS_WITH(gpu.set_blend(hsib_blend{0, 7, 0.5f, 0}), Catch::Matchers::Contains("not a blend of this sequence"));
  });
}

TEST_CASE("GPU playback derivative rows reproduce the runtime's Jacobian by hand", "[hsib_gpu]") {
  Golden g;
  const hsib_blend blend{0, 2, 0.6f, 0};
  hsib_info info;
  hsib_get_info(g.s, &info);
  const uint32_t R = info.row_length, T = hsib_gpu_texels_per_vertex(g.s);
  const uint32_t width = 5;  // any width: texel 2(v*T + q) (d/dx) and 2(v*T + q) + 1 (d/dy), line after line
  std::vector<float> texels(hsib_gpu_derivative_rows_floats(g.bd, width), -1.0f);
  REQUIRE(!texels.empty());
  REQUIRE(texels.size() % (4 * width) == 0);
  CHECK(texels.size() >= 8ull * T * (g.xy.size() / 2));
  REQUIRE(hsib_gpu_derivative_rows(g.bd, width, texels.data()) == HSIB_OK);
  std::vector<float> u(4 * (2 + R));
  REQUIRE(hsib_gpu_uniforms(g.s, &blend, u.data()) == HSIB_OK);
  const size_t n = g.xy.size() / 2;
  std::vector<float> want(4 * n);
  REQUIRE(hsib_evaluate_jacobian_range(g.bd, &blend, 0, n, want.data(), 0) == HSIB_OK);
  std::vector<float> row(R), dx(R), dy(R);
  for (size_t v = 0; v < n; v += 11) {
    REQUIRE(hsib_basis_row_derivatives(g.s, g.xy[2 * v], g.xy[2 * v + 1], row.data(), dx.data(), dy.data()) == HSIB_OK);
    double fx[4] = {0, 0, 0, 0}, fy[4] = {0, 0, 0, 0};  // (x, y in frame 0, x, y in frame 1)
    for (uint32_t k = 0; k < 4 * T; ++k) {
      const float ex = texels[4 * (2 * (v * T + k / 4)) + k % 4], ey = texels[4 * (2 * (v * T + k / 4) + 1) + k % 4];
      if (k < R) {
        CHECK(ex == dx[k]);
        CHECK(ey == dy[k]);
        for (int c = 0; c < 4; ++c) {
          fx[c] += double(ex) * u[8 + 4 * k + c];
          fy[c] += double(ey) * u[8 + 4 * k + c];
        }
      } else {
        CHECK(ex == 0.0f);  // padding
        CHECK(ey == 0.0f);
      }
    }
    const double s = 0.6;
    const double J[4] = {(1 - s) * fx[0] + s * fx[2], (1 - s) * fx[1] + s * fx[3], (1 - s) * fy[0] + s * fy[2], (1 - s) * fy[1] + s * fy[3]};
    for (int k = 0; k < 4; ++k) CHECK(std::abs(J[k] - want[4 * v + k]) < 1e-5 * (1 + std::abs(J[k])));
  }
}

TEST_CASE("GPU playback (Vulkan) singular values match the C runtime", "[vulkan][hsib_gpu]") {
  Golden g;
  hsi::test::with_vulkan([&](const hsi::compute::Context& ctx) {
    const uint32_t instances = 2;
    CHECK_THROWS_WITH(hsi::compute::HsibPlayback(ctx, g.b, 1, hsi::compute::MemoryUse::kReadback, true),
                      Catch::Matchers::Contains("derivative rows"));
    hsi::compute::HsibPlayback plain(ctx, g.b, 1);
    CHECK_THROWS_WITH(plain.sigmas(), Catch::Matchers::Contains("distortion"));
    hsi::compute::HsibPlayback gpu(ctx, g.bd, instances, hsi::compute::MemoryUse::kReadback, true);
    for (const hsib_blend blend : {hsib_blend{0, 0, 0.0f, 0}, hsib_blend{1, 2, 0.25f, 0}, hsib_blend{0, 2, 0.9f, 0}}) {
      INFO("frames " << blend.frame0 << ", " << blend.frame1 << " at s = " << blend.s);
      gpu.set_blend(blend);
      gpu.run();
      const std::vector<float> got = gpu.sigmas(), got_xy = gpu.positions();
      const size_t n = g.xy.size() / 2;
      std::vector<float> want(2 * n), want_xy(2 * n);
      REQUIRE(hsib_evaluate_blend_distortion(g.bd, &blend, want.data(), 0) == HSIB_OK);
      REQUIRE(hsib_evaluate_blend(g.bd, &blend, want_xy.data(), 0) == HSIB_OK);
      REQUIRE(got.size() == instances * want.size());
      // Float sums of R products in another order: their rounding is relative to the
      // sum of the products' sizes, sum_r (|dx_r| + |dy_r|) |W_r|, not to sigma itself
      // (near the cage the derivative rows are large and cancel).
      hsib_info info;
      hsib_get_info(g.s, &info);
      const uint32_t R = info.row_length;
      std::vector<float> w(2 * R), row(R), dx(R), dy(R);
      REQUIRE(hsib_blend_weights(g.s, &blend, w.data(), nullptr) == HSIB_OK);
      std::vector<double> scale(n);
      for (size_t v = 0; v < n; ++v) {
        REQUIRE(hsib_basis_row_derivatives(g.s, g.xy[2 * v], g.xy[2 * v + 1], row.data(), dx.data(), dy.data()) == HSIB_OK);
        for (uint32_t r = 0; r < R; ++r) scale[v] += (std::abs(dx[r]) + std::abs(dy[r])) * (std::abs(w[2 * r]) + std::abs(w[2 * r + 1]));
      }
      double worst = 0, worst_xy = 0;
      for (uint32_t i = 0; i < instances; ++i)
        for (size_t v = 0; v < n; ++v) {
          for (int c = 0; c < 2; ++c) {
            worst = std::max(worst, double(std::abs(got[i * 2 * n + 2 * v + c] - want[2 * v + c])) / scale[v]);
            worst_xy = std::max(worst_xy, double(std::abs(got_xy[i * 2 * n + 2 * v + c] - want_xy[2 * v + c])));
          }
        }
      INFO("largest sigma difference " << worst << " of the products' size");
      CHECK(worst < 1e-6);  // a few float ulps (6e-8) of that size
      CHECK(worst_xy < 2e-5);
    }
  });
}
