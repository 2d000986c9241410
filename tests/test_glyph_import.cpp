// Font glyph import (glyph_import.h): hole counts, scaling, orientation, flattening,
// and the refusals (blank glyphs, several pieces, missing font or character).
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <string>

#include "hsi/glyph_import.h"

using hsi::cd;
using hsi::GlyphImportOptions;
using hsi::import_glyph;
using hsi::InputError;

namespace {

size_t vertex_count(const hsi::Shape& s) {
  size_t n = s.outer.size();
  for (const auto& h : s.holes) n += h.size();
  return n;
}

// The message of the InputError thrown by f, or "" if none was thrown.
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("glyph import: hole counts of DejaVu Sans letters and digits", "[glyph]") {
  struct Case {
    char32_t c;
    size_t holes;
  };
  for (const Case& k : {Case{U'B', 2}, Case{U'A', 1}, Case{U'O', 1}, Case{U'L', 0}, Case{U'8', 2}, Case{U'o', 1},
                        Case{U'S', 0}, Case{U'R', 1}}) {
    INFO("character " << hsi::describe_codepoint(k.c));
    const hsi::Shape s = import_glyph(k.c);
    CHECK(s.holes.size() == k.holes);
    CHECK_NOTHROW(hsi::validate(s));
  }
}

TEST_CASE("glyph import: bounding box is height tall with its corner at the origin", "[glyph]") {
  for (double height : {1.0, 2.5, 0.01}) {
    GlyphImportOptions opt;
    opt.height = height;
    const hsi::Shape s = import_glyph(U'B', opt);
    const hsi::BoundingBox bb = hsi::bounding_box(s);
    CHECK(bb.lo.real() == Approx(0.0).margin(1e-12 * height));
    CHECK(bb.lo.imag() == Approx(0.0).margin(1e-12 * height));
    CHECK(bb.hi.imag() == Approx(height).epsilon(1e-12));
    // 'B' in DejaVu Sans is narrower than tall.
    CHECK(bb.hi.real() > 0.5 * height);
    CHECK(bb.hi.real() < 1.0 * height);
    // Holes lie within the outer loop's box.
    for (const auto& h : s.holes) {
      const hsi::BoundingBox hb = hsi::bounding_box(h);
      CHECK(hb.lo.real() > 0);
      CHECK(hb.hi.imag() < height);
    }
  }
}

TEST_CASE("glyph import: orientation is normalized and areas are sensible", "[glyph]") {
  for (char32_t c : {U'B', U'A', U'O', U'L', U'8'}) {
    INFO("character " << hsi::describe_codepoint(c));
    const hsi::Shape s = import_glyph(c);
    CHECK(hsi::signed_area(s.outer) > 0);
    for (const auto& h : s.holes) CHECK(hsi::signed_area(h) < 0);
    const hsi::BoundingBox bb = hsi::bounding_box(s);
    const double box = (bb.hi.real() - bb.lo.real()) * (bb.hi.imag() - bb.lo.imag());
    const double a = hsi::area(s);
    CHECK(a > 0.1 * box);  // strokes, not hairlines
    CHECK(a < 0.7 * box);  // and not a filled box
  }
  // 'O' is a ring: its hole is most of the outer area, but not all of it.
  const hsi::Shape o = import_glyph(U'O');
  const double outer = hsi::signed_area(o.outer), hole = -hsi::signed_area(o.holes[0]);
  CHECK(hole > 0.3 * outer);
  CHECK(hole < 0.8 * outer);
  // 'L' is two straight strokes: flattening adds nothing, so it stays a hexagon.
  CHECK(import_glyph(U'L').outer.size() == 6);
}

TEST_CASE("glyph import: finer flatness gives more vertices and converges", "[glyph]") {
  GlyphImportOptions coarse, fine, finer;
  coarse.flatness = 0.01;
  fine.flatness = 0.002;
  finer.flatness = 0.0002;
  const hsi::Shape a = import_glyph(U'O', coarse), b = import_glyph(U'O', fine), c = import_glyph(U'O', finer);
  CHECK(vertex_count(a) < vertex_count(b));
  CHECK(vertex_count(b) < vertex_count(c));
  // The flattened areas converge as the tolerance shrinks.
  CHECK(hsi::area(a) == Approx(hsi::area(c)).epsilon(0.05));
  CHECK(hsi::area(b) == Approx(hsi::area(c)).epsilon(0.01));
  // The default flatness keeps loops small enough to use directly.
  for (char32_t ch : {U'B', U'8', U'A', U'O'}) {
    const hsi::Shape s = import_glyph(ch);
    CHECK(s.outer.size() < 400);
    for (const auto& h : s.holes) CHECK(h.size() < 400);
  }
}

TEST_CASE("glyph import: refusals name the font and the character", "[glyph]") {
  SECTION("a blank glyph") {
    const std::string msg = error_of([] { import_glyph(U' '); });
    CHECK(msg.find("no outline") != std::string::npos);
    CHECK(msg.find("U+0020") != std::string::npos);
    CHECK(msg.find("DejaVu Sans") != std::string::npos);
  }
  SECTION("several pieces") {
    for (auto [c, pieces] : {std::pair{U'%', 3}, std::pair{U'i', 2}, std::pair{U'"', 2}, std::pair{U':', 2}}) {
      const std::string msg = error_of([c = c] { import_glyph(c); });
      INFO(msg);
      CHECK(msg.find(std::to_string(pieces) + " separate pieces") != std::string::npos);
      CHECK(msg.find("one connected shape") != std::string::npos);
      CHECK(msg.find(hsi::describe_codepoint(c)) != std::string::npos);
      CHECK(msg.find("DejaVu Sans") != std::string::npos);
    }
  }
  SECTION("a missing font") {
    GlyphImportOptions opt;
    opt.font = "/nonexistent/dir/NoSuchFont.ttf";
    const std::string msg = error_of([&] { import_glyph(U'B', opt); });
    CHECK(msg.find("NoSuchFont.ttf") != std::string::npos);
    CHECK(msg.find("does not exist") != std::string::npos);
    CHECK(msg.find("'B'") != std::string::npos);
  }
  SECTION("a file that is not a font") {
    GlyphImportOptions opt;
    opt.font = std::string(HSI_TESTS_DIR) + "/test_glyph_import.cpp";
    const std::string msg = error_of([&] { import_glyph(U'B', opt); });
    CHECK(msg.find("cannot read") != std::string::npos);
    CHECK(msg.find("test_glyph_import.cpp") != std::string::npos);
  }
  SECTION("a character the font does not have") {
    const std::string msg = error_of([] { import_glyph(U'\U0010FFFD'); });
    CHECK(msg.find("no glyph") != std::string::npos);
    CHECK(msg.find("U+10FFFD") != std::string::npos);
    CHECK(msg.find("DejaVu Sans") != std::string::npos);
  }
  SECTION("options out of range") {
    GlyphImportOptions opt;
    opt.height = 0;
    CHECK_THROWS_AS(import_glyph(U'B', opt), InputError);
    opt.height = 1;
    opt.flatness = -1;
    CHECK_THROWS_AS(import_glyph(U'B', opt), InputError);
  }
}

TEST_CASE("glyph import: another font file works too", "[glyph]") {
  GlyphImportOptions opt;
  opt.font = hsi::default_glyph_font().parent_path() / "DejaVuSerif.ttf";
  if (!std::filesystem::exists(opt.font)) {
    WARN("skipped: " << opt.font << " is not installed");
    return;
  }
  const hsi::Shape s = import_glyph(U'B', opt);
  CHECK(s.holes.size() == 2);
  CHECK(hsi::bounding_box(s).hi.imag() == Approx(1.0));
}
