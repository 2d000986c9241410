// Baked playback (.hsib, hsi/baked.h + the C runtime hsi/baked_runtime.h): the
// runtime reproduces direct evaluation of every frame at any rest vertices; damaged
// files give clear errors.
#include <Eigen/SVD>
#include <array>
#include <catch2/catch.hpp>
#include <cstring>
#include <fstream>

#include "hsi/baked.h"
#include "hsi/baked_runtime.h"
#include "hsi/certificate.h"
#include "hsi/samples.h"
#include "hsi/scene_sequence.h"
#include "hsi/triangulate.h"
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
    // The static part: the cage, the outline and the stored triangulation (8 bytes a vertex, 12 a triangle).
    const double mesh_bytes = 8.0 * info.mesh_vertex_count + 12.0 * info.mesh_triangle_count;
    CHECK(info.mesh_vertex_count > 1000);
    CHECK(static_cast<double>(bytes.size()) < 20000 + mesh_bytes + static_cast<double>(F.seq.frames.size()) * per_frame);
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
      CHECK((flags & 15u) == ((fr.certified ? 1u : 0u) | (fr.keyframe ? 2u : 0u) | (fr.converged ? 4u : 0u) |
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
  std::string v3 = bytes;
  v3[4] = 3;
  CHECK(open(v3, &msg) == HSIB_ERROR_VERSION);
  CHECK_THAT(msg, Contains("unsupported baked format version 3") && Contains("reads versions 1 and 2"));
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

namespace {

// The engine's map at points, for comparisons with the runtime.
VectorXcd engine_map(const Cage& cage, const std::vector<cd>& pts, const HarmonicMap& map) {
  return evaluate_map(evaluate_basis(cage, pts, kBasisC), map).f;
}

HarmonicMap blend_of(const HarmonicMap& a, const HarmonicMap& b, double s) {
  return {(1 - s) * a.phi + s * b.phi, (1 - s) * a.psi + s * b.psi};
}

}  // namespace

TEST_CASE("baked blends: certified at k sub-steps, played only where certified", "[baked][blend]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  const FrameFile ff = F.seq.frame_file();
  BakeOptions bo;
  bo.blend_substeps = 4;
  bo.certificate_samples = 1000;
  Sequence S(encode_baked(setup.shape, ff, bo));
  REQUIRE(S.status == HSIB_OK);
  hsib_info info;
  hsib_get_info(S.s, &info);
  CHECK(info.version == 2);
  CHECK(info.blend_substeps == 4);
  const std::vector<cd> pts = rest_vertices(setup, 400);
  const std::vector<float> xy = packed(pts);
  hsib_binding* b = nullptr;
  REQUIRE(hsib_bind(S.s, xy.data(), pts.size(), 0, &b, nullptr, 0) == HSIB_OK);
  const Certifier certifier(setup.shape, setup.cage, sample_boundary(setup.shape, 1000));
  std::vector<float> out(xy.size());
  for (uint32_t i = 0; i + 1 < info.frame_count; ++i) {
    uint32_t flags = 0;
    double t0, t1;
    REQUIRE(hsib_frame_info(S.s, i, &t0, &flags) == HSIB_OK);
    REQUIRE(hsib_frame_info(S.s, i + 1, &t1, nullptr) == HSIB_OK);
    // The flag is the engine's certificate of every sub-step blend.
    bool all = true;
    for (int j = 1; j < 4; ++j) all = all && certifier.certify(blend_of(ff.frames[i].map, ff.frames[i + 1].map, j / 4.0)).certified;
    INFO("interval " << i);
    CHECK(((flags & HSIB_FRAME_BLEND_CERTIFIED) != 0) == all);
    REQUIRE(all);  // the two-hole scene's small steps blend certifiably
    for (int j = 0; j <= 4; ++j) {
      // Certified steps: the time a bit past sub-step j snaps to it; the map is the blend.
      const double t = t0 + (t1 - t0) * (j + 0.1) / 4.0;
      const hsib_blend bl = hsib_blend_at_time(S.s, t, HSIB_PLAY_CERTIFIED_STEPS);
      CHECK((bl.flags & HSIB_FRAME_CERTIFIED) != 0);
      REQUIRE(hsib_evaluate_blend(b, &bl, out.data(), 0) == HSIB_OK);
      const VectorXcd want = engine_map(setup.cage, pts, blend_of(ff.frames[i].map, ff.frames[i + 1].map, j / 4.0));
      double worst = 0;
      for (size_t v = 0; v < pts.size(); ++v) worst = std::max(worst, std::abs(cd(out[2 * v], out[2 * v + 1]) - want(static_cast<Eigen::Index>(v))));
      CHECK(worst < 1e-5 * setup.size);
      if (j == 0 || j == 4) {
        CHECK(bl.frame0 == bl.frame1);
        CHECK((bl.flags & HSIB_BLEND_BLENDED) == 0);
      } else {
        CHECK(bl.frame0 == i);
        CHECK(bl.frame1 == i + 1);
        CHECK(bl.s == Approx(j / 4.0));
        CHECK((bl.flags & HSIB_BLEND_BLENDED) != 0);
      }
    }
    // Exact blending: between sub-steps the map is not called certified.
    const hsib_blend mid = hsib_blend_at_time(S.s, t0 + (t1 - t0) * 0.3, HSIB_PLAY_BLEND);
    CHECK(mid.s == Approx(0.3));
    CHECK(mid.flags == HSIB_BLEND_BLENDED);
    const hsib_blend near = hsib_blend_at_time(S.s, t0 + (t1 - t0) * 0.3, HSIB_PLAY_NEAREST);
    CHECK(near.frame0 == i);
    CHECK(near.frame1 == i);
  }
  hsib_unbind(b);
  // No sub-steps baked: every mode plays the nearest frame.
  bo.blend_substeps = 0;
  Sequence N(encode_baked(setup.shape, ff, bo));
  REQUIRE(N.status == HSIB_OK);
  double t0, t1;
  hsib_frame_info(N.s, 1, &t0, nullptr);
  hsib_frame_info(N.s, 2, &t1, nullptr);
  const hsib_blend nb = hsib_blend_at_time(N.s, t0 + 0.4 * (t1 - t0), HSIB_PLAY_BLEND);
  CHECK(nb.frame0 == 1);
  CHECK(nb.frame1 == 1);
  CHECK(nb.s == 0.0f);
  // An uncertified frame: the intervals on both sides are not blended.
  FrameFile bad = ff;
  bad.frames[2].certified = false;
  bo.blend_substeps = 4;
  Sequence U(encode_baked(setup.shape, bad, bo));
  REQUIRE(U.status == HSIB_OK);
  for (uint32_t i = 0; i + 1 < info.frame_count; ++i) {
    uint32_t flags = 0;
    hsib_frame_info(U.s, i, nullptr, &flags);
    CHECK(((flags & HSIB_FRAME_BLEND_CERTIFIED) != 0) == (i != 1 && i != 2));
  }
  CHECK(hsib_blend_at_time(U.s, t0 + 0.4 * (t1 - t0), HSIB_PLAY_BLEND).frame1 == 1);
}

TEST_CASE("baked blends through a degenerate map are not certified", "[baked][blend]") {
  // f0 = identity, f1 = rotation by pi: both certified, but the blend at s = 1/2 is the
  // zero map. k = 4 has that sub-step and refuses the interval; k = 3 (s = 1/3, 2/3,
  // maps ±w/3) certifies it, and exact blending at s = 1/2 is then reported uncertified.
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  FrameFile ff;
  ff.cage = setup.cage;
  ff.frames.resize(2);
  ff.frames[0].t = 0;
  ff.frames[1].t = 1;
  ff.frames[0].map = identity_map(setup.cage);
  ff.frames[1].map = affine_map(setup.cage, cd(-1, 0), cd(0, 0), cd(0, 0));
  for (StoredFrame& f : ff.frames) f.certified = f.converged = true;
  BakeOptions bo;
  bo.certificate_samples = 1000;
  bo.blend_substeps = 4;
  Sequence K4(encode_baked(setup.shape, ff, bo));
  REQUIRE(K4.status == HSIB_OK);
  uint32_t flags = 0;
  hsib_frame_info(K4.s, 0, nullptr, &flags);
  CHECK((flags & HSIB_FRAME_BLEND_CERTIFIED) == 0);
  CHECK(hsib_blend_at_time(K4.s, 0.45, HSIB_PLAY_CERTIFIED_STEPS).s == 0.0f);  // nearest frame: 0
  CHECK(hsib_blend_at_time(K4.s, 0.55, HSIB_PLAY_BLEND).frame0 == 1);
  bo.blend_substeps = 3;
  Sequence K3(encode_baked(setup.shape, ff, bo));
  REQUIRE(K3.status == HSIB_OK);
  hsib_frame_info(K3.s, 0, nullptr, &flags);
  CHECK((flags & HSIB_FRAME_BLEND_CERTIFIED) != 0);
  const hsib_blend half = hsib_blend_at_time(K3.s, 0.5, HSIB_PLAY_BLEND);
  CHECK(half.s == 0.5f);
  CHECK((half.flags & HSIB_FRAME_CERTIFIED) == 0);
  const hsib_blend step = hsib_blend_at_time(K3.s, 0.5, HSIB_PLAY_CERTIFIED_STEPS);
  CHECK((step.s == Approx(1 / 3.0) || step.s == Approx(2 / 3.0)));
  CHECK((step.flags & HSIB_FRAME_CERTIFIED) != 0);
}

TEST_CASE("baked runtime reads version 1 files (nearest-frame playback, no mesh)", "[baked][blend]") {
  // Written by the version 1 baker: hsi bake assets/annulus.json --frames 3 --samples 1000.
  hsib_sequence* s1 = nullptr;
  char error[256];
  const std::string golden = std::string(HSI_TESTS_DIR) + "/golden/annulus_v1.hsib";
  REQUIRE(hsib_open_file(golden.c_str(), &s1, error, sizeof error) == HSIB_OK);
  hsib_info info;
  hsib_get_info(s1, &info);
  CHECK(info.version == 1);
  CHECK(info.frame_count == 3);
  CHECK(info.blend_substeps == 0);
  CHECK(info.mesh_vertex_count == 0);
  hsib_mesh mesh;
  CHECK(hsib_get_mesh(s1, &mesh) == HSIB_ERROR_VERSION);
  const hsib_blend bl = hsib_blend_at_time(s1, 0.3, HSIB_PLAY_BLEND);
  CHECK(bl.frame0 == bl.frame1);
  // The same scene baked now plays the same frames.
  Scene scene = load_scene(std::filesystem::path(HSI_ASSETS_DIR) / "annulus.json");
  SceneSequenceOptions o;
  o.frames = 3;
  o.samples = 1000;
  const SceneSequence seq = interpolate_scene(scene, o);
  Sequence S2(encode_baked(seq.setup->shape, seq.frame_file()));
  REQUIRE(S2.status == HSIB_OK);
  const std::vector<float> xy = packed(rest_vertices(*seq.setup, 200));
  hsib_binding *b1 = nullptr, *b2 = nullptr;
  REQUIRE(hsib_bind(s1, xy.data(), xy.size() / 2, 0, &b1, nullptr, 0) == HSIB_OK);
  REQUIRE(hsib_bind(S2.s, xy.data(), xy.size() / 2, 0, &b2, nullptr, 0) == HSIB_OK);
  std::vector<float> o1(xy.size()), o2(xy.size());
  for (uint32_t f = 0; f < 3; ++f) {
    REQUIRE(hsib_evaluate(b1, f, o1.data(), 0) == HSIB_OK);
    REQUIRE(hsib_evaluate(b2, f, o2.data(), 0) == HSIB_OK);
    for (size_t k = 0; k < xy.size(); ++k) CHECK(std::abs(o1[k] - o2[k]) < 1e-4 * seq.setup->size);
  }
  hsib_unbind(b1);
  hsib_unbind(b2);
  hsib_close(s1);
}

TEST_CASE("baked files carry the shape's triangulation, outline and texture coordinates", "[baked][mesh]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  BakeOptions bo;
  bo.mesh_vertices = 500;
  bo.texture_rect = std::array<double, 4>{-2.0, -1.5, 3.0, 2.5};
  Sequence S(encode_baked(setup.shape, F.seq.frame_file(), bo));
  REQUIRE(S.status == HSIB_OK);
  hsib_mesh mesh;
  REQUIRE(hsib_get_mesh(S.s, &mesh) == HSIB_OK);
  TriangulateOptions to;
  to.max_edge = edge_for_vertex_count(setup.shape, 500);
  const TriMesh want = triangulate(setup.shape, to);
  REQUIRE(mesh.vertex_count == static_cast<uint32_t>(want.vertex_count()));
  REQUIRE(mesh.triangle_count == static_cast<uint32_t>(want.triangle_count()));
  for (uint32_t v = 0; v < mesh.vertex_count; ++v) {
    CHECK(mesh.xy[2 * v] == static_cast<float>(want.vertices[v].real()));
    CHECK(mesh.uv[2 * v] == Approx((mesh.xy[2 * v] - -2.0) / 5.0).margin(1e-6));
    CHECK(mesh.uv[2 * v + 1] == Approx((2.5 - mesh.xy[2 * v + 1]) / 4.0).margin(1e-6));
  }
  for (uint32_t t = 0; t < mesh.triangle_count; ++t)
    for (int k = 0; k < 3; ++k) CHECK(mesh.triangles[3 * t + k] == static_cast<uint32_t>(want.triangles[t][static_cast<size_t>(k)]));
  CHECK(mesh.texture_rect[2] == 3.0);
  // The whole mesh binds (its boundary vertices lie on the shape, inside the cage).
  hsib_binding* b = nullptr;
  REQUIRE(hsib_bind(S.s, mesh.xy, mesh.vertex_count, 0, &b, nullptr, 0) == HSIB_OK);
  hsib_unbind(b);
}

TEST_CASE("baked point regions match the engine's inside tests", "[baked][mesh]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  Sequence S(encode_baked(setup.shape, F.seq.frame_file()));
  REQUIRE(S.status == HSIB_OK);
  const BoundingBox bb = bounding_box(setup.cage.loops[0]);
  int counts[3] = {0, 0, 0};
  const int n = 60;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const cd p(bb.lo.real() - 0.1 + (bb.hi.real() - bb.lo.real() + 0.2) * i / n, bb.lo.imag() - 0.1 + (bb.hi.imag() - bb.lo.imag() + 0.2) * j / n);
      double near = 1e300;
      for (const Loop& l : setup.cage.loops) near = std::min(near, loop_distance(l, p));
      for (int l = 0; l < setup.shape.loop_count(); ++l) near = std::min(near, loop_distance(setup.shape.loop(l), p));
      if (near < 1e-6 * setup.size) continue;  // on a boundary: either answer
      bool in_cage = point_in_loop(setup.cage.loops[0], p);
      for (size_t l = 1; l < setup.cage.loops.size(); ++l) in_cage = in_cage && !point_in_loop(setup.cage.loops[l], p);
      bool in_shape = point_in_loop(setup.shape.outer, p);
      for (const Loop& h : setup.shape.holes) in_shape = in_shape && !point_in_loop(h, p);
      const hsib_region want = !in_cage ? HSIB_REGION_OUTSIDE : (in_shape ? HSIB_REGION_SHAPE : HSIB_REGION_CAGE);
      INFO(p);
      CHECK(hsib_point_region(S.s, p.real(), p.imag()) == want);
      ++counts[want];
    }
  CHECK(counts[0] > 50);
  CHECK(counts[1] > 50);
  CHECK(counts[2] > 50);
}

TEST_CASE("baked bindings clamp vertices outside the cage per vertex", "[baked][mesh]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  Sequence S(encode_baked(setup.shape, F.seq.frame_file()));
  REQUIRE(S.status == HSIB_OK);
  const cd inside = test::interior_points(setup.shape, 1)[0];
  const BoundingBox bb = bounding_box(setup.cage.loops[0]);
  const cd far_right(bb.hi.real() + 0.5, 0.5 * (bb.lo.imag() + bb.hi.imag()));
  const cd hole = setup.cage.hole_points[0];
  const std::vector<cd> pts{inside, far_right, hole};
  const std::vector<float> xy = packed(pts);
  hsib_binding* b = nullptr;
  char error[512];
  // Refusing stays the default, and its message names the way out.
  CHECK(hsib_bind(S.s, xy.data(), 3, 0, &b, error, sizeof error) == HSIB_ERROR_DOMAIN);
  CHECK_THAT(error, Contains("rest vertex 1") && Contains("HSIB_OUTSIDE_CLAMP"));
  std::vector<uint8_t> region(3, 99);
  hsib_bind_options o{};
  o.outside = HSIB_OUTSIDE_CLAMP;
  o.vertex_region = region.data();
  REQUIRE(hsib_bind_ex(S.s, xy.data(), 3, 0, &o, &b, error, sizeof error) == HSIB_OK);
  CHECK(region[0] == HSIB_REGION_SHAPE);
  CHECK(region[1] == HSIB_REGION_OUTSIDE);
  CHECK(region[2] == HSIB_REGION_OUTSIDE);
  // A clamped vertex follows the map at the nearest point of the cage domain.
  std::vector<float> out(6);
  REQUIRE(hsib_evaluate(b, 2, out.data(), 0) == HSIB_OK);
  const HarmonicMap& map = F.seq.frames[2].map;
  auto nearest_on = [&](const Loop& loop, cd p) {
    cd best = loop[0];
    for (size_t i = 0; i < loop.size(); ++i) {
      const cd a = loop[i], c = loop[(i + 1) % loop.size()];
      const double t = std::clamp(std::real((p - a) * std::conj(c - a)) / std::norm(c - a), 0.0, 1.0);
      if (std::abs(a + t * (c - a) - p) < std::abs(best - p)) best = a + t * (c - a);
    }
    return best;
  };
  const cd edge_point = nearest_on(setup.cage.loops[0], far_right);
  const cd inward = 1e-4 * setup.size * (inside - edge_point) / std::abs(inside - edge_point);
  const VectorXcd want = engine_map(setup.cage, {inside, edge_point + inward}, map);
  CHECK(std::abs(cd(out[0], out[1]) - want(0)) < 1e-5 * setup.size);
  CHECK(std::abs(cd(out[2], out[3]) - want(1)) < 1e-2 * setup.size);
  hsib_unbind(b);
}

namespace {
struct CountingAllocator {
  static inline int allocations = 0;
  static void* allocate(size_t bytes, void*) {
    ++allocations;
    return std::malloc(bytes);
  }
  static void release(void* p, void*) { std::free(p); }
};
}  // namespace

TEST_CASE("baked sequences and bindings live in caller-provided memory", "[baked][mesh]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  const std::string bytes = encode_baked(setup.shape, F.seq.frame_file());
  size_t need = 0;
  char error[256];
  REQUIRE(hsib_sequence_bytes(bytes.data(), bytes.size(), &need, error, sizeof error) == HSIB_OK);
  REQUIRE(need > 0);
  std::vector<std::max_align_t> memory(need / sizeof(std::max_align_t) + 2);
  const std::vector<cd> pts = rest_vertices(setup, 100);
  const std::vector<float> xy = packed(pts);
  const hsib_allocator counting{CountingAllocator::allocate, CountingAllocator::release, nullptr};
  hsib_set_allocator(&counting);
  CountingAllocator::allocations = 0;
  hsib_sequence* s = nullptr;
  // Too small and misaligned memory are refused with a message.
  CHECK(hsib_open_in_place(bytes.data(), bytes.size(), memory.data(), need - 16, &s, error, sizeof error) == HSIB_ERROR_MEMORY);
  CHECK_THAT(error, Contains("the sequence needs " + std::to_string(need)));
  CHECK(hsib_open_in_place(bytes.data(), bytes.size(), reinterpret_cast<char*>(memory.data()) + 4, need, &s, error, sizeof error) ==
        HSIB_ERROR_ARGUMENT);
  REQUIRE(hsib_open_in_place(bytes.data(), bytes.size(), memory.data(), memory.size() * sizeof(std::max_align_t), &s, error,
                             sizeof error) == HSIB_OK);
  hsib_info info;
  hsib_get_info(s, &info);
  CHECK(info.sequence_bytes == need);
  const size_t bind_need = hsib_binding_memory_size(s, pts.size());
  std::vector<std::max_align_t> bind_memory(bind_need / sizeof(std::max_align_t) + 1);
  hsib_bind_options o{};
  o.memory = bind_memory.data();
  o.memory_bytes = bind_memory.size() * sizeof(std::max_align_t);
  hsib_binding* b = nullptr;
  REQUIRE(hsib_bind_ex(s, xy.data(), pts.size(), 0, &o, &b, error, sizeof error) == HSIB_OK);
  std::vector<float> out(xy.size());
  REQUIRE(hsib_evaluate(b, 1, out.data(), 0) == HSIB_OK);
  hsib_unbind(b);
  hsib_close(s);
  CHECK(CountingAllocator::allocations == 0);
  hsib_set_allocator(nullptr);
  // Same numbers as a sequence the runtime allocated.
  Sequence A(bytes);
  hsib_binding* ba = nullptr;
  REQUIRE(hsib_bind(A.s, xy.data(), pts.size(), 0, &ba, nullptr, 0) == HSIB_OK);
  std::vector<float> out_a(xy.size());
  REQUIRE(hsib_evaluate(ba, 1, out_a.data(), 0) == HSIB_OK);
  CHECK(out == out_a);
  hsib_unbind(ba);
}

// ---------------------------------------------------------------- distortion (issue #25)

namespace {

// hsi's singular values of a map at points, from the engine's own basis (in double):
// sigma1 = |f_z| + |f_zbar|, sigma2 = |f_z| − |f_zbar|.
std::vector<std::array<double, 2>> engine_sigmas(const Cage& cage, const std::vector<cd>& pts, const HarmonicMap& map) {
  const MapValues v = evaluate_map(evaluate_basis(cage, pts, kBasisD), map);
  std::vector<std::array<double, 2>> out;
  for (Eigen::Index i = 0; i < v.f_z.size(); ++i) {
    const double a = std::abs(v.f_z(i)), b = std::abs(v.fzbar_conj(i));
    out.push_back({a + b, a - b});
  }
  return out;
}

// The row sources of a baked file (the static section after the cage and hole points,
// as hsi/baked_runtime.h lays it out), so that a test can name each row's function.
std::vector<uint32_t> row_sources(const std::string& bytes, const hsib_info& info) {
  const size_t header = info.version == 1 ? HSIB_HEADER_SIZE_V1 : HSIB_HEADER_SIZE;
  const size_t at = header + 4ull * info.loop_count + 16ull * info.cage_vertex_count + 16ull * info.hole_count;
  std::vector<uint32_t> src(info.row_length);
  std::memcpy(src.data(), bytes.data() + at, 4ull * info.row_length);
  return src;
}

BakeOptions exact_bake() {
  BakeOptions o;
  o.single_precision = false;  // the engine's coefficients exactly: the comparisons below see the runtime's own error only
  o.blend_substeps = 0;
  return o;
}

}  // namespace

TEST_CASE("baked derivative rows are the derivatives of the basis rows", "[baked][distortion]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  const std::string bytes = encode_baked(setup.shape, F.seq.frame_file(), exact_bake());
  Sequence S(bytes);
  REQUIRE(S.status == HSIB_OK);
  hsib_info info;
  hsib_get_info(S.s, &info);
  const uint32_t R = info.row_length;
  const std::vector<uint32_t> src = row_sources(bytes, info);
  const int m = setup.cage.vertex_count();
  const std::vector<cd> pts = rest_vertices(setup, 200);
  const BasisRows engine = evaluate_basis(setup.cage, pts, kBasisD);
  std::vector<float> row(R), dx(R), dy(R), rp(R), rm(R);
  // Central differences of the runtime's own (float) rows: h is large enough that the
  // rows' rounding (about 1e-7 of a row) stays far below the tolerance, small enough
  // that the truncation error h²/6 f''' does too.
  const double h = 3e-4 * setup.size;
  double worst_fd = 0, worst_engine = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    const double x = pts[i].real(), y = pts[i].imag();
    REQUIRE(hsib_basis_row_derivatives(S.s, x, y, row.data(), dx.data(), dy.data()) == HSIB_OK);
    std::vector<float> plain(R);
    REQUIRE(hsib_basis_row(S.s, x, y, plain.data()) == HSIB_OK);
    CHECK(plain == row);
    double scale = 1.0 / setup.size;  // derivatives are 1/length
    for (uint32_t r = 0; r < R; ++r) scale = std::max(scale, std::max(std::abs(double(dx[r])), std::abs(double(dy[r]))));
    for (int axis = 0; axis < 2; ++axis) {
      const double ex = axis == 0 ? h : 0, ey = axis == 0 ? 0 : h;
      if (hsib_basis_row(S.s, x + ex, y + ey, rp.data()) != HSIB_OK || hsib_basis_row(S.s, x - ex, y - ey, rm.data()) != HSIB_OK)
        continue;  // a margin point within h of the cage
      for (uint32_t r = 0; r < R; ++r) {
        const double fd = (double(rp[r]) - double(rm[r])) / (2 * h);
        const double got = axis == 0 ? dx[r] : dy[r];
        worst_fd = std::max(worst_fd, std::abs(got - fd) / scale);
      }
    }
    // Against the engine's closed-form C' (basis.cpp's D), through the row sources:
    // Re C: (Re D, −Im D); Im C: (Im D, Re D); log|w − ρ|: D = 1/(w − ρ), (Re D, −Im D).
    for (uint32_t r = 0; r < R; ++r) {
      const uint32_t part = src[r] & 3u, col = src[r] >> 2;
      const cd D = engine.D(static_cast<Eigen::Index>(i), part == 2u ? m + static_cast<int>(col) : static_cast<int>(col));
      const double want_x = part == 1u ? D.imag() : D.real(), want_y = part == 1u ? D.real() : -D.imag();
      worst_engine = std::max(worst_engine, std::max(std::abs(dx[r] - want_x), std::abs(dy[r] - want_y)) / scale);
    }
  }
  INFO("finite differences: largest error " << worst_fd << ", engine's C': " << worst_engine << " (relative to the row's largest derivative)");
  CHECK(worst_fd < 1e-3);
  CHECK(worst_engine < 1e-6);  // the same closed form, rounded to float once
  CHECK(hsib_basis_row_derivatives(S.s, 1e9, 0, row.data(), dx.data(), dy.data()) == HSIB_ERROR_DOMAIN);
  CHECK(hsib_basis_row_derivatives(S.s, 0, 0, row.data(), nullptr, dy.data()) == HSIB_ERROR_ARGUMENT);
}

TEST_CASE("baked distortion matches the engine's singular values", "[baked][distortion]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  Sequence S(encode_baked(setup.shape, F.seq.frame_file(), exact_bake()));
  REQUIRE(S.status == HSIB_OK);
  hsib_info info;
  hsib_get_info(S.s, &info);
  const std::vector<cd> pts = rest_vertices(setup, 2000);
  const std::vector<float> xy = packed(pts);
  hsib_binding* b = nullptr;
  hsib_binding* plain = nullptr;
  char error[256];
  REQUIRE(hsib_bind_flags(S.s, xy.data(), pts.size(), 0, nullptr, HSIB_BIND_DERIVATIVES, &b, error, sizeof error) == HSIB_OK);
  REQUIRE(hsib_bind(S.s, xy.data(), pts.size(), 0, &plain, error, sizeof error) == HSIB_OK);
  CHECK(hsib_binding_flags(b) == HSIB_BIND_DERIVATIVES);
  CHECK(hsib_binding_flags(plain) == 0u);
  // Opt in: a plain binding costs what it did; one with derivatives three times the rows.
  CHECK(hsib_binding_bytes(plain) == hsib_binding_memory_size(S.s, pts.size()));
  CHECK(hsib_binding_bytes(b) == hsib_binding_memory_size_flags(S.s, pts.size(), HSIB_BIND_DERIVATIVES));
  CHECK(hsib_binding_bytes(b) - hsib_binding_bytes(plain) == 2 * (hsib_binding_bytes(plain) - hsib_binding_memory_size(S.s, 0)));
  std::vector<float> sigma(pts.size() * 2), pos(xy.size()), pos_plain(xy.size());
  double worst = 0, folds = 0;
  for (uint32_t f = 0; f < info.frame_count; ++f) {
    const FrameResult& fr = F.seq.frames[f];
    REQUIRE(hsib_evaluate_distortion(b, f, sigma.data(), 0) == HSIB_OK);
    const auto want = engine_sigmas(setup.cage, pts, fr.map);
    for (size_t i = 0; i < pts.size(); ++i) {
      // float arithmetic over R products: relative to the Jacobian's size, sigma1
      const double rel = std::max(std::abs(sigma[2 * i] - want[i][0]), std::abs(sigma[2 * i + 1] - want[i][1])) / want[i][0];
      worst = std::max(worst, rel);
      folds += sigma[2 * i + 1] <= 0;
    }
    // The positions of a binding with derivatives are the plain binding's, bit for bit.
    REQUIRE(hsib_evaluate(b, f, pos.data(), 0) == HSIB_OK);
    REQUIRE(hsib_evaluate(plain, f, pos_plain.data(), 0) == HSIB_OK);
    CHECK(pos == pos_plain);
  }
  INFO("largest error " << worst << " of sigma1");
  CHECK(worst < 5e-6);  // measured 1e-6
  CHECK(folds == 0);  // certified frames: locally injective on the shape, and these points are in it or on its outline
  // Strides and ranges: sigma of vertices [10, 30) at 16 bytes apart.
  std::vector<float> strided(4 * 20, -7.0f);
  const hsib_blend one{2, 2, 0.0f, 0};
  REQUIRE(hsib_evaluate_blend_distortion_range(b, &one, 10, 20, strided.data(), 16) == HSIB_OK);
  REQUIRE(hsib_evaluate_distortion(b, 2, sigma.data(), 0) == HSIB_OK);
  for (size_t i = 0; i < 20; ++i) {
    CHECK(strided[4 * i] == sigma[2 * (10 + i)]);
    CHECK(strided[4 * i + 1] == sigma[2 * (10 + i) + 1]);
    CHECK(strided[4 * i + 2] == -7.0f);
  }
  // Refusals: no derivative rows, a range past the end, unknown flags.
  CHECK(hsib_evaluate_distortion(plain, 0, sigma.data(), 0) == HSIB_ERROR_ARGUMENT);
  CHECK(hsib_gpu_derivative_rows_floats(plain, 8) == 0);
  CHECK(hsib_gpu_derivative_rows(plain, 8, sigma.data()) == HSIB_ERROR_ARGUMENT);
  CHECK(hsib_evaluate_blend_distortion_range(b, &one, pts.size() - 1, 2, sigma.data(), 0) == HSIB_ERROR_ARGUMENT);
  CHECK(hsib_evaluate_distortion(b, info.frame_count, sigma.data(), 0) == HSIB_ERROR_ARGUMENT);
  hsib_binding* bad = nullptr;
  CHECK(hsib_bind_flags(S.s, xy.data(), pts.size(), 0, nullptr, 6u, &bad, error, sizeof error) == HSIB_ERROR_ARGUMENT);
  CHECK_THAT(error, Contains("unknown flags 0x6"));
  CHECK(bad == nullptr);
  CHECK(hsib_binding_memory_size_flags(S.s, 10, 2u) == 0);
  hsib_unbind(plain);
  hsib_unbind(b);
}

TEST_CASE("baked blend distortion is the singular values of the blended Jacobian", "[baked][distortion][blend]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  const FrameFile ff = F.seq.frame_file();
  Sequence S(encode_baked(setup.shape, ff, exact_bake()));
  REQUIRE(S.status == HSIB_OK);
  const std::vector<cd> pts = rest_vertices(setup, 1000);
  const std::vector<float> xy = packed(pts);
  hsib_binding* b = nullptr;
  REQUIRE(hsib_bind_flags(S.s, xy.data(), pts.size(), 0, nullptr, HSIB_BIND_DERIVATIVES, &b, nullptr, 0) == HSIB_OK);
  const size_t n = pts.size();
  for (const hsib_blend blend : {hsib_blend{1, 2, 0.37f, 0}, hsib_blend{0, 4, 0.5f, 0}}) {
    INFO("frames " << blend.frame0 << ", " << blend.frame1 << " at s = " << blend.s);
    const double s = blend.s;
    std::vector<float> J0(4 * n), J1(4 * n), Jb(4 * n), sigma(2 * n), s0(2 * n), s1(2 * n);
    const hsib_blend f0{blend.frame0, blend.frame0, 0.0f, 0}, f1{blend.frame1, blend.frame1, 0.0f, 0};
    REQUIRE(hsib_evaluate_jacobian_range(b, &f0, 0, n, J0.data(), 0) == HSIB_OK);
    REQUIRE(hsib_evaluate_jacobian_range(b, &f1, 0, n, J1.data(), 0) == HSIB_OK);
    REQUIRE(hsib_evaluate_jacobian_range(b, &blend, 0, n, Jb.data(), 0) == HSIB_OK);
    REQUIRE(hsib_evaluate_blend_distortion(b, &blend, sigma.data(), 0) == HSIB_OK);
    REQUIRE(hsib_evaluate_distortion(b, blend.frame0, s0.data(), 0) == HSIB_OK);
    REQUIRE(hsib_evaluate_distortion(b, blend.frame1, s1.data(), 0) == HSIB_OK);
    const auto engine = engine_sigmas(setup.cage, pts, blend_of(ff.frames[blend.frame0].map, ff.frames[blend.frame1].map, s));
    double worst_J = 0, worst_svd = 0, worst_engine = 0, sigma_blend_gap = 0;
    for (size_t i = 0; i < n; ++i) {
      // J of the blend = the blend of the Jacobians (as positions blend).
      Eigen::Matrix2d J;
      for (int k = 0; k < 4; ++k) J(k % 2, k / 2) = (1 - s) * J0[4 * i + k] + s * J1[4 * i + k];  // column-major: (a, c, b, d)
      for (int k = 0; k < 4; ++k) worst_J = std::max(worst_J, std::abs(Jb[4 * i + k] - J(k % 2, k / 2)) / J.norm());
      // Its sigma: the SVD of the blended J, sigma2 signed by the orientation (det J).
      const Eigen::Vector2d sv = Eigen::JacobiSVD<Eigen::Matrix2d>(J).singularValues();
      const double det = J(0, 0) * J(1, 1) - J(0, 1) * J(1, 0);
      const double want1 = sv(0), want2 = (det < 0 ? -1.0 : 1.0) * sv(1);
      worst_svd = std::max(worst_svd, std::max(std::abs(sigma[2 * i] - want1), std::abs(sigma[2 * i + 1] - want2)) / want1);
      worst_engine = std::max(worst_engine, std::max(std::abs(sigma[2 * i] - engine[i][0]), std::abs(sigma[2 * i + 1] - engine[i][1])) /
                                                engine[i][0]);
      // Not the blend of the two frames' sigma (the measure that would be wrong here).
      sigma_blend_gap = std::max(sigma_blend_gap, std::abs((1 - s) * s0[2 * i] + s * s1[2 * i] - want1) / want1);
    }
    INFO("J " << worst_J << ", SVD " << worst_svd << ", engine " << worst_engine << ", blend of sigma off by " << sigma_blend_gap);
    CHECK(worst_J < 5e-6);  // measured about 8e-7 for all three
    CHECK(worst_svd < 5e-6);
    CHECK(worst_engine < 5e-6);
    CHECK(sigma_blend_gap > 1000 * 5e-6);  // the test tells the two apart (measured 0.03)
  }
  float J[4] = {0, 2, -2, 0}, sv[2];  // a rotation by 90° scaled by 2: f_z = 2i, f_zbar = 0
  hsib_singular_values(J, sv);
  CHECK(sv[0] == 2.0f);
  CHECK(sv[1] == 2.0f);
  const float flip[4] = {1, 0, 0, -3};  // a reflection: |f_zbar| > |f_z|
  hsib_singular_values(flip, sv);
  CHECK(sv[0] == 3.0f);
  CHECK(sv[1] == -1.0f);
  hsib_unbind(b);
}

// ---- Stop reasons (issue #20): the frame record's stop word at byte 12 ----------------

namespace {

// Frames over the fixture's cage, one per stop reason (t = its value), then one not
// recorded (not converged, stop empty) and one converged that does not say.
// A quick bake for the stop-word tests: no blend sub-steps, a coarse mesh.
BakeOptions small_bake_options() {
  BakeOptions bo;
  bo.blend_substeps = 0;
  bo.mesh_vertices = 100;
  return bo;
}

FrameFile frames_with_every_stop(const ShapeSetup& setup) {
  FrameFile ff;
  ff.cage = setup.cage;
  for (int k = 0; k <= kNewtonStopCount + 1; ++k) {
    StoredFrame s;
    s.t = k;
    s.certified = true;
    s.map = affine_map(setup.cage, cd(1.0 + 0.01 * k, 0), cd(0, 0), cd(0.05 * k, 0));
    if (k < kNewtonStopCount) s.stop = static_cast<NewtonStop>(k);
    s.converged = k == 0 || k == kNewtonStopCount + 1;
    ff.frames.push_back(s);
  }
  return ff;
}

uint32_t le_u32(const std::string& b, size_t at) {
  uint32_t v = 0;
  for (int k = 3; k >= 0; --k) v = (v << 8) | static_cast<unsigned char>(b[at + static_cast<size_t>(k)]);
  return v;
}
void put_le_u32(std::string& b, size_t at, uint32_t v) {
  for (size_t k = 0; k < 4; ++k) b[at + k] = static_cast<char>((v >> (8 * k)) & 0xFFu);
}

// Frame f's record in a baked file: its offset and size, from the header.
struct Record {
  size_t at, size;
};
Record frame_record(const std::string& bytes, uint32_t f) {
  const uint32_t F = le_u32(bytes, 40), S = le_u32(bytes, 44);
  return {bytes.size() - static_cast<size_t>(F - f) * S, S};
}
// Sets frame f's stop word and fixes its CRC, so that only the word is wrong.
std::string with_stop_word(std::string bytes, uint32_t f, uint32_t word) {
  const Record r = frame_record(bytes, f);
  put_le_u32(bytes, r.at + 12, word);
  put_le_u32(bytes, r.at + r.size - 4, hsib_crc32(bytes.data() + r.at, r.size - 4));
  return bytes;
}

}  // namespace

TEST_CASE("baked frames carry every stop reason (hsib_frame_stop)", "[baked][stop]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  const FrameFile ff = frames_with_every_stop(setup);
  const BakeOptions bo = small_bake_options();
  const std::string bytes = encode_baked(setup.shape, ff, bo);
  Sequence S(bytes);
  REQUIRE(S.status == HSIB_OK);
  hsib_info info;
  hsib_get_info(S.s, &info);
  CHECK(info.version == 2);
  REQUIRE(info.frame_count == ff.frames.size());
  for (uint32_t f = 0; f < info.frame_count; ++f) {
    INFO("frame " << f);
    uint32_t flags = 0, stop = 12345;
    REQUIRE(hsib_frame_info(S.s, f, nullptr, &flags) == HSIB_OK);
    REQUIRE(hsib_frame_stop(S.s, f, &stop) == HSIB_OK);
    CHECK(((flags & HSIB_FRAME_CONVERGED) != 0) == ff.frames[f].converged);
    const uint32_t word = le_u32(bytes, frame_record(bytes, f).at + 12);
    if (f < static_cast<uint32_t>(kNewtonStopCount)) {
      CHECK(stop == f);
      CHECK(word == (0x100u | f));
      CHECK(std::string(hsib_stop_name(stop)) == to_string(static_cast<NewtonStop>(f)));
    } else if (f == static_cast<uint32_t>(kNewtonStopCount)) {
      CHECK(stop == HSIB_STOP_NOT_RECORDED);  // not converged, reason unknown
      CHECK(word == 0);
      CHECK(std::string(hsib_stop_name(stop)) == "not recorded");
    } else {
      CHECK(stop == HSIB_STOP_CONVERGED);  // a converged frame that did not say: stored as converged
      CHECK(word == 0x100u);
    }
  }
  CHECK(std::string(hsib_stop_name(HSIB_STOP_COUNT)) == "unknown");
  uint32_t stop = 0;
  CHECK(hsib_frame_stop(S.s, info.frame_count, &stop) == HSIB_ERROR_ARGUMENT);
  CHECK(hsib_frame_stop(S.s, 0, nullptr) == HSIB_ERROR_ARGUMENT);
  CHECK(hsib_frame_stop(nullptr, 0, &stop) == HSIB_ERROR_ARGUMENT);
  // The baker refuses a reason that contradicts the converged flag, naming the frame.
  FrameFile bad = ff;
  bad.frames[4].converged = true;
  CHECK_THROWS_WITH(encode_baked(setup.shape, bad, bo), Contains("bake: frame 4") && Contains("no decrease") && Contains("contradicts"));
}

TEST_CASE("baked files without stop words read with the stop derived from flag 4", "[baked][stop]") {
  // Files baked before the stop word wrote 0 there (reserved): converged frames read as
  // converged, the others as not recorded.
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  const FrameFile ff = frames_with_every_stop(setup);
  const BakeOptions bo = small_bake_options();
  std::string old = encode_baked(setup.shape, ff, bo);
  for (uint32_t f = 0; f < ff.frames.size(); ++f) old = with_stop_word(old, f, 0);
  Sequence S(old);
  REQUIRE(S.status == HSIB_OK);
  for (uint32_t f = 0; f < ff.frames.size(); ++f) {
    INFO("frame " << f);
    uint32_t stop = 12345;
    REQUIRE(hsib_frame_stop(S.s, f, &stop) == HSIB_OK);
    CHECK(stop == (ff.frames[f].converged ? HSIB_STOP_CONVERGED : HSIB_STOP_NOT_RECORDED));
  }
  // The version 1 golden file: every frame converged, none says so in a stop word.
  hsib_sequence* s1 = nullptr;
  const std::string golden = std::string(HSI_TESTS_DIR) + "/golden/annulus_v1.hsib";
  REQUIRE(hsib_open_file(golden.c_str(), &s1, nullptr, 0) == HSIB_OK);
  for (uint32_t f = 0; f < 3; ++f) {
    uint32_t flags = 0, stop = 12345;
    REQUIRE(hsib_frame_info(s1, f, nullptr, &flags) == HSIB_OK);
    REQUIRE(hsib_frame_stop(s1, f, &stop) == HSIB_OK);
    CHECK(stop == ((flags & HSIB_FRAME_CONVERGED) ? HSIB_STOP_CONVERGED : HSIB_STOP_NOT_RECORDED));
  }
  hsib_close(s1);
}

TEST_CASE("baked runtime refuses an unknown stop code or one that contradicts flag 4, naming the frame and byte", "[baked][stop]") {
  BakedFixture& F = fixture();
  const ShapeSetup& setup = *F.seq.setup;
  const FrameFile ff = frames_with_every_stop(setup);
  const BakeOptions bo = small_bake_options();
  const std::string bytes = encode_baked(setup.shape, ff, bo);
  const std::string at3 = "(at byte " + std::to_string(frame_record(bytes, 3).at + 12) + ")";
  auto refused = [](const std::string& b) {
    Sequence S(b);
    CHECK(S.status == HSIB_ERROR_FORMAT);
    CHECK(S.s == nullptr);
    return std::string(S.error);
  };
  for (const uint32_t code : {HSIB_STOP_COUNT, 100u, HSIB_STOP_NOT_RECORDED}) {
    const std::string msg = refused(with_stop_word(bytes, 3, 0x100u | code));
    INFO(msg);
    CHECK_THAT(msg, Contains("frame 3: unknown stop code " + std::to_string(code)) && Contains(at3));
  }
  CHECK_THAT(refused(with_stop_word(bytes, 3, 3u)), Contains("frame 3: unknown stop word 0x3") && Contains(at3));
  CHECK_THAT(refused(with_stop_word(bytes, 3, 0x200u | 0x100u | 3u)), Contains("frame 3: unknown stop word 0x303"));
  // Frame 3 did not converge: code 0 contradicts; frame 0 did: any other code does.
  CHECK_THAT(refused(with_stop_word(bytes, 3, 0x100u)), Contains("frame 3: stop code 0 (converged) contradicts the converged flag 4") &&
                                                          Contains(at3));
  CHECK_THAT(refused(with_stop_word(bytes, 0, 0x102u)), Contains("frame 0: stop code 2 (stagnated) contradicts the converged flag 4"));
  // Without the CRC fixed, the checksum catches the change first.
  std::string raw = bytes;
  raw[frame_record(bytes, 3).at + 12] ^= 0x01;
  Sequence C(raw);
  CHECK(C.status == HSIB_ERROR_CHECKSUM);
  // A right word in another frame reads.
  Sequence ok(with_stop_word(bytes, 3, 0x100u | HSIB_STOP_START_FOLDS));
  REQUIRE(ok.status == HSIB_OK);
  uint32_t stop = 0;
  REQUIRE(hsib_frame_stop(ok.s, 3, &stop) == HSIB_OK);
  CHECK(stop == HSIB_STOP_START_FOLDS);
}
