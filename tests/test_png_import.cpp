// PNG alpha import: every test writes its own PNG (a small encoder below, with
// stored deflate blocks, so no binaries are checked in and no PNG library is needed
// here), imports it, and checks loops, areas, orientation, warnings and refusals.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "hsi/cage.h"
#include "hsi/domain.h"
#include "hsi/png_import.h"

using namespace hsi;
using Catch::Matchers::Contains;

namespace {

constexpr double kPi = std::numbers::pi;

// ---- A minimal PNG encoder ----------------------------------------------------

uint32_t crc32(const std::vector<uint8_t>& bytes, size_t from) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t n = 0; n < 256; ++n) {
      uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  uint32_t c = 0xffffffffu;
  for (size_t i = from; i < bytes.size(); ++i) c = table[(c ^ bytes[i]) & 0xffu] ^ (c >> 8);
  return c ^ 0xffffffffu;
}

void put32(std::vector<uint8_t>& out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<uint8_t>(v >> s));
}

void chunk(std::vector<uint8_t>& out, const char* type, const std::vector<uint8_t>& data) {
  put32(out, static_cast<uint32_t>(data.size()));
  const size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  put32(out, crc32(out, start));
}

// zlib stream of stored (uncompressed) deflate blocks.
std::vector<uint8_t> zlib_stored(const std::vector<uint8_t>& raw) {
  std::vector<uint8_t> z{0x78, 0x01};
  size_t pos = 0;
  do {
    const size_t len = std::min<size_t>(65535, raw.size() - pos);
    const bool last = pos + len == raw.size();
    z.push_back(last ? 1 : 0);
    z.push_back(static_cast<uint8_t>(len & 0xff));
    z.push_back(static_cast<uint8_t>(len >> 8));
    z.push_back(static_cast<uint8_t>(~len & 0xff));
    z.push_back(static_cast<uint8_t>((~len >> 8) & 0xff));
    const auto from = raw.begin() + static_cast<std::ptrdiff_t>(pos);
    z.insert(z.end(), from, from + static_cast<std::ptrdiff_t>(len));
    pos += len;
  } while (pos < raw.size());
  uint32_t a = 1, b = 0;
  for (uint8_t v : raw) a = (a + v) % 65521, b = (b + a) % 65521;
  put32(z, (b << 16) | a);
  return z;
}

struct PngSpec {
  int width = 0, height = 0;
  int color_type = 6;  // 0 grey, 2 RGB, 3 palette, 4 grey+alpha, 6 RGBA
  int bit_depth = 8;
  std::vector<uint8_t> samples;  // rows without filter bytes, big-endian for 16 bits
  std::vector<uint8_t> palette;  // PLTE (RGB triples)
  std::vector<uint8_t> trns;     // tRNS
};

std::vector<uint8_t> encode_png(const PngSpec& s) {
  std::vector<uint8_t> out{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<uint8_t> ihdr;
  put32(ihdr, static_cast<uint32_t>(s.width));
  put32(ihdr, static_cast<uint32_t>(s.height));
  ihdr.insert(ihdr.end(), {static_cast<uint8_t>(s.bit_depth), static_cast<uint8_t>(s.color_type), 0, 0, 0});
  chunk(out, "IHDR", ihdr);
  if (!s.palette.empty()) chunk(out, "PLTE", s.palette);
  if (!s.trns.empty()) chunk(out, "tRNS", s.trns);
  const size_t row = s.samples.size() / static_cast<size_t>(s.height);
  std::vector<uint8_t> raw;
  for (int y = 0; y < s.height; ++y) {
    raw.push_back(0);  // filter: none
    const auto begin = s.samples.begin() + static_cast<std::ptrdiff_t>(row * static_cast<size_t>(y));
    raw.insert(raw.end(), begin, begin + static_cast<std::ptrdiff_t>(row));
  }
  chunk(out, "IDAT", zlib_stored(raw));
  chunk(out, "IEND", {});
  return out;
}

std::filesystem::path tmp_path(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(HSI_TEST_TMP) / "png_import";
  std::filesystem::create_directories(dir);
  return dir / name;
}

void write_bytes(const std::filesystem::path& p, const std::vector<uint8_t>& bytes) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  REQUIRE(f.good());
}

// ---- Test images --------------------------------------------------------------

// Anti-aliased coverage of a region given by inside(x, y) in pixel coordinates
// (x right, y down; pixel (i, j) covers [i, i+1] × [j, j+1]), 8 × 8 supersampling.
using Region = std::function<bool(double, double)>;
std::vector<double> coverage(int w, int h, const Region& inside) {
  std::vector<double> c(static_cast<size_t>(w) * static_cast<size_t>(h));
  constexpr int ss = 8;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      int n = 0;
      for (int b = 0; b < ss; ++b)
        for (int a = 0; a < ss; ++a) n += inside(i + (a + 0.5) / ss, j + (b + 0.5) / ss) ? 1 : 0;
      c[static_cast<size_t>(j) * static_cast<size_t>(w) + static_cast<size_t>(i)] = n / double(ss * ss);
    }
  return c;
}

uint8_t to8(double v) { return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255)); }

// An RGBA image with alpha = the given values and a colour gradient.
PngSpec rgba(int w, int h, const std::vector<double>& alpha) {
  PngSpec s{w, h, 6, 8, {}, {}, {}};
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
      s.samples.insert(s.samples.end(), {to8(double(i) / w), to8(double(j) / h), 128,
                                         to8(alpha[static_cast<size_t>(j * w + i)])});
  return s;
}

std::filesystem::path write_rgba(const std::string& name, int w, int h, const Region& inside) {
  const auto p = tmp_path(name);
  write_bytes(p, encode_png(rgba(w, h, coverage(w, h, inside))));
  return p;
}

Region disc(double cx, double cy, double r) {
  return [=](double x, double y) { return (x - cx) * (x - cx) + (y - cy) * (y - cy) < r * r; };
}

size_t vertex_count(const Shape& s) {
  size_t n = s.outer.size();
  for (const Loop& h : s.holes) n += h.size();
  return n;
}

// Area centroid of a simple polygon.
cd centroid(const Loop& l) {
  cd c = 0;
  double a = 0;
  for (size_t i = 0; i < l.size(); ++i) {
    const cd p = l[i], q = l[(i + 1) % l.size()];
    const double w = p.real() * q.imag() - q.real() * p.imag();
    a += w;
    c += w * (p + q);
  }
  return c / (3.0 * a);
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError thrown)";
}

}  // namespace

TEST_CASE("png import: a filled disc gives one loop of the right area", "[png]") {
  const double r = 80;
  const auto p = write_rgba("disc.png", 200, 200, disc(100, 100, r));
  const PngShape s = import_png_alpha(p);
  CHECK(s.width == 200);
  CHECK(s.height == 200);
  CHECK(s.shape.holes.empty());
  CHECK(s.warnings.empty());
  CHECK(signed_area(s.shape.outer) > 0);
  CHECK(area(s.shape) == Approx(kPi * r * r).epsilon(0.01));
  CHECK(s.texture_rect == std::array<double, 4>{0, 0, 200, 200});
  CHECK(std::abs(centroid(s.shape.outer) - cd(100, 100)) < 0.5);
  // Simplification at 0.75 px keeps a circle of radius 80 to a few dozen vertices.
  CHECK(s.shape.outer.size() < 80);
  CHECK(s.shape.outer.size() > 16);
  CHECK_NOTHROW(validate(s.shape));
}

TEST_CASE("png import: an annulus gives one hole, areas and orientation right", "[png]") {
  const double R = 80, r = 40;
  const auto p = write_rgba("annulus.png", 200, 200, [](double x, double y) {
    const double d2 = (x - 100) * (x - 100) + (y - 100) * (y - 100);
    return d2 < 80 * 80 && d2 > 40 * 40;
  });
  const PngShape s = import_png_alpha(p);
  REQUIRE(s.shape.holes.size() == 1);
  CHECK(s.warnings.empty());
  CHECK(signed_area(s.shape.outer) > 0);
  CHECK(signed_area(s.shape.holes[0]) < 0);
  CHECK(signed_area(s.shape.outer) == Approx(kPi * R * R).epsilon(0.01));
  CHECK(-signed_area(s.shape.holes[0]) == Approx(kPi * r * r).epsilon(0.015));
  CHECK(area(s.shape) == Approx(kPi * (R * R - r * r)).epsilon(0.01));
  CHECK(point_in_shape(s.shape, {100, 100 + 60}));
  CHECK_FALSE(point_in_shape(s.shape, {100, 100}));
}

TEST_CASE("png import: a rectangle with three holes gives three holes", "[png]") {
  const auto p = write_rgba("rect3.png", 200, 140, [](double x, double y) {
    if (x < 20 || x > 180 || y < 30 || y > 110) return false;
    for (double cx : {50.0, 100.0, 150.0})
      if ((x - cx) * (x - cx) + (y - 70) * (y - 70) < 15 * 15) return false;
    return true;
  });
  const PngShape s = import_png_alpha(p);
  REQUIRE(s.shape.holes.size() == 3);
  CHECK(s.warnings.empty());
  CHECK(area(s.shape) == Approx(160 * 80 - 3 * kPi * 225).epsilon(0.01));
  // The rectangle's straight sides simplify to (about) its 4 corners.
  CHECK(s.shape.outer.size() <= 8);
  for (const Loop& h : s.shape.holes) CHECK(signed_area(h) < 0);
  // Holes come sorted left to right.
  CHECK(centroid(s.shape.holes[0]).real() == Approx(50).margin(0.5));
  CHECK(centroid(s.shape.holes[2]).real() == Approx(150).margin(0.5));
}

TEST_CASE("png import: of two blobs the largest is kept, with a warning", "[png]") {
  const auto p = write_rgba("blobs.png", 220, 200, [](double x, double y) {
    return disc(70, 100, 50)(x, y) || disc(180, 100, 20)(x, y);
  });
  const PngShape s = import_png_alpha(p);
  CHECK(s.shape.holes.empty());
  CHECK(area(s.shape) == Approx(kPi * 2500).epsilon(0.01));
  CHECK(centroid(s.shape.outer).real() == Approx(70).margin(0.5));
  REQUIRE(s.warnings.size() == 1);
  CHECK_THAT(s.warnings[0], Contains("dropped 1 smaller piece") && Contains("86% of the opaque area"));
}

TEST_CASE("png import: an island inside a hole is a separate piece", "[png]") {
  const auto p = write_rgba("island.png", 200, 200, [](double x, double y) {
    const double d2 = (x - 100) * (x - 100) + (y - 100) * (y - 100);
    return (d2 < 90 * 90 && d2 > 50 * 50) || d2 < 20 * 20;
  });
  const PngShape s = import_png_alpha(p);
  REQUIRE(s.shape.holes.size() == 1);
  CHECK(area(s.shape) == Approx(kPi * (8100 - 2500)).epsilon(0.01));
  REQUIRE(s.warnings.size() == 1);
  CHECK_THAT(s.warnings[0], Contains("dropped 1 smaller piece"));
}

TEST_CASE("png import: holes of a few pixels are dropped with a warning", "[png]") {
  const auto p = write_rgba("pinholes.png", 100, 100, [](double x, double y) {
    if (x < 10 || x > 90 || y < 10 || y > 90) return false;
    if (x > 30 && x < 31 && y > 30 && y < 31) return false;              // 1 px
    if (x > 60 && x < 61.5 && y > 60 && y < 61.5) return false;          // ~2 px²
    return !disc(50, 30, 8)(x, y);                                       // a real hole
  });
  const PngShape s = import_png_alpha(p);
  CHECK(s.shape.holes.size() == 1);
  REQUIRE(s.warnings.size() == 1);
  CHECK_THAT(s.warnings[0], Contains("dropped 2 holes smaller than 4 square pixels"));
}

TEST_CASE("png import: saddle cells follow the cell-centre average", "[png]") {
  // Two opaque 1-px blocks meeting at a corner only: the corner cell's centre
  // average is exactly 0.5, so at threshold 0.5 they stay apart (two pieces) and
  // at a lower threshold they join.
  PngSpec spec{20, 20, 6, 8, {}, {}, {}};
  std::vector<double> alpha(400, 0.0);
  for (int j = 5; j < 10; ++j)
    for (int i = 5; i < 10; ++i) alpha[static_cast<size_t>(j * 20 + i)] = 1;
  for (int j = 10; j < 15; ++j)
    for (int i = 10; i < 15; ++i) alpha[static_cast<size_t>(j * 20 + i)] = 1;
  const auto p = tmp_path("saddle.png");
  write_bytes(p, encode_png(rgba(20, 20, alpha)));
  PngImportOptions exact;
  exact.tolerance = 0.01;
  const PngShape apart = import_png_alpha(p, exact);
  CHECK(apart.warnings.size() == 1);
  // The 5 × 5 block with its corners cut by 1/8 px² each (the marching-squares
  // vertices sit halfway between pixel centres), the saddle corner included.
  CHECK(area(apart.shape) == Approx(25 - 0.5).margin(1e-9));
  PngImportOptions low = exact;
  low.alpha_threshold = 0.4;
  const PngShape joined = import_png_alpha(p, low);
  CHECK(joined.warnings.empty());
  CHECK(area(joined.shape) > 40);
}

TEST_CASE("png import: the threshold picks the iso-line, interpolated below a pixel", "[png]") {
  // alpha falls off linearly with the distance from the centre: 1 − d/100.
  const int w = 220;
  std::vector<double> alpha(static_cast<size_t>(w * w));
  for (int j = 0; j < w; ++j)
    for (int i = 0; i < w; ++i)
      alpha[static_cast<size_t>(j * w + i)] = 1 - std::hypot(i + 0.5 - 110, j + 0.5 - 110) / 100;
  const auto p = tmp_path("radial.png");
  write_bytes(p, encode_png(rgba(w, w, alpha)));
  for (double t : {0.25, 0.5, 0.75}) {
    PngImportOptions o;
    o.alpha_threshold = t;
    o.tolerance = 0.2;
    const double r = 100 * (1 - t);
    CAPTURE(t);
    CHECK(area(import_png_alpha(p, o).shape) == Approx(kPi * r * r).epsilon(0.01));
  }
}

TEST_CASE("png import: grey+alpha, palette+tRNS and 16-bit images are read", "[png]") {
  const int w = 120;
  const std::vector<double> cov = coverage(w, w, disc(60, 60, 40));
  // The same disc as 8-bit RGBA is the reference; all formats should agree with it
  // to well below a pixel, and with πr² to the simplification's 1.25% (chords of
  // sagitta ≤ 0.75 px on r = 40 px).
  const PngShape reference = import_png_alpha(write_rgba("fmt_rgba.png", w, w, disc(60, 60, 40)));
  const size_t expected = reference.shape.outer.size();
  const double expected_area = area(reference.shape);
  CHECK(expected_area == Approx(kPi * 1600).epsilon(0.0125));
  SECTION("grey + alpha, 8 bits") {
    PngSpec s{w, w, 4, 8, {}, {}, {}};
    for (double c : cov) s.samples.insert(s.samples.end(), {200, to8(c)});
    const auto p = tmp_path("fmt_ga.png");
    write_bytes(p, encode_png(s));
    const PngShape r = import_png_alpha(p);
    CHECK(r.shape.outer.size() == expected);
    CHECK(area(r.shape) == Approx(expected_area).epsilon(1e-6));
  }
  SECTION("palette with tRNS") {
    // 17 alpha levels through a palette.
    PngSpec s{w, w, 3, 8, {}, {}, {}};
    for (int k = 0; k <= 16; ++k) {
      s.palette.insert(s.palette.end(), {static_cast<uint8_t>(15 * k), 90, 40});
      s.trns.push_back(static_cast<uint8_t>(std::min(255, 16 * k)));
    }
    for (double c : cov) s.samples.push_back(static_cast<uint8_t>(std::lround(c * 16)));
    const auto p = tmp_path("fmt_palette.png");
    write_bytes(p, encode_png(s));
    // Alpha quantized to 17 levels moves the iso-line by up to ~1/34 px.
    CHECK(area(import_png_alpha(p).shape) == Approx(expected_area).epsilon(0.005));
  }
  SECTION("RGBA, 16 bits") {
    PngSpec s{w, w, 6, 16, {}, {}, {}};
    for (double c : cov) {
      const auto a = static_cast<uint16_t>(std::lround(c * 65535));
      s.samples.insert(s.samples.end(), {0x12, 0x34, 0x56, 0x78, 0x9a, 0xbc, static_cast<uint8_t>(a >> 8),
                                         static_cast<uint8_t>(a & 0xff)});
    }
    const auto p = tmp_path("fmt_rgba16.png");
    write_bytes(p, encode_png(s));
    CHECK(area(import_png_alpha(p).shape) == Approx(expected_area).epsilon(0.001));
  }
}

TEST_CASE("png import: y points up and pixel_size scales", "[png]") {
  // A blob in the top-left corner of a 100 × 80 image.
  const auto p = write_rgba("topleft.png", 100, 80, disc(15, 15, 10));
  const PngShape s = import_png_alpha(p);
  const cd c = centroid(s.shape.outer);
  CHECK(c.real() == Approx(15).margin(0.5));
  CHECK(c.imag() == Approx(80 - 15).margin(0.5));
  CHECK(signed_area(s.shape.outer) > 0);
  PngImportOptions o;
  o.pixel_size = 0.5;
  const PngShape half = import_png_alpha(p, o);
  CHECK(centroid(half.shape.outer).real() == Approx(7.5).margin(0.25));
  CHECK(centroid(half.shape.outer).imag() == Approx(32.5).margin(0.25));
  CHECK(half.texture_rect == std::array<double, 4>{0, 0, 50, 40});
  CHECK(area(half.shape) == Approx(area(s.shape) / 4).epsilon(1e-9));
}

TEST_CASE("png import: tolerance trades vertices for accuracy, monotonically and within bounds", "[png]") {
  // A wavy blob: r(θ) = 70 + 12 sin 7θ.
  const auto p = write_rgba("wavy.png", 200, 200, [](double x, double y) {
    const double dx = x - 100, dy = y - 100;
    return std::hypot(dx, dy) < 70 + 12 * std::sin(7 * std::atan2(dy, dx));
  });
  PngImportOptions fine;
  fine.tolerance = 1e-4;
  const Loop raw = import_png_alpha(p, fine).shape.outer;
  size_t previous = std::numeric_limits<size_t>::max();
  for (double tol : {0.05, 0.1, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 4.0, 8.0}) {
    PngImportOptions o;
    o.tolerance = tol;
    const PngShape s = import_png_alpha(p, o);
    CAPTURE(tol);
    CHECK(s.warnings.empty());
    const size_t n = vertex_count(s.shape);
    CHECK(n <= previous);
    previous = n;
    // Both ways: the fine contour is within tol of the simplified one, and the
    // simplified vertices lie on the fine contour.
    double out = 0, back = 0;
    for (const cd& q : raw) out = std::max(out, loop_distance(s.shape.outer, q));
    for (const cd& q : s.shape.outer) back = std::max(back, loop_distance(raw, q));
    CHECK(out <= tol + 1e-3);
    CHECK(back <= 1e-3);
  }
  CHECK(previous < 20);
}

TEST_CASE("png import: simplification never makes loops cross", "[png]") {
  // A disc with a ring of holes 3 px from its rim: simplifying the rim at 8 px
  // would cut through the holes, so those loops are simplified less.
  const auto p = write_rgba("ring.png", 200, 200, [](double x, double y) {
    if (!disc(100, 100, 90)(x, y)) return false;
    for (int k = 0; k < 8; ++k) {
      const double t = 2 * kPi * (k + 0.5) / 8;  // between the vertices DP keeps on the rim
      if (disc(100 + 72 * std::cos(t), 100 + 72 * std::sin(t), 15)(x, y)) return false;
    }
    return true;
  });
  PngImportOptions o;
  o.tolerance = 8;
  PngShape s;
  REQUIRE_NOTHROW(s = import_png_alpha(p, o));
  CHECK(s.shape.holes.size() == 8);
  CHECK_NOTHROW(validate(s.shape));
  REQUIRE(!s.warnings.empty());
  CHECK_THAT(s.warnings.back(), Contains("smaller tolerance"));
}

TEST_CASE("png import: refusals name the file and the problem", "[png]") {
  const auto good = write_rgba("good.png", 64, 64, disc(32, 32, 20));
  std::ifstream in(good, std::ios::binary);
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  REQUIRE(bytes.size() > 1000);

  SECTION("fully transparent") {
    const auto p = write_rgba("empty.png", 32, 32, [](double, double) { return false; });
    CHECK_THAT(message_of([&] { import_png_alpha(p); }),
               Contains(p.string()) && Contains("no opaque pixels above alpha threshold 0.5"));
  }
  SECTION("RGB without alpha") {
    PngSpec s{16, 16, 2, 8, std::vector<uint8_t>(16 * 16 * 3, 200), {}, {}};
    const auto p = tmp_path("rgb.png");
    write_bytes(p, encode_png(s));
    CHECK_THAT(message_of([&] { import_png_alpha(p); }), Contains(p.string()) && Contains("no alpha channel"));
  }
  SECTION("truncated") {
    for (size_t cut : {bytes.size() / 2, size_t{8}, size_t{20}, size_t{40}, bytes.size() - 30}) {
      CAPTURE(cut);
      const auto p = tmp_path("truncated.png");
      write_bytes(p, std::vector<uint8_t>(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(cut)));
      CHECK_THAT(message_of([&] { import_png_alpha(p); }), Contains(p.string()) && Contains("PNG"));
    }
  }
  SECTION("corrupt data") {
    std::vector<uint8_t> bad = bytes;
    for (size_t i = 60; i < 90; ++i) bad[i] ^= 0x5a;  // inside IDAT: CRC and zlib errors
    const auto p = tmp_path("corrupt.png");
    write_bytes(p, bad);
    CHECK_THAT(message_of([&] { import_png_alpha(p); }), Contains(p.string()) && Contains("corrupt"));
  }
  SECTION("not a PNG") {
    const auto p = tmp_path("not_a_png.png");
    write_bytes(p, {'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd', '\n'});
    CHECK_THAT(message_of([&] { import_png_alpha(p); }), Contains(p.string()) && Contains("not a PNG"));
    const auto e = tmp_path("empty_file.png");
    write_bytes(e, {});
    CHECK_THAT(message_of([&] { import_png_alpha(e); }), Contains("not a PNG"));
  }
  SECTION("missing file") {
    const auto p = tmp_path("does_not_exist.png");
    std::filesystem::remove(p);
    CHECK_THAT(message_of([&] { import_png_alpha(p); }), Contains(p.string()) && Contains("no such file"));
  }
  SECTION("too large") {
    PngSpec s{16385, 1, 6, 8, std::vector<uint8_t>(16385 * 4, 255), {}, {}};
    const auto p = tmp_path("wide.png");
    write_bytes(p, encode_png(s));
    CHECK_THAT(message_of([&] { import_png_alpha(p); }), Contains("too large") && Contains("16384"));
  }
  SECTION("bad options") {
    for (double t : {0.0, 1.0, -0.5, 1.5, std::nan("")}) {
      PngImportOptions o;
      o.alpha_threshold = t;
      CHECK_THAT(message_of([&] { import_png_alpha(good, o); }), Contains("threshold") && Contains(good.string()));
    }
    for (double tol : {-1.0, std::nan("")}) {  // 0 is automatic (png_tolerance_for)
      PngImportOptions o;
      o.tolerance = tol;
      CHECK_THAT(message_of([&] { import_png_alpha(good, o); }), Contains("tolerance"));
    }
    for (double ps : {0.0, -2.0, std::numeric_limits<double>::infinity()}) {
      PngImportOptions o;
      o.pixel_size = ps;
      CHECK_THAT(message_of([&] { import_png_alpha(good, o); }), Contains("pixel size"));
    }
  }
}

TEST_CASE("png import: sliver holes too narrow for a cage are filled, so the scene works", "[png][authoring]") {
  // A game sprite's slivers: a 1.2 x 10 px slot and a 1.6 x 8 px one (12 and 13 px², above the
  // minimum hole area), beside a real hole, in a 256 px sprite: the cage must keep 0.002 of
  // the size (0.7 px) from the boundary, more than a sliver has room for, so without
  // filling build_cage fails.
  const Region sprite = [](double x, double y) {
    if (x < 8 || x > 248 || y < 8 || y > 248) return false;
    if (x > 40 && x < 41.2 && y > 60 && y < 70) return false;
    if (x > 190 && x < 191.6 && y > 150 && y < 158) return false;
    return !disc(128, 128, 30)(x, y);
  };
  const auto p = write_rgba("slivers.png", 256, 256, sprite);
  PngImportOptions keep;
  keep.fill_narrow_holes = false;
  const std::string refused = message_of([&] { (void)import_png_alpha(p, keep); });
  CHECK_THAT(refused, Contains("slivers.png: the hole at (") && Contains("is too narrow for a cage") &&
                          Contains("fill it (the default, without --keep-narrow-holes)"));
  const PngShape s = import_png_alpha(p);
  REQUIRE(s.shape.holes.size() >= 1);
  CHECK(s.shape.holes.size() < 3);
  CHECK(std::any_of(s.warnings.begin(), s.warnings.end(), [](const std::string& w) {
    return w.find("filled the hole at (") != std::string::npos && w.find("too narrow for a cage") != std::string::npos;
  }));
  // The real hole is kept, and the scene gets a cage.
  CHECK(std::any_of(s.shape.holes.begin(), s.shape.holes.end(), [](const Loop& h) { return std::abs(signed_area(h)) > 2500; }));
  CHECK_NOTHROW(build_cage(s.shape));
  // --min-hole-area drops them by area instead.
  PngImportOptions by_area;
  by_area.min_hole_area = 20;
  const PngShape a = import_png_alpha(p, by_area);
  CHECK(a.shape.holes.size() == 1);
}

TEST_CASE("png import: a shape below the minimum size is refused, naming its size", "[png][authoring]") {
  const auto one = write_rgba("one_pixel.png", 8, 8, [](double x, double y) { return x > 3 && x < 4 && y > 3 && y < 4; });
  CHECK_THAT(message_of([&] { (void)import_png_alpha(one); }),
             Contains("one_pixel.png: the sprite's shape is only") && Contains("at least 16 square pixels"));
  const auto small = write_rgba("five_pixels.png", 8, 8, [](double x, double y) { return x > 2 && x < 7 && y > 2 && y < 7; });
  CHECK_NOTHROW(import_png_alpha(small));
}

TEST_CASE("png import: a sprite sheet's pieces are listed, and any one can be picked or cropped", "[png][authoring]") {
  // Four discs in a 2 x 2 sheet; the largest is bottom left.
  const auto p = write_rgba("sheet.png", 120, 120, [](double x, double y) {
    return disc(30, 30, 20)(x, y) || disc(90, 30, 15)(x, y) || disc(30, 90, 25)(x, y) || disc(90, 90, 10)(x, y);
  });
  const std::vector<PngPiece> pieces = list_png_pieces(p);
  REQUIRE(pieces.size() == 4);
  // Reading order (top, then left), with the pixels each covers and its area.
  const double cx[4] = {30, 90, 30, 90}, cy[4] = {30, 30, 90, 90}, r[4] = {20, 15, 25, 10};
  for (int i = 0; i < 4; ++i) {
    CAPTURE(i);
    CHECK(pieces[static_cast<size_t>(i)].index == i);
    const PixelRect& b = pieces[static_cast<size_t>(i)].box;
    CHECK(std::abs(b.x - (cx[i] - r[i])) <= 1);
    CHECK(std::abs(b.y - (cy[i] - r[i])) <= 1);
    CHECK(std::abs(b.width - 2 * r[i]) <= 2);
    CHECK(pieces[static_cast<size_t>(i)].area == Approx(kPi * r[i] * r[i]).epsilon(0.03));
  }
  // Default: the largest (piece 2), with a warning naming it and how to pick another.
  const PngShape largest = import_png_alpha(p);
  CHECK(largest.piece == 2);
  CHECK(largest.pieces == 4);
  REQUIRE(!largest.warnings.empty());
  CHECK_THAT(largest.warnings[0], Contains("dropped 3 smaller pieces (largest kept: piece 2") && Contains("--piece K"));
  // --piece 1: the top right disc, no warning about dropped pieces.
  PngImportOptions one;
  one.piece = 1;
  const PngShape s1 = import_png_alpha(p, one);
  CHECK(s1.piece == 1);
  CHECK(area(s1.shape) == Approx(kPi * 225).epsilon(0.03));
  CHECK(centroid(s1.shape.outer).real() == Approx(90).margin(0.5));
  CHECK(centroid(s1.shape.outer).imag() == Approx(120 - 30).margin(0.5));  // y up
  CHECK(s1.warnings.empty());
  // A crop rectangle (the bottom right cell): only that piece, at its place in the image.
  PngImportOptions cell;
  cell.crop = PixelRect{60, 60, 60, 60};
  const PngShape sc = import_png_alpha(p, cell);
  CHECK(sc.pieces == 1);
  CHECK(area(sc.shape) == Approx(kPi * 100).epsilon(0.05));
  CHECK(centroid(sc.shape.outer).real() == Approx(90).margin(0.5));
  CHECK(sc.texture_rect == std::array<double, 4>{0, 0, 120, 120});  // the texture still maps unchanged
  // Refusals name the problem.
  PngImportOptions nine;
  nine.piece = 9;
  CHECK_THAT(message_of([&] { import_png_alpha(p, nine); }), Contains("piece 9 does not exist: the image has 4 pieces (0 to 3"));
  PngImportOptions outside;
  outside.crop = PixelRect{100, 100, 40, 40};
  CHECK_THAT(message_of([&] { import_png_alpha(p, outside); }),
             Contains("crop rectangle 100,100,40,40") && Contains("does not lie inside the 120x120 px image"));
  PngImportOptions empty_cell;
  empty_cell.crop = PixelRect{0, 55, 5, 5};
  CHECK_THAT(message_of([&] { import_png_alpha(p, empty_cell); }), Contains("no opaque pixels") && Contains("crop rectangle"));
}

TEST_CASE("png import: small sprites get a tolerance that scales with them, and nearest filtering", "[png][authoring]") {
  // A 30 x 38 sprite (a head on a body): at the old fixed 0.75 px its outline was visibly faceted.
  const auto p = write_rgba("small.png", 30, 38, [](double x, double y) {
    return std::pow((x - 15) / 11, 2) + std::pow((y - 24) / 12, 2) <= 1 || std::pow((x - 15) / 6, 2) + std::pow((y - 7) / 6, 2) <= 1;
  });
  const PngShape s = import_png_alpha(p);
  CHECK(s.tolerance_auto);
  CHECK(s.tolerance == Approx(png_tolerance_for(std::max(s.width, s.height) - 3)).margin(0.02));
  CHECK(s.tolerance < 0.25);
  CHECK(png_tolerance_for(30) == Approx(0.15));
  CHECK(png_tolerance_for(400) == Approx(0.75));  // large sprites keep the old default
  CHECK(png_tolerance_for(4) == Approx(0.1));
  PngImportOptions fixed;
  fixed.tolerance = 0.75;
  const PngShape coarse = import_png_alpha(p, fixed);
  CHECK_FALSE(coarse.tolerance_auto);
  CHECK(vertex_count(s.shape) > vertex_count(coarse.shape) + 4);
  // Every traced point stays within the tolerance of the outline.
  PngImportOptions fine;
  fine.tolerance = 1e-4;
  const Loop raw = import_png_alpha(p, fine).shape.outer;
  double out = 0;
  for (const cd& q : raw) out = std::max(out, loop_distance(s.shape.outer, q));
  CHECK(out <= s.tolerance + 1e-3);
  // Pixel-art sizes are drawn with nearest filtering unless asked otherwise; large sprites linear.
  CHECK(s.filter == TextureFilter::Nearest);
  CHECK(s.filter_auto);
  PngImportOptions smooth;
  smooth.filter = TextureFilter::Linear;
  CHECK(import_png_alpha(p, smooth).filter == TextureFilter::Linear);
  const auto big = write_rgba("big.png", 300, 300, disc(150, 150, 100));
  CHECK(import_png_alpha(big).filter == TextureFilter::Linear);
}
