// Offscreen rendering (compute/renderer.h) on whatever Vulkan device the loader finds
// (lavapipe on a machine without a GPU), with the validation layer on: any message
// fails the test. Pixels are checked against what the map must produce (texture
// colours where the shape maps, background in holes and outside, the colour map,
// overlays, the red of an uncertified frame), and a few frames of bundled scenes
// against golden images in tests/golden/ with a perceptual tolerance.
//
// Goldens: HSI_UPDATE_GOLDEN=1 ./hsi_tests "[golden]" rewrites tests/golden/*.png
// from this machine's rendering (see tests/golden/README.md); look at them before
// committing. Without a Vulkan device the tests WARN and pass, unless
// HSI_REQUIRE_VULKAN=1 (CI) turns that into a failure.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>

#include "hsi/compute/renderer.h"
#include "hsi/compute/vulkan_context.h"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/shape_setup.h"
#include "hsi/triangulate.h"
#include "test_shapes.h"
#include "vulkan_test.h"

using namespace hsi;
using Catch::Matchers::Contains;

namespace {

using test::env_set;
using test::with_vulkan;

// A 2 × 1.5 rectangle with a rectangular hole right of centre.
Shape framed_shape() {
  return normalize(Shape{test::rect(-1, -0.75, 1, 0.75), {test::rect(0.2, -0.3, 0.6, 0.3)}});
}
constexpr std::array<double, 4> kRect = {-1, -0.75, 1, 0.75};

// A linear gradient: R grows left to right, G top to bottom, B = 128.
RgbaImage gradient(int w, int h) {
  RgbaImage img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* p = img.at(x, y);
      p[0] = static_cast<uint8_t>(std::lround(255.0 * x / (w - 1)));
      p[1] = static_cast<uint8_t>(std::lround(255.0 * y / (h - 1)));
      p[2] = 128;
      p[3] = 255;
    }
  return img;
}

// The world point at the centre of pixel (x, y).
cd world_at(const compute::View& v, int x, int y) {
  return {v.world_center.real() + (x + 0.5 - v.pixel_center.real()) / v.pixels_per_unit,
          v.world_center.imag() - (y + 0.5 - v.pixel_center.imag()) / v.pixels_per_unit};
}

// Signed distance to the shape's boundary: > 0 inside, < 0 outside or in a hole.
double signed_distance(const Shape& s, cd p) { return (point_in_shape(s, p) ? 1 : -1) * boundary_distance(s, p); }

int max_channel_diff(const uint8_t* a, const uint8_t* b) {
  int d = 0;
  for (int c = 0; c < 4; ++c) d = std::max(d, std::abs(int(a[c]) - int(b[c])));
  return d;
}

// Every pixel test runs with both rasterizers (renderer.h): they must draw the same picture.
#define FOR_EACH_RASTERIZER()                                                                               \
  const bool use_compute = GENERATE(false, true);                                                        \
  const compute::Rasterizer rasterizer = use_compute ? compute::Rasterizer::kCompute : compute::Rasterizer::kGraphics; \
  INFO("rasterizer: " << rasterizer_name(rasterizer))

const char* rasterizer_name(compute::Rasterizer r) {
  return r == compute::Rasterizer::kCompute ? "compute" : r == compute::Rasterizer::kGraphics ? "graphics" : "auto";
}

compute::RendererOptions with_rasterizer(compute::Rasterizer r, compute::RendererOptions o = {}) {
  o.rasterizer = r;
  return o;
}

struct Setup {
  Shape shape = framed_shape();
  Cage cage = build_cage(shape);
  TriMesh mesh;
  Setup(double edge = 0.05) {
    TriangulateOptions o;
    o.max_edge = edge;
    mesh = triangulate(shape, o);
  }
};

// Solves f(w) = a w + b conj(w) + c for w.
cd affine_inverse(cd a, cd b, cd c, cd q) {
  // [Re; Im] of a w + b conj(w) = M [x; y] with M = [[ar + br, -ai + bi], [ai + bi, ar - br]].
  const double m00 = a.real() + b.real(), m01 = -a.imag() + b.imag(), m10 = a.imag() + b.imag(), m11 = a.real() - b.real();
  const cd r = q - c;
  const double det = m00 * m11 - m01 * m10;
  return {(m11 * r.real() - m01 * r.imag()) / det, (-m10 * r.real() + m00 * r.imag()) / det};
}

// Perceptual comparison with a golden image: mean absolute difference over all
// channels, and the fraction of pixels differing by more than 48/255 in some channel
// (a shifted edge, a missing line). Rasterizers differ in edge coverage and
// rounding, never in what is drawn where.
struct Difference {
  double mean_abs = 0, outlier_fraction = 0;
};
Difference compare(const RgbaImage& a, const RgbaImage& b) {
  Difference d;
  size_t outliers = 0, n = static_cast<size_t>(a.width) * a.height;
  double sum = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const uint8_t *p = a.at(x, y), *q = b.at(x, y);
      for (int c = 0; c < 4; ++c) sum += std::abs(int(p[c]) - int(q[c]));
      outliers += max_channel_diff(p, q) > 48;
    }
  d.mean_abs = sum / (4.0 * static_cast<double>(n));
  d.outlier_fraction = static_cast<double>(outliers) / static_cast<double>(n);
  return d;
}

void check_golden(const RgbaImage& img, const std::string& name) {
  const std::filesystem::path golden = std::filesystem::path(HSI_TESTS_DIR) / "golden" / (name + ".png");
  if (env_set("HSI_UPDATE_GOLDEN")) {
    std::filesystem::create_directories(golden.parent_path());
    write_png(golden, img);
    WARN("HSI_UPDATE_GOLDEN: wrote " << golden.string());
    return;
  }
  INFO("golden " << golden.string() << " (regenerate with HSI_UPDATE_GOLDEN=1, see tests/golden/README.md)");
  REQUIRE(std::filesystem::exists(golden));
  const RgbaImage ref = read_png(golden);
  REQUIRE(ref.width == img.width);
  REQUIRE(ref.height == img.height);
  const Difference d = compare(img, ref);
  if (d.mean_abs > 1.5 || d.outlier_fraction > 0.01) {
    const std::filesystem::path dir = std::filesystem::path(HSI_TEST_TMP) / "golden";
    std::filesystem::create_directories(dir);
    write_png(dir / (name + ".actual.png"), img);
    RgbaImage diff(img.width, img.height, {0, 0, 0, 255});
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        const int m = std::min(255, 4 * max_channel_diff(img.at(x, y), ref.at(x, y)));
        diff.at(x, y)[0] = static_cast<uint8_t>(m);
      }
    write_png(dir / (name + ".diff.png"), diff);
    INFO("wrote " << (dir / (name + ".actual.png")).string() << " and .diff.png");
  }
  INFO("mean abs diff " << d.mean_abs << "/255, pixels off by > 48: " << 100 * d.outlier_fraction << "%");
  CHECK(d.mean_abs <= 1.5);
  CHECK(d.outlier_fraction <= 0.01);
}

// A view showing where the map sends the shape (its boundary and handles), as the
// hsi tool frames it.
compute::View frame_view(const Shape& shape, const Cage& cage, const HarmonicMap& map, int w, int h, double margin) {
  std::vector<cd> pts;
  for (int l = 0; l < shape.loop_count(); ++l)
    for (const cd& z : subdivide_edges(shape.loop(l), bounding_box(shape).diagonal() / 200)) pts.push_back(z);
  const MapValues v = evaluate_map(cage, map, pts);
  BoundingBox box{v.f(0), v.f(0)};
  for (Eigen::Index k = 0; k < v.f.size(); ++k) {
    box.lo = {std::min(box.lo.real(), v.f(k).real()), std::min(box.lo.imag(), v.f(k).imag())};
    box.hi = {std::max(box.hi.real(), v.f(k).real()), std::max(box.hi.imag(), v.f(k).imag())};
  }
  return compute::View::fit(box, w, h, margin);
}

}  // namespace

TEST_CASE("render: the identity map shows the texture unchanged, clipped at the outline and the hole", "[vulkan][render]") {
  FOR_EACH_RASTERIZER();
  with_vulkan([&](compute::Context& ctx) {
    const Setup s;
    const int W = 256, H = 192;
    const RgbaImage tex = gradient(W, H);
    compute::Renderer r(ctx, W, H, with_rasterizer(rasterizer));
    CHECK(r.msaa_samples() >= 1);
    r.set_mesh(s.mesh);
    r.set_texture(tex, kRect);
    // The texture's rectangle fills the image exactly: texel (x, y) lies under pixel (x, y).
    const compute::View view = compute::View::fit({{-1, -0.75}, {1, 0.75}}, W, H);
    REQUIRE(view.pixels_per_unit == Approx(128.0));
    compute::RenderStyle style;
    style.background = {1, 1, 1, 1};
    const RgbaImage img = r.render(s.cage, identity_map(s.cage), view, style);
    REQUIRE(img.width == W);
    REQUIRE(img.height == H);
    int inside = 0, hole = 0, worst_inside = 0, worst_hole = 0;
    const uint8_t white[4] = {255, 255, 255, 255};
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const double d = signed_distance(s.shape, world_at(view, x, y)) * view.pixels_per_unit;
        if (d > 1.5) {
          ++inside;
          worst_inside = std::max(worst_inside, max_channel_diff(img.at(x, y), tex.at(x, y)));
        } else if (d < -1.5) {
          ++hole;
          worst_hole = std::max(worst_hole, max_channel_diff(img.at(x, y), white));
        }
      }
    CHECK(inside > 30000);
    CHECK(hole > 2000);  // the hole is 0.4 × 0.6 = 51 × 77 px
    CHECK(worst_inside <= 2);
    CHECK(worst_hole == 0);
  });
}

TEST_CASE("render: nearest filtering draws each texel of a small texture as a crisp block", "[vulkan][render]") {
  FOR_EACH_RASTERIZER();
  with_vulkan([&](compute::Context& ctx) {
    const Setup s;
    const int W = 256, H = 192;
    // An 8 x 6 checkerboard of black and white texels over the whole image: 32 px per texel.
    RgbaImage tex(8, 6);
    for (int y = 0; y < 6; ++y)
      for (int x = 0; x < 8; ++x) {
        const uint8_t v = (x + y) % 2 ? 255 : 0;
        const uint8_t px[4] = {v, v, v, 255};
        std::copy(px, px + 4, tex.at(x, y));
      }
    const compute::View view = compute::View::fit({{-1, -0.75}, {1, 0.75}}, W, H);
    compute::RenderStyle style;
    // Pixels inside the shape whose value is neither black nor white: blended texels.
    auto blended = [&](TextureFilter f) {
      compute::Renderer r(ctx, W, H, with_rasterizer(rasterizer));
      r.set_mesh(s.mesh);
      r.set_texture(tex, kRect, f);
      CHECK(r.texture_filter() == f);
      const RgbaImage img = r.render(s.cage, identity_map(s.cage), view, style);
      int grey = 0, wrong_texel = 0;
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          if (signed_distance(s.shape, world_at(view, x, y)) * view.pixels_per_unit <= 1.5) continue;
          const uint8_t v = img.at(x, y)[0];
          grey += v > 8 && v < 247;
          wrong_texel += (v > 128) != (((x / 32) + (y / 32)) % 2 == 1);  // the texel under the pixel's centre
        }
      return std::pair{grey, wrong_texel};
    };
    const auto [nearest_grey, nearest_wrong] = blended(TextureFilter::Nearest);
    const auto [linear_grey, linear_wrong] = blended(TextureFilter::Linear);
    CHECK(nearest_grey == 0);
    CHECK(nearest_wrong == 0);
    CHECK(linear_grey > 5000);  // bilinear blends across every texel edge (the default is unchanged)
  });
}

TEST_CASE("render: an affine map moves the texture with the shape, holes stay empty", "[vulkan][render]") {
  FOR_EACH_RASTERIZER();
  with_vulkan([&](compute::Context& ctx) {
    const Setup s;
    const int W = 240, H = 240;
    const RgbaImage tex = gradient(200, 150);
    const cd a(0.8, 0.35), b(0.12, -0.05), c(0.3, -0.2);
    const HarmonicMap map = affine_map(s.cage, a, b, c);
    compute::Renderer r(ctx, W, H, with_rasterizer(rasterizer));
    r.set_mesh(s.mesh);
    r.set_texture(tex, kRect);
    const compute::View view = frame_view(s.shape, s.cage, map, W, H, 10);
    compute::RenderStyle style;
    style.background = {0, 0, 0, 0};  // transparent
    const RgbaImage img = r.render(s.cage, map, view, style);
    const double sigma2 = std::abs(a) - std::abs(b);
    // The expected colour: the gradient's value at the rest point, as texel centres define it.
    auto expected = [&](cd w, int channel) {
      const double u = (w.real() - kRect[0]) / (kRect[2] - kRect[0]), v = (kRect[3] - w.imag()) / (kRect[3] - kRect[1]);
      const double t = channel == 0 ? (u * tex.width - 0.5) / (tex.width - 1) : (v * tex.height - 0.5) / (tex.height - 1);
      return 255.0 * std::clamp(t, 0.0, 1.0);
    };
    int inside = 0, outside = 0, bad_inside = 0, bad_outside = 0, in_hole = 0;
    double worst = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const cd w = affine_inverse(a, b, c, world_at(view, x, y));
        const double d = signed_distance(s.shape, w) * sigma2 * view.pixels_per_unit;  // ≤ the distance in pixels
        const uint8_t* p = img.at(x, y);
        if (d > 3) {
          ++inside;
          const double e = std::max(std::abs(p[0] - expected(w, 0)), std::abs(p[1] - expected(w, 1)));
          worst = std::max(worst, e);
          bad_inside += e > 4 || std::abs(p[2] - 128) > 2 || p[3] != 255;
        } else if (d < -1.5 * (std::abs(a) + std::abs(b)) / sigma2) {
          ++outside;
          in_hole += point_in_loop(s.shape.outer, w);
          bad_outside += p[3] != 0;
        }
      }
    INFO("worst colour error inside: " << worst);
    CHECK(inside > 10000);
    CHECK(in_hole > 500);
    CHECK(outside > 10000);
    CHECK(bad_inside == 0);
    CHECK(bad_outside == 0);
  });
}

TEST_CASE("render: the distortion overlay shows sigma1/sigma2 through the colour map", "[vulkan][render]") {
  FOR_EACH_RASTERIZER();
  with_vulkan([&](compute::Context& ctx) {
    const Setup s(0.1);
    const cd a(1.1, 0.2), b(0.3, 0.1);
    const double kappa = (std::abs(a) + std::abs(b)) / (std::abs(a) - std::abs(b));
    const HarmonicMap map = affine_map(s.cage, a, b, 0);
    compute::Renderer r(ctx, 160, 160, with_rasterizer(rasterizer));
    r.set_mesh(s.mesh);
    r.set_texture(gradient(64, 48), kRect);
    const compute::View view = frame_view(s.shape, s.cage, map, 160, 160, 8);
    for (const double t : {0.0, 0.3, 0.75}) {
      compute::RenderStyle style;
      style.overlays = compute::kOverlayDistortion;
      style.distortion_opacity = 1;
      style.distortion_lo = kappa - t;  // κ lands at t of the range [κ − t, κ − t + 1]
      style.distortion_hi = kappa - t + 1;
      const RgbaImage img = r.render(s.cage, map, view, style);
      const auto cm = compute::colormap(t);
      const cd centre = view.to_pixel(a * cd(-0.5, 0) + b * std::conj(cd(-0.5, 0)));
      const uint8_t* p = img.at(static_cast<int>(centre.real()), static_cast<int>(centre.imag()));
      INFO("t = " << t << ": pixel " << int(p[0]) << "," << int(p[1]) << "," << int(p[2]) << " colour map "
                  << cm[0] * 255 << "," << cm[1] * 255 << "," << cm[2] * 255);
      for (int c = 0; c < 3; ++c) CHECK(std::abs(p[c] - cm[static_cast<size_t>(c)] * 255) <= 2.5);
    }
  });
  // The host colour map is viridis: dark purple to yellow.
  const auto lo = compute::colormap(0), hi = compute::colormap(1);
  CHECK(lo[2] > lo[1]);
  CHECK(hi[0] > 0.9);
  CHECK(hi[1] > 0.85);
  CHECK(hi[2] < 0.2);
}

TEST_CASE("render: boundary lines, handle discs, and the red of an uncertified frame", "[vulkan][render]") {
  FOR_EACH_RASTERIZER();
  with_vulkan([&](compute::Context& ctx) {
    const Setup s;
    const int W = 200, H = 160;
    compute::Renderer r(ctx, W, H, with_rasterizer(rasterizer));
    const std::vector<cd> handles = {{-0.6, 0.4}, {0.4, 0.5}};
    r.set_mesh(s.mesh, handles);
    const HarmonicMap id = identity_map(s.cage);
    const compute::View view = compute::View::fit({{-1, -0.75}, {1, 0.75}}, W, H, 16);
    auto px = [&](const RgbaImage& img, cd w) {
      const cd q = view.to_pixel(w);
      return img.at(static_cast<int>(q.real()), static_cast<int>(q.imag()));
    };
    compute::RenderStyle style;
    style.fill = {0.5f, 0.5f, 0.5f, 1};  // no texture: a grey fill
    style.overlays = compute::kOverlayBoundary | compute::kOverlayHandles;
    style.boundary_width_px = 3;
    style.handle_radius_px = 8;
    style.handle_outline_px = 3;
    const RgbaImage img = r.render(s.cage, id, view, style);
    CHECK(!r.has_texture());
    const uint8_t* grey = px(img, {-0.5, -0.3});
    CHECK(std::abs(grey[0] - 128) <= 1);
    CHECK(grey[0] == grey[1]);
    CHECK(grey[1] == grey[2]);
    // On the outline and the hole's edge: the boundary colour.
    for (const cd& on : {cd(0, -0.75), cd(-1, 0.1), cd(0.2, 0.0), cd(0.4, 0.3)}) {
      const uint8_t* p = px(img, on);
      INFO("boundary point " << on);
      CHECK(max_channel_diff(p, std::array<uint8_t, 4>{13, 18, 31, 255}.data()) <= 20);
    }
    // Handle centres: the handle colour; the outline ring is dark.
    for (const cd& h : handles) {
      const uint8_t* p = px(img, h);
      CHECK(max_channel_diff(p, std::array<uint8_t, 4>{255, 158, 26, 255}.data()) <= 3);
      const uint8_t* ring = px(img, h + cd(6.5 / view.pixels_per_unit, 0));
      CHECK(ring[0] < 100);
    }
    // Without overlays, those pixels are the fill or the background.
    style.overlays = compute::kOverlayNone;
    const RgbaImage plain = r.render(s.cage, id, view, style);
    CHECK(max_channel_diff(px(plain, handles[0]), grey) <= 1);

    // Uncertified: red border around the image, the shape tinted red.
    style.uncertified = true;
    const RgbaImage red = r.render(s.cage, id, view, style);
    for (const auto& [x, y] : std::vector<std::pair<int, int>>{{0, 0}, {W - 1, H - 1}, {W / 2, 1}, {1, H / 2}, {W - 2, H / 2}}) {
      const uint8_t* p = red.at(x, y);
      INFO("border pixel " << x << ", " << y);
      CHECK(p[0] > 200);
      CHECK(p[1] < 30);
      CHECK(p[2] < 30);
    }
    const uint8_t* tinted = px(red, {-0.5, -0.3});
    CHECK(tinted[0] > tinted[1] + 80);
    CHECK(tinted[0] > tinted[2] + 80);
    const uint8_t* bg = px(red, {0.4, 0.0});  // in the hole: still the background, not tinted
    CHECK(max_channel_diff(bg, std::array<uint8_t, 4>{255, 255, 255, 255}.data()) == 0);
  });
}

TEST_CASE("render: float precision, 1 sample, refusals", "[vulkan][render]") {
  FOR_EACH_RASTERIZER();
  with_vulkan([&](compute::Context& ctx) {
    const Setup s(0.1);
    compute::RendererOptions o;
    o.msaa_samples = 1;
    o.evaluation.precision = compute::Precision::kFloat;
    compute::Renderer r(ctx, 96, 72, with_rasterizer(rasterizer, o));
    CHECK(r.msaa_samples() == 1);
    CHECK(r.rasterizer() == rasterizer);
    CHECK(!r.double_precision());
    const compute::View view = compute::View::fit({{-1, -0.75}, {1, 0.75}}, 96, 72);
    CHECK_THROWS_WITH(r.render(s.cage, identity_map(s.cage), view, {}), Contains("no mesh"));
    r.set_mesh(s.mesh);
    r.set_texture(gradient(96, 72), kRect);
    const RgbaImage img = r.render(s.cage, identity_map(s.cage), view, {});
    CHECK(max_channel_diff(img.at(20, 36), gradient(96, 72).at(20, 36)) <= 2);
    HarmonicMap bad = identity_map(s.cage);
    bad.phi.conservativeResize(bad.phi.size() - 1);
    CHECK_THROWS_AS(r.render(s.cage, bad, view, {}), InputError);
    compute::RenderStyle style;
    style.distortion_hi = style.distortion_lo;
    CHECK_THROWS_WITH(r.render(s.cage, identity_map(s.cage), view, style), Contains("hi > lo"));
    CHECK_THROWS_AS(r.set_texture(gradient(8, 8), {1, 0, 0, 1}), InputError);
    TriMesh broken = s.mesh;
    broken.triangles[0][1] = broken.vertex_count();
    CHECK_THROWS_WITH(r.set_mesh(broken), Contains("outside"));
    CHECK_THROWS_AS(compute::Renderer(ctx, 0, 10), InputError);
  });
  CHECK_THROWS_AS(compute::View::fit({{0, 0}, {0, 0}}, 10, 10), InputError);
  CHECK_THROWS_WITH(read_png(std::filesystem::path(HSI_TEST_TMP) / "no_such.png"), Contains("no_such.png"));
}

TEST_CASE("render: PNG round trip", "[render]") {
  const RgbaImage img = gradient(37, 21);
  const auto path = std::filesystem::path(HSI_TEST_TMP) / "render_roundtrip.png";
  std::filesystem::create_directories(path.parent_path());
  write_png(path, img);
  const RgbaImage back = read_png(path);
  CHECK(back.width == 37);
  CHECK(back.height == 21);
  CHECK(back.pixels == img.pixels);
}

// --- goldens: bundled scenes, a keyframe and interpolated frames ---------------------------

namespace {

struct Bundled {
  Scene scene;
  Cage cage;
  TriMesh mesh;
  RgbaImage texture;
  std::array<double, 4> rect;
  explicit Bundled(const std::string& name) : scene(load_scene(std::filesystem::path(HSI_ASSETS_DIR) / (name + ".json"))) {
    cage = scene_cage(scene);
    TriangulateOptions o;
    o.max_edge = edge_for_vertex_count(scene.shape, 6000);
    mesh = triangulate(scene.shape, o);
    texture = read_png(scene.texture_path());
    rect = scene.texture_rect_or_bounds();
  }
  std::vector<HarmonicMap> keyframes() const {
    std::vector<HarmonicMap> out;
    for (const Keyframe& k : scene.keyframes) {
      REQUIRE(k.coefficients);
      out.push_back(*k.coefficients);
    }
    return out;
  }
};

}  // namespace

TEST_CASE("render goldens: keyframes and interpolated frames of bundled scenes", "[vulkan][render][golden]") {
  FOR_EACH_RASTERIZER();
  with_vulkan([&](compute::Context& ctx) {
    SECTION("bar_holes: keyframe 1, interpolated t = 0.5 (distortion), uncertified marking") {
      const Bundled b("bar_holes");
      const std::vector<HarmonicMap> keys = b.keyframes();
      compute::Renderer r(ctx, 256, 160, with_rasterizer(rasterizer));
      r.set_mesh(b.mesh, b.scene.handles);
      r.set_texture(b.texture, b.rect);
      compute::RenderStyle style;
      style.overlays = compute::kOverlayBoundary | compute::kOverlayHandles;
      style.boundary_width_px = 1.5f;
      style.handle_radius_px = 4;
      style.handle_outline_px = 1;
      const compute::View key_view = frame_view(b.scene.shape, b.cage, keys[1], 256, 160, 8);
      check_golden(r.render(b.cage, keys[1], key_view, style), "bar_holes_key1");

      // An interpolated frame, half way between keyframes 0 and 1.
      const auto setup = make_shape_setup(b.scene, 2000);
      std::vector<double> times;
      for (const Keyframe& k : b.scene.keyframes) times.push_back(k.time);
      Interpolator interp(*setup, times, keys);
      const FrameResult f = interp.frame(0.5 * (times[0] + times[1]));
      REQUIRE(f.certified);
      REQUIRE(!f.keyframe);
      const compute::View view = frame_view(b.scene.shape, setup->cage, f.map, 256, 160, 8);
      style.overlays = compute::kOverlayDistortion | compute::kOverlayBoundary;
      style.distortion_lo = 1;
      style.distortion_hi = 1.5;
      check_golden(r.render(setup->cage, f.map, view, style), "bar_holes_t0.5_distortion");
      style.overlays = compute::kOverlayNone;
      style.uncertified = true;
      check_golden(r.render(setup->cage, f.map, view, style), "bar_holes_t0.5_uncertified");
    }
    SECTION("sprite_pretzel: the sprite's own alpha, on a transparent background") {
      const Bundled b("sprite_pretzel");
      const std::vector<HarmonicMap> keys = b.keyframes();
      compute::Renderer r(ctx, 192, 192, with_rasterizer(rasterizer));
      r.set_mesh(b.mesh, b.scene.handles);
      r.set_texture(b.texture, b.rect);
      compute::RenderStyle style;
      style.background = {0, 0, 0, 0};
      const HarmonicMap& k = keys.back();
      check_golden(r.render(b.cage, k, frame_view(b.scene.shape, b.cage, k, 192, 192, 6), style), "pretzel_last_key");
    }
  });
}

TEST_CASE("render: given positions equal to f(vertices) draw the image of the map path", "[vulkan][render]") {
  FOR_EACH_RASTERIZER();
  with_vulkan([&](compute::Context& ctx) {
    // A bundled keyframe (a real harmonic map, not affine), every overlay on.
    const Bundled b("two_holes");
    const HarmonicMap key = b.keyframes().back();
    const int W = 256, H = 192;
    compute::Renderer r(ctx, W, H, with_rasterizer(rasterizer));
    r.set_mesh(b.mesh, b.scene.handles);
    r.set_texture(b.texture, b.rect);
    const compute::View view = frame_view(b.scene.shape, b.cage, key, W, H, 8);
    const MapValues v = evaluate_map(b.cage, key, b.mesh.vertices);
    std::vector<cd> pos(b.mesh.vertices.size());
    std::vector<double> kappa(pos.size());
    double kappa_max = 1;
    for (size_t i = 0; i < pos.size(); ++i) {
      const auto k = static_cast<Eigen::Index>(i);
      pos[i] = v.f(k);
      const double a = std::abs(v.f_z(k)), c = std::abs(v.fzbar_conj(k));
      kappa[i] = (a + c) / (a - c);
      kappa_max = std::max(kappa_max, kappa[i]);
    }
    REQUIRE(kappa_max > 1.05);  // the overlay shows something
    const std::vector<cd> handles = map_points(b.cage, key, b.scene.handles);
    compute::RenderStyle style;
    style.overlays = compute::kOverlayDistortion | compute::kOverlayBoundary | compute::kOverlayHandles;
    style.distortion_lo = 1;
    style.distortion_hi = kappa_max;
    style.distortion_opacity = 0.6f;
    const RgbaImage from_map = r.render(b.cage, key, view, style);
    const RgbaImage given = r.render(pos, kappa, view, style, handles);
    const Difference d = compare(given, from_map);
    int worst = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) worst = std::max(worst, max_channel_diff(given.at(x, y), from_map.at(x, y)));
    INFO("mean abs diff " << d.mean_abs << "/255, worst pixel " << worst);
    CHECK(d.mean_abs < 0.05);
    CHECK(worst <= 3);

    // The test can fail: moved positions, other distortion values, or no handles differ.
    std::vector<cd> moved = pos;
    for (cd& p : moved) p += cd(4 / view.pixels_per_unit, 0);
    CHECK(compare(r.render(moved, kappa, view, style, handles), from_map).mean_abs > 1);
    std::vector<double> flat(kappa.size(), 1.0);
    CHECK(compare(r.render(pos, flat, view, style, handles), from_map).mean_abs > 1);
    CHECK(compare(r.render(pos, kappa, view, style), from_map).outlier_fraction > 1e-3);

    // Refusals: sizes, non-finite positions, a handle count that is neither 0 nor all.
    CHECK_THROWS_WITH(r.render(std::span(pos).first(pos.size() - 1), kappa, view, style), Contains("one position"));
    std::vector<cd> nan_pos = pos;
    nan_pos[7] = cd(std::nan(""), 0);
    CHECK_THROWS_WITH(r.render(nan_pos, kappa, view, style), Contains("position 7 is not finite"));
    CHECK_THROWS_WITH(r.render(pos, kappa, view, style, std::span(handles).first(1)), Contains("handle positions"));
  });
}

TEST_CASE("render: an unwelded mesh shows per-triangle distortion flat", "[vulkan][render]") {
  FOR_EACH_RASTERIZER();
  const Setup s(0.25);
  const compute::UnweldedMesh u = compute::unweld(s.mesh);
  REQUIRE(u.mesh.vertex_count() == 3 * s.mesh.triangle_count());
  REQUIRE(u.mesh.triangle_count() == s.mesh.triangle_count());
  REQUIRE(u.mesh.boundary_edges.size() == s.mesh.boundary_edges.size());
  for (size_t e = 0; e < s.mesh.boundary_edges.size(); ++e)
    for (size_t k = 0; k < 2; ++k)
      CHECK(u.mesh.vertices[static_cast<size_t>(u.mesh.boundary_edges[e][k])] ==
            s.mesh.vertices[static_cast<size_t>(s.mesh.boundary_edges[e][k])]);
  for (size_t v = 0; v < u.source.size(); ++v) CHECK(u.mesh.vertices[v] == s.mesh.vertices[static_cast<size_t>(u.source[v])]);
  with_vulkan([&](compute::Context& ctx) {
    const int W = 200, H = 150;
    compute::Renderer r(ctx, W, H, with_rasterizer(rasterizer));
    r.set_mesh(u.mesh);
    const compute::View view = compute::View::fit({{-1, -0.75}, {1, 0.75}}, W, H);
    // Triangle t gets κ = 1 + (t mod 5) / 4 over the range [1, 2]: five colours.
    std::vector<double> kappa(u.mesh.vertices.size());
    for (size_t v = 0; v < kappa.size(); ++v) kappa[v] = 1 + static_cast<double>((v / 3) % 5) / 4;
    compute::RenderStyle style;
    style.overlays = compute::kOverlayDistortion;
    style.distortion_opacity = 1;
    const RgbaImage img = r.render(u.mesh.vertices, kappa, view, style);
    int checked = 0, bad = 0;
    for (size_t t = 0; t < u.mesh.triangles.size(); ++t) {
      const auto& tri = u.mesh.triangles[t];
      const cd a = u.mesh.vertices[static_cast<size_t>(tri[0])], b = u.mesh.vertices[static_cast<size_t>(tri[1])],
               c = u.mesh.vertices[static_cast<size_t>(tri[2])];
      const cd q = view.to_pixel((a + b + c) / 3.0);
      // Only where the pixel lies well inside the triangle (≥ 2 px from its edges).
      auto dist = [&](cd p0, cd p1) {
        const cd e = view.to_pixel(p1) - view.to_pixel(p0);
        return std::abs((std::conj(e) * (q - view.to_pixel(p0))).imag()) / std::abs(e);
      };
      if (std::min({dist(a, b), dist(b, c), dist(c, a)}) < 2.5) continue;
      ++checked;
      const auto cm = compute::colormap(static_cast<double>(t % 5) / 4);
      const uint8_t* p = img.at(static_cast<int>(q.real()), static_cast<int>(q.imag()));
      for (size_t ch = 0; ch < 3; ++ch) bad += std::abs(p[ch] - cm[ch] * 255) > 2.5;
    }
    CHECK(checked > 20);
    CHECK(bad == 0);
  });
}

TEST_CASE("render: a frame recorded into the caller's submission is render()'s image; marks time its parts",
          "[vulkan][render]") {
  FOR_EACH_RASTERIZER();
  with_vulkan([&](compute::Context& ctx) {
    const Bundled b("two_holes");
    const HarmonicMap key = b.keyframes().back();
    const int W = 160, H = 120;
    compute::Renderer r(ctx, W, H, with_rasterizer(rasterizer));
    r.set_mesh(b.mesh, b.scene.handles);
    r.set_texture(b.texture, b.rect);
    const compute::View view = frame_view(b.scene.shape, b.cage, key, W, H, 8);
    compute::RenderStyle style;
    style.overlays = compute::kOverlayBoundary | compute::kOverlayHandles;
    CHECK_THROWS_WITH(r.read_frame(), Contains("no frame drawn yet"));
    const RgbaImage reference = r.render(b.cage, key, view, style);
    // Draw something else first, so read_frame() must return the recorded frame.
    r.draw(b.cage, identity_map(b.cage), view, style);
    REQUIRE(compare(r.read_frame(), reference).mean_abs > 1);
    ctx.submit_and_wait([&](VkCommandBuffer cmd) {
      ctx.mark(cmd);
      r.record(cmd, b.cage, key, view, style, true);
    });
    const RgbaImage recorded = r.read_frame();
    const Difference d = compare(recorded, reference);
    INFO("mean abs diff " << d.mean_abs << "/255");
    CHECK(d.mean_abs == 0);
    CHECK(d.outlier_fraction == 0);
    if (ctx.info().timestamp_valid_bits > 0) {
      // The marks of that submission (read_frame's own submission came after it, so
      // repeat the record to look at them).
      ctx.submit_and_wait([&](VkCommandBuffer cmd) {
        ctx.mark(cmd);
        r.record(cmd, b.cage, key, view, style, true);
      });
      const std::vector<double> marks = ctx.last_device_marks();
      REQUIRE(marks.size() == 2);
      CHECK(marks[0] >= 0);
      CHECK(marks[1] >= marks[0]);
      CHECK(ctx.last_device_ms() >= marks[1]);
    }
  });
}

TEST_CASE("render: the compute and graphics rasterizers draw the same frames of bundled scenes", "[vulkan][render]") {
  with_vulkan([](compute::Context& ctx) {
    compute::Renderer automatic(ctx, 16, 16);
    // kAuto: compute on GPUs, graphics on CPU devices (lavapipe rasterizes faster there).
    CHECK(automatic.rasterizer() == (ctx.info().is_cpu() ? compute::Rasterizer::kGraphics : compute::Rasterizer::kCompute));
    // A visibility buffer beyond one storage buffer (16384² pixels × 8 samples × 4 bytes
    // = 8 GiB) is refused before anything is allocated.
    compute::RendererOptions huge;
    huge.msaa_samples = 8;
    CHECK_THROWS_WITH(compute::Renderer(ctx, 16384, 16384, with_rasterizer(compute::Rasterizer::kCompute, huge)),
                      Contains("maxStorageBufferRange"));
    for (const std::string name : {"two_holes", "sprite_pretzel"}) {
      const Bundled b(name);
      const int W = 224, H = 176;
      for (const int samples : {1, 4, 8}) {
        compute::RendererOptions o;
        o.msaa_samples = samples;
        compute::Renderer graphics(ctx, W, H, with_rasterizer(compute::Rasterizer::kGraphics, o));
        compute::Renderer compute(ctx, W, H, with_rasterizer(compute::Rasterizer::kCompute, o));
        if (graphics.msaa_samples() != samples) continue;  // the device's graphics path lacks this count
        CHECK(compute.msaa_samples() == samples);
        for (compute::Renderer* r : {&graphics, &compute}) {
          r->set_mesh(b.mesh, b.scene.handles);
          r->set_texture(b.texture, b.rect);
        }
        for (const HarmonicMap& key : b.keyframes()) {
          compute::RenderStyle style;
          style.overlays = compute::kOverlayDistortion | compute::kOverlayBoundary | compute::kOverlayHandles;
          style.distortion_opacity = 0.5f;
          style.distortion_hi = 1.5;
          style.background = {0.2f, 0.3f, 0.4f, name == "sprite_pretzel" ? 0.0f : 1.0f};
          const compute::View view = frame_view(b.scene.shape, b.cage, key, W, H, 8);
          const RgbaImage a = graphics.render(b.cage, key, view, style), c = compute.render(b.cage, key, view, style);
          const Difference d = compare(c, a);
          INFO(name << ", " << samples << " samples: mean abs diff " << d.mean_abs << "/255, pixels off by > 48: "
                    << 100 * d.outlier_fraction << "%");
          // Edges differ by the rasterizers' rules for samples on an edge and their
          // rounding; with one sample a pixel is all one or all the other.
          CHECK(d.mean_abs <= (samples == 1 ? 1.0 : 0.5));
          CHECK(d.outlier_fraction <= (samples == 1 ? 0.01 : 0.002));
          // The tolerance can fail: the same frame 2 px to the right is far off.
          compute::View shifted = view;
          shifted.pixel_center += 2.0;
          CHECK(compare(c, graphics.render(b.cage, key, shifted, style)).mean_abs > 2);
        }
      }
    }
  });
}

namespace {

// A regular grid of nx × ny squares over [x0, x1] × [y0, y1], each split into two
// triangles along alternating diagonals; vertices jittered by up to `jitter` of a cell
// (fixed seed) unless 0.
TriMesh grid_mesh(int nx, int ny, double x0, double y0, double x1, double y1, double jitter) {
  TriMesh m;
  uint32_t state = 12345;
  auto rnd = [&] {
    state = state * 1664525u + 1013904223u;
    return (state >> 8) / double(1u << 24) - 0.5;
  };
  const double dx = (x1 - x0) / nx, dy = (y1 - y0) / ny;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const bool interior = i > 0 && i < nx && j > 0 && j < ny;
      m.vertices.push_back({x0 + dx * (i + (interior ? jitter * rnd() : 0)), y0 + dy * (j + (interior ? jitter * rnd() : 0))});
    }
  auto v = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if ((i + j) % 2 == 0) {
        m.triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
        m.triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
      } else {
        m.triangles.push_back({v(i, j), v(i + 1, j), v(i, j + 1)});
        m.triangles.push_back({v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)});
      }
    }
  return m;
}

}  // namespace

TEST_CASE("render: no cracks between triangles, large triangles, the last triangle on top", "[vulkan][render]") {
  FOR_EACH_RASTERIZER();
  with_vulkan([&](compute::Context& ctx) {
    const int W = 256, H = 192;
    const compute::View view = compute::View::fit({{-1, -0.75}, {1, 0.75}}, W, H);  // 128 px per unit
    compute::RenderStyle style;
    style.background = {0, 0, 0, 1};
    style.fill = {1, 1, 1, 1};
    for (const int samples : {1, 4}) {
      compute::RendererOptions o;
      o.msaa_samples = samples;
      // Fine grids put samples exactly on edges and vertices (unjittered: vertices on
      // pixel corners and centres) or anywhere (jittered); the coarse grid's triangles
      // span thousands of pixels (the compute path's workgroup-per-triangle pass).
      struct Case {
        int nx, ny;
        double jitter;
      };
      compute::Renderer r(ctx, W, H, with_rasterizer(rasterizer, o));
      for (const Case c : {Case{128, 96, 0.0}, Case{101, 77, 0.45}, Case{4, 3, 0.3}}) {
        // Inset by a quarter pixel: no sample lies on the outer edge.
        const double inset = 0.25 / view.pixels_per_unit;
        const TriMesh m = grid_mesh(c.nx, c.ny, -1 + inset, -0.75 + inset, 1 - inset, 0.75 - inset, c.jitter);
        r.set_mesh(m);  // a new mesh for a renderer that has drawn others
        const std::vector<double> kappa(m.vertices.size(), 1.0);
        const RgbaImage img = r.render(m.vertices, kappa, view, style);
        // (With 4 samples, the image's outermost pixels have samples outside the inset.)
        const int edge = samples == 1 ? 0 : 1;
        int holes = 0;
        for (int y = edge; y < H - edge; ++y)
          for (int x = edge; x < W - edge; ++x) holes += img.at(x, y)[0] != 255 || img.at(x, y)[1] != 255;
        INFO(samples << " samples, " << c.nx << " x " << c.ny << " grid, jitter " << c.jitter);
        CHECK(holes == 0);
        // Zoomed in 3x: every triangle at the image's sides is cut by it, and the
        // image lies inside the shape: all of it is the fill.
        compute::View zoomed = view;
        zoomed.pixels_per_unit *= 3;
        const RgbaImage z = r.render(m.vertices, kappa, zoomed, style);
        int off = 0;
        for (int y = 0; y < H; ++y)
          for (int x = 0; x < W; ++x) off += z.at(x, y)[0] != 255 || z.at(x, y)[1] != 255;
        CHECK(off == 0);
      }
    }
    // Two overlapping triangles (given geometry, no texture): triangle 1 (κ = 2, the top
    // of the colour map) is drawn after triangle 0 (κ = 1) and covers it where they overlap.
    TriMesh two;
    two.vertices = {{-0.8, -0.5}, {0.4, -0.5}, {-0.2, 0.6}, {-0.4, -0.6}, {0.8, -0.6}, {0.2, 0.5}};
    two.triangles = {{0, 1, 2}, {3, 4, 5}};
    compute::Renderer r(ctx, W, H, with_rasterizer(rasterizer));
    r.set_mesh(two);
    style.overlays = compute::kOverlayDistortion;
    style.distortion_opacity = 1;
    const RgbaImage img = r.render(two.vertices, std::vector<double>{1, 1, 1, 2, 2, 2}, view, style);
    auto at = [&](cd w) {
      const cd q = view.to_pixel(w);
      return img.at(static_cast<int>(q.real()), static_cast<int>(q.imag()));
    };
    const auto top = compute::colormap(1), below = compute::colormap(0);
    for (const auto& [w, cm] : {std::pair{cd(0.0, 0.0), top}, std::pair{cd(-0.6, -0.3), below}, std::pair{cd(0.6, -0.4), top}}) {
      INFO("at " << w);
      for (size_t ch = 0; ch < 3; ++ch) CHECK(std::abs(at(w)[ch] - cm[ch] * 255) <= 2.5);
    }
  });
}

TEST_CASE("render: the distortion legend's upper end is a round number at or above the largest value", "[render]") {
  CHECK(compute::round_distortion_hi(1.9) == Approx(2.0));   // steps of 0.25
  CHECK(compute::round_distortion_hi(5.49) == Approx(9.0));  // steps of 2
  CHECK(compute::round_distortion_hi(2.0) == Approx(2.0));   // already round
  CHECK(compute::round_distortion_hi(1.0) == Approx(1.001));  // the smallest span, 1e-3, in steps of 0.00025
  for (double hi : {1.01, 1.37, 3.3, 12.0, 250.0}) CHECK(compute::round_distortion_hi(hi) >= hi);
}

TEST_CASE("render: a mesh whose image overlaps itself shows the later layer alone, the same in both rasterizers",
          "[vulkan][render][overlap]") {
  // A bar [0, 7] x [-0.2, 0.2] rolled up by g(z) = exp((0.05 + i) z) (issue #20): its far
  // end lies over its near end. The grid's triangles go row by row (y), and the far
  // layer lies at larger y wherever the two overlap, so it is the later one there.
  // Translucent colour (fill alpha 0 under the colour map at half opacity) shows whether
  // anything of the layer below comes through: it must not, in either rasterizer.
  with_vulkan([](compute::Context& ctx) {
    const int W = 192, H = 192;
    const TriMesh m = grid_mesh(140, 8, 0.0, -0.2, 7.0, 0.2, 0.0);
    const auto g = [](cd z) { return std::exp(cd(0.05, 1.0) * z); };
    std::vector<cd> pos;
    std::vector<double> kappa;
    for (const cd& z : m.vertices) {
      pos.push_back(g(z));
      kappa.push_back(z.real() < 3.5 ? 1.0 : 2.0);  // near layer: colour map 0, far layer: colour map 1
    }
    const compute::View view = compute::View::fit({{-1.9, -1.9}, {1.9, 1.9}}, W, H);
    compute::RenderStyle style;
    style.background = {1, 1, 1, 1};
    style.fill = {0, 0, 0, 0};
    style.overlays = compute::kOverlayDistortion;
    style.distortion_opacity = 0.5f;
    style.distortion_lo = 1;
    style.distortion_hi = 2;
    // A point of the near layer that the far layer covers: z1 and, one turn on, z2.
    const cd z1(0.36, -0.16);
    const cd w = g(z1);
    REQUIRE(std::abs(w - g(z1 + cd(2 * std::numbers::pi, 0.1 * std::numbers::pi))) < 0.03);
    const auto far = compute::colormap(1);
    std::map<int, std::vector<RgbaImage>> images;  // per sample count: graphics, compute
    for (const int samples : {1, 4})
      for (const compute::Rasterizer ras : {compute::Rasterizer::kGraphics, compute::Rasterizer::kCompute}) {
        compute::RendererOptions o;
        o.msaa_samples = samples;
        compute::Renderer r(ctx, W, H, with_rasterizer(ras, o));
        if (r.msaa_samples() != samples) continue;
        r.set_mesh(m);
        const RgbaImage a = r.render(pos, kappa, view, style);
        const RgbaImage b = r.render(pos, kappa, view, style);
        INFO(rasterizer_name(ras) << ", " << samples << " samples");
        CHECK(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size()) == 0);  // deterministic
        // Where the layers overlap: the far layer's half-opaque colour over white, nothing
        // of the near layer's (which would pull it towards colour map 0).
        const cd q = view.to_pixel(w);
        const uint8_t* px = a.at(static_cast<int>(q.real()), static_cast<int>(q.imag()));
        for (size_t ch = 0; ch < 3; ++ch) CHECK(std::abs(px[ch] - (0.5 * far[ch] + 0.5) * 255) <= 2.5);
        images[samples].push_back(a);
      }
    REQUIRE(images[1].size() == 2);
    for (const auto& [samples, pair] : images) {
      if (pair.size() < 2) continue;
      const Difference d = compare(pair[0], pair[1]);
      INFO(samples << " samples, graphics vs compute: mean abs diff " << d.mean_abs << "/255, pixels off by > 48: "
                   << 100 * d.outlier_fraction << "%");
      CHECK(d.mean_abs <= (samples == 1 ? 1.0 : 0.5));
      CHECK(d.outlier_fraction <= (samples == 1 ? 0.01 : 0.002));
    }
  });
}

TEST_CASE("render: the triangulation's spatial order shows an overlapping layer whole, not speckled", "[vulkan][render][overlap]") {
  // The bar rolled over itself (as above), now meshed by triangulate(): its triangles
  // come in Hilbert-curve order of their rest centroids, so the far end (later on the
  // curve) covers the near end everywhere they overlap. CGAL's own face order, which
  // the renderers used to draw in, alternated the two layers triangle by triangle.
  with_vulkan([](compute::Context& ctx) {
    const int W = 256, H = 256;
    const Shape bar = normalize(Shape{test::rect(0, -0.2, 7, 0.2), {}});
    TriangulateOptions to;
    to.max_edge = 0.05;
    const TriMesh m = triangulate(bar, to);
    const cd c(0.05, 1.0);
    const auto g = [&](cd z) { return std::exp(c * z); };
    std::vector<cd> pos;
    std::vector<double> kappa;
    for (const cd& z : m.vertices) {
      pos.push_back(g(z));
      kappa.push_back(z.real() < 3.5 ? 1.0 : 2.0);
    }
    const compute::View view = compute::View::fit({{-1.9, -1.9}, {1.9, 1.9}}, W, H);
    compute::RenderStyle style;
    style.background = {1, 1, 1, 1};
    style.overlays = compute::kOverlayDistortion;
    style.distortion_opacity = 1;
    style.distortion_lo = 1;
    style.distortion_hi = 2;
    const auto far = compute::colormap(1);
    // Inside the bar by a margin (in rest units) that keeps pixels off the layers' edges.
    const auto inside = [](cd z) { return z.real() > 0.03 && z.real() < 6.97 && std::abs(z.imag()) < 0.17; };
    for (const compute::Rasterizer ras : {compute::Rasterizer::kGraphics, compute::Rasterizer::kCompute}) {
      compute::Renderer r(ctx, W, H, with_rasterizer(ras));
      r.set_mesh(m);
      const RgbaImage img = r.render(pos, kappa, view, style);
      int both = 0, wrong = 0;
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          const cd w = world_at(view, x, y);
          // The two preimages of w one turn apart: z_k = (Log w + 2 pi i k) / c.
          const double a = std::arg(w) < 0 ? std::arg(w) + 2 * std::numbers::pi : std::arg(w);
          const cd z0 = cd(std::log(std::abs(w)), a) / c, z1 = cd(std::log(std::abs(w)), a + 2 * std::numbers::pi) / c;
          if (!inside(z0) || !inside(z1)) continue;
          ++both;
          const uint8_t* px = img.at(x, y);
          bool ok = true;
          for (size_t ch = 0; ch < 3; ++ch) ok = ok && std::abs(px[ch] - far[ch] * 255) <= 2.5;
          wrong += !ok;
        }
      INFO(rasterizer_name(ras) << ": " << both << " pixels covered by both layers, " << wrong << " not the far layer's colour");
      CHECK(both > 80);  // 115 at 256 x 256
      CHECK(wrong == 0);
    }
  });
}
