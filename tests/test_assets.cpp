// The bundled assets (assets/*.json): every scene loads and validates, its texture is a
// readable PNG, and the scenes made by scripts/make_assets.py have the loops they
// are documented to have. Cages are covered elsewhere.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "hsi/domain.h"
#include "hsi/scene_io.h"

namespace fs = std::filesystem;

namespace {

// The scenes scripts/make_assets.py generates, with their hole counts.
struct Expected {
  size_t holes;
  bool procedural;  // made from formulas (clearance guaranteed), not a font glyph
};
const std::map<std::string, Expected>& generated_assets() {
  static const std::map<std::string, Expected> table = {
      {"annulus", {1, true}},  {"bar_holes", {4, true}}, {"two_holes", {2, true}},
      {"links", {2, true}},    {"arm", {1, true}},       {"blob", {0, true}},
      {"glyph_B", {2, false}}, {"glyph_8", {2, false}},  {"glyph_A", {1, false}},
  };
  return table;
}

std::vector<fs::path> scene_files() {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(HSI_ASSETS_DIR))
    if (e.is_regular_file() && e.path().extension() == ".json") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

struct PngHeader {
  bool ok = false;
  std::string problem;
  uint32_t width = 0, height = 0;
  int bit_depth = 0, color_type = 0;
};

uint32_t be32(const unsigned char* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}

// Reads the signature and the IHDR chunk (which must come first).
PngHeader read_png_header(const fs::path& path) {
  PngHeader h;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    h.problem = "cannot open";
    return h;
  }
  std::array<unsigned char, 33> b{};
  in.read(reinterpret_cast<char*>(b.data()), static_cast<std::streamsize>(b.size()));
  if (in.gcount() != static_cast<std::streamsize>(b.size())) {
    h.problem = "shorter than a PNG header";
    return h;
  }
  static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (!std::equal(sig, sig + 8, b.begin())) {
    h.problem = "no PNG signature";
    return h;
  }
  if (be32(&b[8]) != 13 || std::string(reinterpret_cast<const char*>(&b[12]), 4) != "IHDR") {
    h.problem = "first chunk is not IHDR";
    return h;
  }
  h.width = be32(&b[16]);
  h.height = be32(&b[20]);
  h.bit_depth = b[24];
  h.color_type = b[25];
  h.ok = true;
  return h;
}

double min_loop_gap(const hsi::Shape& s) {
  double gap = 1e300;
  for (int a = 0; a < s.loop_count(); ++a)
    for (int b = a + 1; b < s.loop_count(); ++b) {
      const hsi::Loop &la = s.loop(a), &lb = s.loop(b);
      for (size_t i = 0; i < la.size(); ++i)
        for (size_t j = 0; j < lb.size(); ++j)
          gap = std::min(gap, hsi::segment_segment_distance(la[i], la[(i + 1) % la.size()], lb[j],
                                                              lb[(j + 1) % lb.size()]));
    }
  return gap;
}

}  // namespace

TEST_CASE("assets: every scene loads, validates and has a readable PNG texture", "[assets]") {
  const std::vector<fs::path> files = scene_files();
  REQUIRE_FALSE(files.empty());
  for (const fs::path& file : files) {
    INFO("asset " << file.filename().string());
    hsi::Scene scene;
    REQUIRE_NOTHROW(scene = hsi::load_scene(file));
    CHECK_NOTHROW(hsi::validate(scene.shape));
    CHECK(hsi::area(scene.shape) > 0);
    if (scene.texture.empty()) continue;
    const fs::path tex = scene.texture_path();
    INFO("texture " << tex.string());
    REQUIRE(fs::is_regular_file(tex));
    const PngHeader png = read_png_header(tex);
    INFO(png.problem);
    REQUIRE(png.ok);
    CHECK(png.width > 0);
    CHECK(png.height > 0);
    CHECK(png.width <= 8192);
    CHECK(png.height <= 8192);
  }
}

TEST_CASE("assets: generated scenes have their documented loops, textures and rectangles", "[assets]") {
  for (const auto& [name, expected] : generated_assets()) {
    INFO("asset " << name);
    const fs::path file = fs::path(HSI_ASSETS_DIR) / (name + ".json");
    REQUIRE(fs::is_regular_file(file));
    const hsi::Scene scene = hsi::load_scene(file);
    const hsi::Shape& s = scene.shape;
    CHECK(scene.name == name);
    CHECK(s.holes.size() == expected.holes);
    // Loaded shapes are normalized.
    CHECK(hsi::signed_area(s.outer) > 0);
    for (const hsi::Loop& h : s.holes) CHECK(hsi::signed_area(h) < 0);
    // Smooth but light: a few hundred vertices per loop at most, coordinates of order 1.
    for (int k = 0; k < s.loop_count(); ++k) {
      CHECK(s.loop(k).size() >= 3);
      CHECK(s.loop(k).size() <= 400);
    }
    const hsi::BoundingBox bb = hsi::bounding_box(s);
    CHECK(bb.diagonal() > 0.5);
    CHECK(bb.diagonal() < 10);
    // Holes keep their distance from the outer loop and from each other.
    if (expected.procedural && !s.holes.empty()) CHECK(min_loop_gap(s) >= 0.079 * bb.diagonal());

    // The texture: a PNG of its own, 256 or 512 square, RGB(A), under 300 KB.
    REQUIRE_FALSE(scene.texture.empty());
    CHECK(scene.texture == fs::path(name + ".png"));
    const fs::path tex = scene.texture_path();
    REQUIRE(fs::is_regular_file(tex));
    CHECK(fs::file_size(tex) < 300u * 1024u);
    const PngHeader png = read_png_header(tex);
    REQUIRE(png.ok);
    CHECK((png.width == 256 || png.width == 512));
    CHECK(png.height == png.width);
    CHECK(png.bit_depth == 8);
    CHECK((png.color_type == 2 || png.color_type == 6));

    // texture_rect: the bounding box expanded by 5% on every side.
    REQUIRE(scene.texture_rect.has_value());
    const auto& r = *scene.texture_rect;
    const double w = bb.hi.real() - bb.lo.real(), h = bb.hi.imag() - bb.lo.imag();
    CHECK(r[0] == Approx(bb.lo.real() - 0.05 * w).margin(1e-5));
    CHECK(r[1] == Approx(bb.lo.imag() - 0.05 * h).margin(1e-5));
    CHECK(r[2] == Approx(bb.hi.real() + 0.05 * w).margin(1e-5));
    CHECK(r[3] == Approx(bb.hi.imag() + 0.05 * h).margin(1e-5));
  }
}

TEST_CASE("assets: specific shapes keep their defining features", "[assets]") {
  auto load = [](const std::string& name) { return hsi::load_scene(fs::path(HSI_ASSETS_DIR) / (name + ".json")).shape; };
  auto inscribed = [](const hsi::Loop& l) { return hsi::largest_inscribed_circle(l).radius; };
  SECTION("two_holes: one large and one very small hole") {
    const hsi::Shape s = load("two_holes");
    REQUIRE(s.holes.size() == 2);
    const double r0 = inscribed(s.holes[0]), r1 = inscribed(s.holes[1]);
    CHECK(std::max(r0, r1) >= 6 * std::min(r0, r1));
  }
  SECTION("glyph scenes are one unit tall") {
    for (const char* name : {"glyph_B", "glyph_8", "glyph_A"}) {
      const hsi::BoundingBox bb = hsi::bounding_box(load(name));
      CHECK(bb.hi.imag() - bb.lo.imag() == Approx(1.0).epsilon(1e-6));
    }
  }
  SECTION("the README lists every generated asset") {
    std::ifstream in(fs::path(HSI_ASSETS_DIR) / "README.md");
    REQUIRE(in);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (const auto& entry : generated_assets()) CHECK(text.find("`" + entry.first + ".json`") != std::string::npos);
    CHECK(text.find("DejaVu") != std::string::npos);
  }
}
