// Baked playback (.hsib, hsi/baked.h + the C runtime hsi/baked_runtime.h): the
// runtime reproduces direct evaluation of every frame at any rest vertices; damaged
// files give clear errors.
#include <catch2/catch.hpp>
#include <cstring>
#include <fstream>

#include "hsi/baked.h"
#include "hsi/baked_runtime.h"
#include "hsi/scene_sequence.h"
#include "test_shapes.h"

using namespace hsi;
using Catch::Matchers::Contains;

namespace {

// A bundled scene with two holes (log terms) interpolated over a few frames.
struct BakedFixture {
  Scene scene;
  SceneSequence seq;
  BakedFixture() {
    scene = load_scene(std::filesystem::path(HSI_ASSETS_DIR) / "two_holes.json");
    SceneSequenceOptions o;
    o.frames = 5;
    o.samples = 1000;
    seq = interpolate_scene(scene, o);
    for (const FrameResult& f : seq.frames) REQUIRE(f.certified);
  }
};

BakedFixture& fixture() {
  static BakedFixture f;
  return f;
}

struct Sequence {
  hsib_sequence* s = nullptr;
  hsib_status status = HSIB_OK;
  char error[256] = {0};
  explicit Sequence(const std::string& bytes) { status = hsib_open_memory(bytes.data(), bytes.size(), &s, error, sizeof error); }
  ~Sequence() { hsib_close(s); }
};

// Rest vertices as a game would have them: floats, inside the shape and in the
// margin between the shape and the cage.
std::vector<cd> rest_vertices(const ShapeSetup& setup, int count) {
  std::vector<cd> pts = test::interior_points(setup.shape, count);
  for (int l = 0; l < setup.shape.loop_count(); ++l)
    for (const cd& p : setup.shape.loop(l)) pts.push_back(p);  // the outline itself
  for (cd& p : pts) p = cd(static_cast<float>(p.real()), static_cast<float>(p.imag()));
  return pts;
}

std::vector<float> packed(const std::vector<cd>& pts) {
  std::vector<float> xy;
  for (const cd& p : pts) {
    xy.push_back(static_cast<float>(p.real()));
    xy.push_back(static_cast<float>(p.imag()));
  }
  return xy;
}

}  // namespace

TEST_CASE("baked playback matches direct evaluation of every frame", "[baked]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  const std::vector<cd> pts = rest_vertices(setup, 3000);
  const std::vector<float> xy = packed(pts);
  const BasisRows rows = evaluate_basis(setup.cage, pts, kBasisC);
  for (const bool single : {true, false}) {
    INFO((single ? "f32" : "f64") << " coefficients");
    const std::string bytes = encode_baked(setup.shape, F.seq.frame_file(), {single});
    Sequence S(bytes);
    REQUIRE(S.status == HSIB_OK);
    hsib_info info;
    hsib_get_info(S.s, &info);
    CHECK(info.frame_count == F.seq.frames.size());
    CHECK(info.coefficient_count == static_cast<uint32_t>(setup.metric_space.dim()));
    CHECK(info.hole_count == 2);
    CHECK(info.single_precision == (single ? 1 : 0));
    // Compact: the cage once, then a few kilobytes per frame.
    const double per_frame = static_cast<double>(48 + info.coefficient_count * (single ? 4 : 8) + 4);
    CHECK(per_frame < 4096);
    CHECK(static_cast<double>(bytes.size()) < 20000 + static_cast<double>(F.seq.frames.size()) * per_frame);
    hsib_binding* b = nullptr;
    char error[256];
    REQUIRE(hsib_bind(S.s, xy.data(), pts.size(), 0, &b, error, sizeof error) == HSIB_OK);
    std::vector<float> out(xy.size());
    double worst = 0;
    for (uint32_t f = 0; f < info.frame_count; ++f) {
      const FrameResult& fr = F.seq.frames[f];
      double t;
      uint32_t flags;
      REQUIRE(hsib_frame_info(S.s, f, &t, &flags) == HSIB_OK);
      CHECK(t == fr.t);
      CHECK(flags == ((fr.certified ? 1u : 0u) | (fr.keyframe ? 2u : 0u) | (fr.converged ? 4u : 0u) |
                      (fr.overlap.overlaps() ? 8u : 0u)));
      REQUIRE(hsib_evaluate(b, f, out.data(), 0) == HSIB_OK);
      const VectorXcd want = evaluate_map(rows, fr.map).f;
      for (size_t i = 0; i < pts.size(); ++i)
        worst = std::max(worst, std::abs(cd(out[2 * i], out[2 * i + 1]) - want(static_cast<Eigen::Index>(i))));
    }
    INFO("largest error " << worst / setup.size << " of the shape's size");
    CHECK(worst < 1e-5 * setup.size);
    hsib_unbind(b);
  }
}

TEST_CASE("baked runtime rows, ranges, strides and frame lookup", "[baked]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  const std::string bytes = encode_baked(setup.shape, F.seq.frame_file());
  Sequence S(bytes);
  REQUIRE(S.status == HSIB_OK);
  hsib_info info;
  hsib_get_info(S.s, &info);
  // One basis row against the engine's Cauchy coordinates and log terms.
  const cd w = test::interior_points(setup.shape, 1, 3)[0];
  std::vector<float> row(info.row_length);
  REQUIRE(hsib_basis_row(S.s, w.real(), w.imag(), row.data()) == HSIB_OK);
  const BasisRows C = evaluate_basis(setup.cage, std::vector<cd>{w}, kBasisC);
  const int m = setup.cage.vertex_count();
  size_t r = 0;
  for (int j : setup.metric_space.active()) {
    if (j < m) {
      CHECK(row[r++] == Approx(C.C(0, j).real()).margin(1e-6));
      CHECK(row[r++] == Approx(C.C(0, j).imag()).margin(1e-6));
    } else {
      CHECK(row[r++] == Approx(C.C(0, j).real()).margin(1e-6));
    }
  }
  CHECK(r == info.row_length);
  // Interleaved vertices (x, y, u, v) in and out; ranges agree with the whole.
  const std::vector<cd> pts = rest_vertices(setup, 300);
  std::vector<float> vbuf(4 * pts.size(), -7.0f);
  for (size_t i = 0; i < pts.size(); ++i) {
    vbuf[4 * i] = static_cast<float>(pts[i].real());
    vbuf[4 * i + 1] = static_cast<float>(pts[i].imag());
  }
  hsib_binding* b = nullptr;
  REQUIRE(hsib_bind(S.s, vbuf.data(), pts.size(), 4 * sizeof(float), &b, nullptr, 0) == HSIB_OK);
  CHECK(hsib_binding_vertex_count(b) == pts.size());
  std::vector<float> whole(2 * pts.size()), parts(2 * pts.size()), strided(4 * pts.size(), 5.0f);
  REQUIRE(hsib_evaluate(b, 3, whole.data(), 0) == HSIB_OK);
  for (size_t first = 0; first < pts.size(); first += 37) {
    const size_t count = std::min<size_t>(37, pts.size() - first);
    REQUIRE(hsib_evaluate_range(b, 3, first, count, parts.data() + 2 * first, 0) == HSIB_OK);
  }
  CHECK(parts == whole);
  REQUIRE(hsib_evaluate(b, 3, strided.data(), 4 * sizeof(float)) == HSIB_OK);
  for (size_t i = 0; i < pts.size(); ++i) {
    CHECK(strided[4 * i] == whole[2 * i]);
    CHECK(strided[4 * i + 2] == 5.0f);  // untouched between vertices
  }
  CHECK(hsib_evaluate(b, info.frame_count, whole.data(), 0) == HSIB_ERROR_ARGUMENT);
  CHECK(hsib_evaluate_range(b, 0, pts.size() - 1, 2, whole.data(), 0) == HSIB_ERROR_ARGUMENT);
  hsib_unbind(b);
  // Frames by time.
  CHECK(hsib_frame_at_time(S.s, -5.0) == 0);
  CHECK(hsib_frame_at_time(S.s, 1e9) == info.frame_count - 1);
  double t2;
  hsib_frame_info(S.s, 2, &t2, nullptr);
  CHECK(hsib_frame_at_time(S.s, t2 + 1e-9) == 2);
  // The runtime's frame weights reproduce a vertex by hand: row · w + c.
  std::vector<float> wts(2 * info.row_length);
  float c[2];
  REQUIRE(hsib_frame_weights(S.s, 3, wts.data(), c) == HSIB_OK);
  double x = c[0], y = c[1];
  REQUIRE(hsib_basis_row(S.s, pts[0].real(), pts[0].imag(), row.data()) == HSIB_OK);
  for (uint32_t k = 0; k < info.row_length; ++k) {
    x += double(row[k]) * wts[2 * k];
    y += double(row[k]) * wts[2 * k + 1];
  }
  CHECK(std::abs(cd(x, y) - cd(whole[0], whole[1])) < 1e-5 * setup.size);
}

TEST_CASE("baked runtime refuses vertices outside the cage", "[baked]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  Sequence S(encode_baked(setup.shape, F.seq.frame_file()));
  REQUIRE(S.status == HSIB_OK);
  const cd inside = test::interior_points(setup.shape, 1)[0];
  const BoundingBox bb = bounding_box(setup.cage.loops[0]);
  const float xy[] = {static_cast<float>(inside.real()), static_cast<float>(inside.imag()), static_cast<float>(bb.hi.real() + 1),
                      static_cast<float>(inside.imag()), static_cast<float>(setup.cage.hole_points[1].real()),
                      static_cast<float>(setup.cage.hole_points[1].imag())};
  hsib_binding* b = nullptr;
  char error[256];
  CHECK(hsib_bind(S.s, xy, 2, 0, &b, error, sizeof error) == HSIB_ERROR_DOMAIN);
  CHECK(b == nullptr);
  CHECK_THAT(error, Contains("rest vertex 1") && Contains("outside"));
  const float hole[] = {xy[0], xy[1], xy[4], xy[5]};
  CHECK(hsib_bind(S.s, hole, 2, 0, &b, error, sizeof error) == HSIB_ERROR_DOMAIN);
  CHECK_THAT(error, Contains("rest vertex 1") && Contains("hole 2"));
}

TEST_CASE("damaged baked files give clear errors", "[baked]") {
  BakedFixture& F = fixture();
  const std::string bytes = encode_baked(F.seq.setup->shape, F.seq.frame_file());
  auto open = [](const std::string& b, std::string* message = nullptr) {
    Sequence S(b);
    if (message) *message = S.error;
    return S.status;
  };
  std::string msg;
  REQUIRE(open(bytes) == HSIB_OK);
  CHECK(open("XXXX" + bytes.substr(4), &msg) == HSIB_ERROR_FORMAT);
  CHECK_THAT(msg, Contains("not an hsi baked sequence"));
  std::string v2 = bytes;
  v2[4] = 2;
  CHECK(open(v2, &msg) == HSIB_ERROR_VERSION);
  CHECK_THAT(msg, Contains("unsupported baked format version 2") && Contains("reads version 1"));
  // Truncated anywhere: a clear error that says so, never a crash.
  for (size_t cut = 0; cut < bytes.size(); cut += 13) {
    INFO("cut at " << cut);
    CHECK(open(bytes.substr(0, cut), &msg) == HSIB_ERROR_TRUNCATED);
    CHECK_THAT(msg, Contains("truncated"));
  }
  CHECK(open(bytes + "junk", &msg) == HSIB_ERROR_TRUNCATED);
  CHECK_THAT(msg, Contains("4 trailing bytes"));
  // Any flipped byte is caught by a checksum, which names the part.
  std::string h = bytes;
  h[40] ^= 0x01;  // the frame count
  CHECK(open(h, &msg) == HSIB_ERROR_CHECKSUM);
  CHECK_THAT(msg, Contains("header checksum"));
  std::string st = bytes;
  st[HSIB_HEADER_SIZE + 30] ^= 0x10;  // a cage vertex
  CHECK(open(st, &msg) == HSIB_ERROR_CHECKSUM);
  CHECK_THAT(msg, Contains("static section checksum"));
  hsib_info info;
  {
    Sequence S(bytes);
    hsib_get_info(S.s, &info);
  }
  const size_t S_bytes = 48 + 4 * info.coefficient_count + 4;
  std::string fr = bytes;
  fr[bytes.size() - 4 * S_bytes + 60] ^= 0x04;  // inside frame F − 4
  CHECK(open(fr, &msg) == HSIB_ERROR_CHECKSUM);
  CHECK_THAT(msg, Contains("frame " + std::to_string(info.frame_count - 4) + " checksum mismatch"));
  for (size_t i = 0; i < bytes.size(); i += 97) {
    std::string c = bytes;
    c[i] = static_cast<char>(c[i] ^ 0x5A);
    CHECK(open(c) != HSIB_OK);
  }
}

TEST_CASE("baked files are written atomically and read back from disk", "[baked]") {
  BakedFixture& F = fixture();
  std::filesystem::create_directories(HSI_TEST_TMP);
  const auto path = std::filesystem::path(HSI_TEST_TMP) / "seq.hsib";
  write_baked(path, F.seq.setup->shape, F.seq.frame_file(), {false});
  hsib_sequence* s = nullptr;
  char error[256];
  REQUIRE(hsib_open_file(path.c_str(), &s, error, sizeof error) == HSIB_OK);
  hsib_info info;
  hsib_get_info(s, &info);
  CHECK(info.frame_count == F.seq.frames.size());
  CHECK(info.file_bytes == std::filesystem::file_size(path));
  CHECK(info.t_begin == F.seq.frames.front().t);
  CHECK(info.t_end == F.seq.frames.back().t);
  hsib_close(s);
  CHECK(hsib_open_file((path.string() + ".missing").c_str(), &s, error, sizeof error) == HSIB_ERROR_IO);
  CHECK(s == nullptr);
  CHECK_THAT(error, Contains(".missing") && Contains("cannot open"));
  // The baker refuses frames that do not fit the cage.
  FrameFile bad = F.seq.frame_file();
  bad.frames[1].map.phi.conservativeResize(3);
  CHECK_THROWS_WITH(encode_baked(F.seq.setup->shape, bad), Contains("frame 1") && Contains("coefficients"));
}

TEST_CASE("baked frames carry the overlaps-itself flag (8)", "[baked][overlap]") {
  // The bent bar (tests/scenes/bent_bar.json): its second keyframe rolls the bar over itself.
  Scene scene = load_scene(std::filesystem::path(HSI_TESTS_DIR) / "scenes" / "bent_bar.json");
  SceneSequenceOptions o;
  o.frames = 3;
  const SceneSequence seq = interpolate_scene(scene, o);
  REQUIRE(seq.frames.back().overlap.overlaps());
  REQUIRE_FALSE(seq.frames.front().overlap.overlaps());
  Sequence S(encode_baked(seq.setup->shape, seq.frame_file()));
  REQUIRE(S.status == HSIB_OK);
  for (uint32_t f = 0; f < 3; ++f) {
    uint32_t flags = 0;
    REQUIRE(hsib_frame_info(S.s, f, nullptr, &flags) == HSIB_OK);
    CHECK(((flags & HSIB_FRAME_OVERLAPS) != 0) == seq.frames[f].overlap.overlaps());
    CHECK(((flags & HSIB_FRAME_CERTIFIED) != 0) == seq.frames[f].certified);
  }
}
