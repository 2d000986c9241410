// Issue #20: a frame that stopped without converging is flagged in every output like
// an uncertified one; and the distortion numbers say what they are: sampled at the
// certificate's breakpoints, or certified bounds over ∂Ω (so over Ω).
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "hsi/baked.h"
#include "hsi/baked_runtime.h"
#include "hsi/frames_io.h"
#include "hsi/scene_sequence.h"
#include "test_shapes.h"

using namespace hsi;

namespace {

Scene two_holes() { return load_scene(std::filesystem::path(HSI_ASSETS_DIR) / "two_holes.json"); }

// σ1, σ2 of a frame's map at `count` points on the shape's boundary, by chunks.
struct Dense {
  double sigma1_max = 0, sigma2_min = std::numeric_limits<double>::infinity(), conformal_max = 0, isometric_max = 0;
};
Dense dense_boundary(const ShapeSetup& setup, const HarmonicMap& map, size_t count) {
  const BoundarySamples pts = sample_boundary(setup.shape, static_cast<int>(count));
  REQUIRE(pts.size() >= count * 9 / 10);
  Dense d;
  const size_t chunk = 10000;
  for (size_t b = 0; b < pts.size(); b += chunk) {
    const size_t e = std::min(pts.size(), b + chunk);
    const std::span<const cd> part(pts.points.data() + b, e - b);
    const MapValues v = evaluate_map(evaluate_basis(setup.cage, part, kBasisD), map);
    for (Eigen::Index i = 0; i < v.f_z.size(); ++i) {
      const double a = std::abs(v.f_z(i)), c = std::abs(v.fzbar_conj(i));
      const double s1 = a + c, s2 = a - c;
      d.sigma1_max = std::max(d.sigma1_max, s1);
      d.sigma2_min = std::min(d.sigma2_min, s2);
      d.conformal_max = std::max(d.conformal_max, s1 / s2);
      d.isometric_max = std::max(d.isometric_max, 0.5 * (s1 * s1 + 1 / (s1 * s1) + s2 * s2 + 1 / (s2 * s2)));
    }
  }
  return d;
}

}  // namespace

TEST_CASE("certified distortion bounds hold against 100k boundary points; sampled values lie within them", "[flags][distortion]") {
  Scene scene = two_holes();
  auto setup = scene_setup(scene, 1000);
  SceneSequenceOptions o;
  o.frames = 5;
  const SceneSequence seq = interpolate_scene(scene, o, {}, nullptr, setup);
  int checked = 0;
  for (const FrameResult& f : seq.frames) {
    INFO("t = " << f.t << ": " << f.message);
    REQUIRE(f.certified);
    const Distortion& c = f.distortion_certified;
    const Distortion& s = f.distortion;
    const Dense d = dense_boundary(*setup, f.map, 100000);
    INFO("sigma1: sampled " << s.sigma1_max << ", dense " << d.sigma1_max << ", certified " << c.sigma1_max);
    INFO("sigma2: sampled " << s.sigma2_min << ", dense " << d.sigma2_min << ", certified " << c.sigma2_min);
    INFO("kappa: sampled " << s.conformal_max << ", dense " << d.conformal_max << ", certified " << c.conformal_max);
    INFO("E_iso: sampled " << s.isometric_max << ", dense " << d.isometric_max << ", certified " << c.isometric_max);
    // Upper bounds above every dense value, the σ2 bound below; sampled values inside.
    CHECK(c.sigma1_max >= d.sigma1_max * (1 - 1e-12));
    CHECK(c.sigma2_min <= d.sigma2_min * (1 + 1e-12));
    CHECK(c.conformal_max >= d.conformal_max * (1 - 1e-12));
    CHECK(c.isometric_max >= d.isometric_max * (1 - 1e-12));
    CHECK(s.sigma1_max <= c.sigma1_max * (1 + 1e-12));
    CHECK(s.sigma2_min >= c.sigma2_min * (1 - 1e-12));
    CHECK(s.conformal_max <= c.conformal_max * (1 + 1e-12));
    CHECK(s.isometric_max <= c.isometric_max * (1 + 1e-12));
    // The keyframes' certified envelope is an envelope of bounds.
    CHECK(f.certified_bound.sigma1_max >= f.bound.sigma1_max);
    CHECK(f.certified_bound.sigma2_min <= f.bound.sigma2_min);
    CHECK(f.certified_bound.conformal_max >= f.bound.conformal_max);
    CHECK(std::isfinite(f.certified_bound_excess));
    CHECK(f.certified_bound_excess >= 0);
    ++checked;
  }
  CHECK(checked == 5);
}

TEST_CASE("an uncertified frame has no certified distortion bound", "[flags][distortion]") {
  CertificateResult c;
  c.certified = false;
  c.sigma1_max = 2;
  c.sigma2_min = 0.5;
  const Distortion d = certified_distortion(c);
  CHECK(std::isnan(d.sigma1_max));
  CHECK(std::isnan(d.isometric_max));
  c.certified = true;
  c.conformal_max = 4;
  const Distortion e = certified_distortion(c);
  CHECK(e.sigma1_max == 2);
  CHECK(e.sigma2_min == 0.5);
  CHECK(e.conformal_max == 4);
  CHECK(e.isometric_max == Approx(0.25 + 4));  // max(g(0.5), g(2)), g(s) = s² + s⁻²
}

TEST_CASE("report.json and the CSV label sampled distortion and certified bounds", "[flags][distortion]") {
  Scene scene = two_holes();
  auto setup = scene_setup(scene, 1000);
  SceneSequenceOptions o;
  o.frames = 3;
  const SceneSequence seq = interpolate_scene(scene, o, {}, nullptr, setup);
  const nlohmann::json rep = nlohmann::json::parse(report_json(scene, seq));
  REQUIRE(rep.contains("distortion_kinds"));
  CHECK_THAT(rep["distortion_kinds"]["sampled"].get<std::string>(), Catch::Matchers::Contains("breakpoints"));
  CHECK_THAT(rep["distortion_kinds"]["certified"].get<std::string>(), Catch::Matchers::Contains("bounds"));
  for (size_t i = 0; i < seq.frames.size(); ++i) {
    const FrameResult& f = seq.frames[i];
    const nlohmann::json& j = rep["frames"][i];
    INFO("frame " << i);
    CHECK(j["distortion_sampled"]["sigma1_max"].get<double>() == f.distortion.sigma1_max);
    CHECK(j["sigma1_max"].get<double>() == f.distortion.sigma1_max);  // the old key: sampled
    CHECK(j["distortion_certified"]["sigma1_max"].get<double>() == f.distortion_certified.sigma1_max);
    CHECK(j["distortion_certified"]["sigma2_min"].get<double>() == f.distortion_certified.sigma2_min);
    CHECK(j["distortion_certified"]["sigma1_max"].get<double>() >= j["distortion_sampled"]["sigma1_max"].get<double>());
    CHECK(j["certified_bound"]["conformal_max"].get<double>() == f.certified_bound.conformal_max);
    CHECK(j["bound"]["conformal_max"].get<double>() == f.bound.conformal_max);
    CHECK(j.contains("certified_bound_excess"));
  }
  const nlohmann::json& s = rep["summary"];
  CHECK(s["frames_within_keyframe_bounds"].is_number_integer());
  CHECK(s["frames_within_keyframe_certified_bounds"].is_number_integer());
  CHECK(s["max_certified_bound_excess"].is_number());
  CHECK(s["not_converged"].get<int>() == 0);
  const std::string csv = report_csv(seq);
  const std::string header = csv.substr(0, csv.find('\n'));
  CHECK_THAT(header, Catch::Matchers::Contains(",certified_sigma1_max,certified_sigma2_min,certified_conformal_max"));
  CHECK_THAT(header, Catch::Matchers::Contains(",certified_bound_excess"));
  // Every line has the header's number of fields.
  const auto fields = [](const std::string& line) { return std::count(line.begin(), line.end(), ',') + 1; };
  size_t at = csv.find('\n') + 1;
  while (at < csv.size()) {
    const size_t end = csv.find('\n', at);
    CHECK(fields(csv.substr(at, end - at)) == fields(header));
    at = end + 1;
  }
}

TEST_CASE("a frame stopped at max_iterations = 1 is flagged not converged in the report, frames file and baked file",
          "[flags][converged]") {
  Scene scene = two_holes();
  auto setup = scene_setup(scene, 1000);
  SceneSequenceOptions o;
  o.frames = 5;
  o.interpolation.max_iterations = 1;  // every solved frame stops after one Newton step
  const SceneSequence seq = interpolate_scene(scene, o, {}, nullptr, setup);
  int not_converged = 0, certified_not_converged = 0;
  for (const FrameResult& f : seq.frames) {
    not_converged += !f.converged;
    certified_not_converged += f.certified && !f.converged;
  }
  REQUIRE(certified_not_converged > 0);  // the hard case this test is about
  const SequenceSummary sum = summarize(seq.frames, seq.total_s);
  CHECK(sum.not_converged == not_converged);
  const nlohmann::json rep = nlohmann::json::parse(report_json(scene, seq));
  CHECK(rep["summary"]["not_converged"].get<int>() == not_converged);
  CHECK(rep["max_iterations"].get<int>() == 1);
  const FrameFile ff = decode_frames(encode_frames(seq.frame_file()), "flags.hsif");
  const std::string baked = encode_baked(setup->shape, ff);
  hsib_sequence* hs = nullptr;
  REQUIRE(hsib_open_memory(baked.data(), baked.size(), &hs, nullptr, 0) == HSIB_OK);
  for (size_t i = 0; i < seq.frames.size(); ++i) {
    const FrameResult& f = seq.frames[i];
    INFO("frame " << i << " t = " << f.t << ": " << f.message);
    CHECK(rep["frames"][i]["converged"].get<bool>() == f.converged);
    CHECK(ff.frames[i].converged == f.converged);
    // Why it stopped, through the frames file and the baked file (issue #20).
    REQUIRE(ff.frames[i].stop.has_value());
    CHECK(*ff.frames[i].stop == f.stop);
    uint32_t flags = 0;
    REQUIRE(hsib_frame_info(hs, static_cast<uint32_t>(i), nullptr, &flags) == HSIB_OK);
    CHECK(((flags & HSIB_FRAME_CONVERGED) != 0) == f.converged);
    uint32_t stop = HSIB_STOP_NOT_RECORDED;
    REQUIRE(hsib_frame_stop(hs, static_cast<uint32_t>(i), &stop) == HSIB_OK);
    CHECK(stop == static_cast<uint32_t>(f.stop));
    CHECK(std::string(hsib_stop_name(stop)) == to_string(f.stop));
  }
  hsib_close(hs);
  const std::string why = stop_counts(ff.frames);
  CHECK_THAT(why, Catch::Matchers::Contains("iteration limit"));
}

// ---- Stop reasons in frames.hsif (version 2: flag bits 8..15) ------------------------

namespace {

// One frame per stop reason (t = its value), then one not recorded (not converged) and
// one converged that does not say (stored as Converged), over a disc's cage.
FrameFile frames_with_every_stop() {
  FrameFile f;
  f.cage = build_cage(test::disc());
  for (int k = 0; k < kNewtonStopCount; ++k) {
    StoredFrame s;
    s.t = k;
    s.certified = true;
    s.stop = static_cast<NewtonStop>(k);
    s.converged = k == 0;
    s.iterations = static_cast<uint32_t>(k);
    s.energy = 2.0 + k;
    s.map = affine_map(f.cage, 1.0 + 0.01 * k, 0.0, cd(0.1 * k, 0));
    f.frames.push_back(s);
  }
  StoredFrame unknown;
  unknown.t = kNewtonStopCount;
  unknown.certified = true;
  unknown.map = identity_map(f.cage);
  f.frames.push_back(unknown);  // converged false, stop empty: not recorded
  StoredFrame converged = unknown;
  converged.t = kNewtonStopCount + 1;
  converged.converged = true;  // stop empty: stored as Converged
  f.frames.push_back(converged);
  return f;
}

// Byte offset of frame i's flags word (after its f64 time) in an .hsif file.
size_t flags_offset(const std::string& bytes, const FrameFile& f, size_t i) {
  const size_t per_frame = 24 + 32 * static_cast<size_t>(basis_size(f.cage));
  return bytes.size() - (f.frames.size() - i) * per_frame + 8;
}

uint32_t read_u32(const std::string& b, size_t at) {
  uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}
void write_u32(std::string& b, size_t at, uint32_t v) { std::memcpy(b.data() + at, &v, 4); }

std::string frames_error(const std::string& bytes) {
  try {
    (void)decode_frames(bytes, "stops.hsif");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("frames.hsif version 2 round-trips every stop reason in flag bits 8..15", "[flags][frames_io][stop]") {
  const FrameFile f = frames_with_every_stop();
  const std::string bytes = encode_frames(f);
  CHECK(read_u32(bytes, 4) == 2);
  CHECK(kFramesVersion == 2);
  for (size_t i = 0; i < f.frames.size(); ++i) {
    INFO("frame " << i);
    const uint32_t flags = read_u32(bytes, flags_offset(bytes, f, i));
    const uint32_t want = i < static_cast<size_t>(kNewtonStopCount) ? static_cast<uint32_t>(i)
                          : i == static_cast<size_t>(kNewtonStopCount) ? kFramesStopNotRecorded
                                                                       : 0u;
    CHECK((flags >> 8) == want);
    CHECK((flags & 0xF0u) == 0);
    CHECK(((flags & 4u) != 0) == f.frames[i].converged);
  }
  const FrameFile g = decode_frames(bytes, "stops.hsif");
  REQUIRE(g.frames.size() == f.frames.size());
  for (int k = 0; k < kNewtonStopCount; ++k) {
    INFO("stop " << to_string(static_cast<NewtonStop>(k)));
    const StoredFrame& s = g.frames[static_cast<size_t>(k)];
    REQUIRE(s.stop.has_value());
    CHECK(*s.stop == static_cast<NewtonStop>(k));
    CHECK(s.converged == (k == 0));
    CHECK(s.certified);
    CHECK(s.iterations == static_cast<uint32_t>(k));
    CHECK(s.map.phi == f.frames[static_cast<size_t>(k)].map.phi);
  }
  const StoredFrame& unknown = g.frames[static_cast<size_t>(kNewtonStopCount)];
  CHECK_FALSE(unknown.stop.has_value());
  CHECK_FALSE(unknown.converged);
  CHECK(std::string(stop_name(unknown.stop)) == "not recorded");
  const StoredFrame& converged = g.frames.back();
  REQUIRE(converged.stop.has_value());
  CHECK(*converged.stop == NewtonStop::Converged);
  CHECK(converged.converged);
  // Written again: the same bytes.
  CHECK(encode_frames(g) == bytes);
  CHECK(stop_counts(g.frames) ==
        "1 iteration limit, 1 stagnated, 1 certificate refused, 1 no decrease, 1 not factored, 1 start folds, "
        "1 start not certified, 1 not recorded");
  CHECK(stop_counts(std::vector<StoredFrame>{converged}).empty());
}

TEST_CASE("frames.hsif writers refuse a stop reason that contradicts the converged flag", "[flags][frames_io][stop]") {
  FrameFile f = frames_with_every_stop();
  f.frames[2].converged = true;  // stagnated, yet converged
  CHECK_THROWS_WITH(encode_frames(f), Catch::Matchers::Contains("frame 2") && Catch::Matchers::Contains("stagnated") &&
                                          Catch::Matchers::Contains("contradicts its converged flag"));
  f = frames_with_every_stop();
  f.frames[0].converged = false;  // converged, yet not
  CHECK_THROWS_WITH(encode_frames(f), Catch::Matchers::Contains("frame 0") && Catch::Matchers::Contains("contradicts"));
}

TEST_CASE("frames.hsif version 1 still reads: stop Converged with flag 4, not recorded without", "[flags][frames_io][stop]") {
  // A version 1 file built byte by byte in its own layout: a triangle cage (K = 3), two
  // frames, the flags word holding bits 0..3 only.
  std::string v1 = "HSIF";
  auto u32 = [&](uint32_t v) { v1.append(reinterpret_cast<const char*>(&v), 4); };
  auto f64 = [&](double v) { v1.append(reinterpret_cast<const char*>(&v), 8); };
  u32(1);        // version
  u32(1);        // one loop
  u32(3);        // of three vertices
  for (double x : {0.0, 0.0, 1.0, 0.0, 0.0, 1.0}) f64(x);
  u32(0);        // no holes
  u32(3);        // K
  u32(2);        // frames
  const uint32_t v1_flags[2] = {1u | 2u | 4u, 1u | 8u};  // certified keyframe converged; certified, overlaps, NOT converged
  for (int fr = 0; fr < 2; ++fr) {
    f64(0.5 * fr);
    u32(v1_flags[fr]);
    u32(7);     // iterations
    f64(2.25);  // energy
    for (int j = 0; j < 12; ++j) f64(0.125 * (j + 1) + fr);  // φ then ψ, (re, im) each
  }
  const FrameFile g = decode_frames(v1, "old.hsif");
  REQUIRE(g.frames.size() == 2);
  CHECK(g.cage.loops.size() == 1);
  CHECK(g.frames[0].certified);
  CHECK(g.frames[0].keyframe);
  CHECK(g.frames[0].converged);
  REQUIRE(g.frames[0].stop.has_value());
  CHECK(*g.frames[0].stop == NewtonStop::Converged);
  CHECK(g.frames[1].certified);
  CHECK(g.frames[1].overlaps);
  CHECK_FALSE(g.frames[1].converged);
  CHECK_FALSE(g.frames[1].stop.has_value());  // version 1 did not say why
  CHECK(g.frames[1].iterations == 7);
  CHECK(g.frames[1].map.psi(2) == cd(0.125 * 11 + 1, 0.125 * 12 + 1));
  CHECK(stop_counts(g.frames) == "1 not recorded");
  // Written again as version 2: the unknown reason stays unknown (code 255).
  const std::string v2 = encode_frames(g);
  CHECK(read_u32(v2, 4) == 2);
  CHECK(read_u32(v2, flags_offset(v2, g, 1)) == (1u | 8u | (kFramesStopNotRecorded << 8)));
  const FrameFile h = decode_frames(v2);
  CHECK_FALSE(h.frames[1].stop.has_value());
  CHECK(*h.frames[0].stop == NewtonStop::Converged);
  // Version 1 knew no bits above 3: a stop code there is refused.
  std::string bad = v1;
  write_u32(bad, flags_offset(bad, g, 1), 1u | (1u << 8));
  CHECK_THAT(frames_error(bad), Catch::Matchers::Contains("frame 1: unknown frame flags 257"));
  // Version 3 is not read.
  std::string v3 = v2;
  write_u32(v3, 4, 3);
  CHECK_THAT(frames_error(v3), Catch::Matchers::Contains("unsupported frames version 3") &&
                                   Catch::Matchers::Contains("reads versions 1 and 2"));
}

TEST_CASE("frames.hsif refuses an unknown stop code or one that contradicts flag 4, naming the frame and byte",
          "[flags][frames_io][stop]") {
  const FrameFile f = frames_with_every_stop();
  const std::string bytes = encode_frames(f);
  auto with_flags = [&](size_t frame, uint32_t flags) {
    std::string b = bytes;
    write_u32(b, flags_offset(b, f, frame), flags);
    return b;
  };
  const size_t at3 = flags_offset(bytes, f, 3);
  const std::string byte3 = "(at byte " + std::to_string(at3) + ")";
  for (const uint32_t code : {static_cast<uint32_t>(kNewtonStopCount), 100u, 254u}) {
    const std::string msg = frames_error(with_flags(3, 1u | (code << 8)));
    INFO(msg);
    CHECK_THAT(msg, Catch::Matchers::Contains("stops.hsif: frame 3: unknown stop code " + std::to_string(code)) &&
                        Catch::Matchers::Contains(byte3));
  }
  // A reason against flag 4: converged with a reason, not converged with code 0, 255 on a converged frame.
  std::string msg = frames_error(with_flags(3, 1u | 4u | (3u << 8)));
  CHECK_THAT(msg, Catch::Matchers::Contains("frame 3: stop code 3 (certificate refused) contradicts the converged flag 4 (set)") &&
                      Catch::Matchers::Contains(byte3));
  msg = frames_error(with_flags(3, 1u));
  CHECK_THAT(msg, Catch::Matchers::Contains("frame 3: stop code 0 (converged) contradicts the converged flag 4 (clear)"));
  msg = frames_error(with_flags(0, 1u | 4u | (kFramesStopNotRecorded << 8)));
  CHECK_THAT(msg, Catch::Matchers::Contains("frame 0: stop code 255 (not recorded) contradicts"));
  // Bits 4..7 and 16..31 stay unknown flags.
  CHECK_THAT(frames_error(with_flags(5, 1u | 16u | (5u << 8))), Catch::Matchers::Contains("frame 5: unknown frame flags"));
  CHECK_THAT(frames_error(with_flags(5, 1u | (5u << 8) | (1u << 16))), Catch::Matchers::Contains("frame 5: unknown frame flags"));
  // The ones that are right read.
  CHECK_NOTHROW(decode_frames(with_flags(3, 1u | (7u << 8))));
}
