// Issue #20: a frame that stopped without converging is flagged in every output like
// an uncertified one; and the distortion numbers say what they are: sampled at the
// certificate's breakpoints, or certified bounds over ∂Ω (so over Ω).
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "hsi/baked.h"
#include "hsi/baked_runtime.h"
#include "hsi/frames_io.h"
#include "hsi/scene_sequence.h"

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
    uint32_t flags = 0;
    REQUIRE(hsib_frame_info(hs, static_cast<uint32_t>(i), nullptr, &flags) == HSIB_OK);
    CHECK(((flags & HSIB_FRAME_CONVERGED) != 0) == f.converged);
  }
  hsib_close(hs);
}
