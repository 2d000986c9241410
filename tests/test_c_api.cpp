// The C API (hsi/hsi.h, libhsi.so): the C example program reproduces the C++
// engine's results; status codes, messages, the buffer protocol, allocator hooks,
// cancellation; only hsi_* / hsib_* symbols are exported.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>
#include <vector>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "hsi/baked_runtime.h"
#include "hsi/hsi.h"
#include "hsi/scene_sequence.h"
#include "test_shapes.h"

using namespace hsi;
using Catch::Matchers::Contains;

namespace {

std::string run(const std::string& command, int* status) {
  std::string out;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  REQUIRE(p);
  char buf[4096];
  while (size_t n = std::fread(buf, 1, sizeof buf, p)) out.append(buf, n);
  *status = pclose(p);
  return out;
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

const std::filesystem::path kScene = std::filesystem::path(HSI_ASSETS_DIR) / "two_holes.json";

}  // namespace

TEST_CASE("the C example reproduces the C++ results", "[c_api]") {
  const auto dir = std::filesystem::path(HSI_TEST_TMP) / "c_example";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  int status = 0;
  const std::string log = run(std::string(HSI_C_EXAMPLE) + " " + kScene.string() + " " + dir.string() + " 5 2000", &status);
  INFO(log);
  REQUIRE(status == 0);
  CHECK_THAT(log, Contains("hsi " HSI_VERSION_STRING) && Contains("5 frames, 5 certified") && Contains("loading a missing file: I/O error"));

  // The same sequence through the C++ engine.
  Scene scene = load_scene(kScene);
  SceneSequenceOptions o;
  o.frames = 5;
  o.samples = 2000;
  const SceneSequence seq = interpolate_scene(scene, o);
  const double size = seq.setup->size;
  const BasisRows rows = evaluate_basis(seq.setup->cage, scene.handles, kBasisC);
  std::ifstream pts(dir / "points.txt");
  for (size_t f = 0; f < seq.frames.size(); ++f) {
    size_t index;
    double t;
    int certified;
    REQUIRE(pts >> index >> t >> certified);
    CHECK(index == f);
    CHECK(t == seq.frames[f].t);
    CHECK(certified == int(seq.frames[f].certified));
    const VectorXcd want = evaluate_map(rows, seq.frames[f].map).f;
    for (Eigen::Index h = 0; h < want.size(); ++h) {
      double x, y;
      REQUIRE(pts >> x >> y);
      CHECK(std::abs(cd(x, y) - want(h)) < 1e-9 * size);
    }
  }
  const auto report = nlohmann::json::parse(slurp(dir / "report.json"));
  REQUIRE(report["frames"].size() == seq.frames.size());
  for (size_t f = 0; f < seq.frames.size(); ++f) {
    CHECK(report["frames"][f]["iterations"] == seq.frames[f].iterations);
    CHECK(report["frames"][f]["energy"].get<double>() == Approx(seq.frames[f].energy).epsilon(1e-9));
  }
  CHECK(report["summary"]["certified"] == 5);
  // Its baked file plays back the C++ frames.
  hsib_sequence* b = nullptr;
  char error[256];
  REQUIRE(hsib_open_file((dir / "sequence.hsib").c_str(), &b, error, sizeof error) == HSIB_OK);
  std::vector<float> xy, out(2 * scene.handles.size());
  for (const cd& h : scene.handles) {
    xy.push_back(static_cast<float>(h.real()));
    xy.push_back(static_cast<float>(h.imag()));
  }
  hsib_binding* bind = nullptr;
  REQUIRE(hsib_bind(b, xy.data(), scene.handles.size(), 0, &bind, error, sizeof error) == HSIB_OK);
  REQUIRE(hsib_evaluate(bind, 2, out.data(), 0) == HSIB_OK);
  const VectorXcd mid = evaluate_map(rows, seq.frames[2].map).f;
  for (size_t h = 0; h < scene.handles.size(); ++h)
    CHECK(std::abs(cd(out[2 * h], out[2 * h + 1]) - mid(static_cast<Eigen::Index>(h))) < 1e-5 * size);
  hsib_unbind(bind);
  hsib_close(b);
}

TEST_CASE("C API: versions, status codes and messages", "[c_api]") {
  CHECK(hsi_version() == HSI_VERSION);
  CHECK(std::string(hsi_version_string()) == HSI_VERSION_STRING);
  CHECK(std::string(hsi_status_name(HSI_ERROR_NOT_CERTIFIED)) == "not certified");
  hsi_scene* s = reinterpret_cast<hsi_scene*>(0x1);
  CHECK(hsi_scene_load_file("/no/such.json", &s) == HSI_ERROR_IO);
  CHECK(s == nullptr);
  CHECK_THAT(hsi_last_error(), Contains("/no/such.json"));
  CHECK(hsi_scene_load_file(nullptr, &s) == HSI_ERROR_INVALID_ARGUMENT);
  const std::string bad = "{ \"hsi_scene\": 1, \"shape\": { \"outer\": [[0,0],[1,0]] } }";
  CHECK(hsi_scene_load_memory(bad.data(), bad.size(), nullptr, &s) == HSI_ERROR_INPUT);
  CHECK_THAT(hsi_last_error(), Contains("outer"));
  const std::string syntax = "{ \"hsi_scene\": 1,\n \"shape\": [ }";
  CHECK(hsi_scene_load_memory(syntax.data(), syntax.size(), nullptr, &s) == HSI_ERROR_INPUT);
  CHECK_THAT(hsi_last_error(), Contains("line 2"));
  // A successful call clears the message.
  hsi_interpolation_options io;
  hsi_interpolation_options_default(&io);
  CHECK(io.max_iterations == 100);
  CHECK(io.projection == HSI_PROJECTION_FULLPROJ);  // the fewest iterations over the stress corpus (issue #20)
  REQUIRE(hsi_scene_load_file(kScene.c_str(), &s) == HSI_OK);
  CHECK(std::string(hsi_last_error()).empty());

  // The two-call buffer protocol.
  size_t length = 0;
  char small[8];
  CHECK(hsi_scene_to_json(s, small, sizeof small, &length) == HSI_ERROR_BUFFER_TOO_SMALL);
  CHECK(length > 100);
  std::string json(length + 1, '\0');
  REQUIRE(hsi_scene_to_json(s, json.data(), json.size(), &length) == HSI_OK);
  CHECK(nlohmann::json::parse(json.c_str())["hsi_scene"] == 1);

  // Keyframe authoring refuses what it cannot do.
  hsi_scene_info info;
  REQUIRE(hsi_scene_get_info(s, &info) == HSI_OK);
  CHECK(info.hole_count == 2);
  CHECK(info.coefficient_count == info.cage_vertex_count + 2);
  std::vector<double> handles(2 * info.handle_count);
  uint32_t count = 0;
  REQUIRE(hsi_scene_get_handles(s, handles.data(), info.handle_count, &count) == HSI_OK);
  CHECK(count == info.handle_count);
  CHECK(hsi_scene_add_keyframe(s, 100.0, handles.data(), count - 1, nullptr) == HSI_ERROR_INVALID_ARGUMENT);
  CHECK_THAT(hsi_last_error(), Contains("targets for"));
  CHECK(hsi_scene_add_keyframe(s, -1.0, handles.data(), count, nullptr) == HSI_ERROR_INVALID_ARGUMENT);
  CHECK_THAT(hsi_last_error(), Contains("must exceed"));
  const double outside[2] = {1e6, 1e6};
  CHECK(hsi_scene_set_handles(s, outside, 1) == HSI_ERROR_INPUT);
  CHECK_THAT(hsi_last_error(), Contains("handle 0") && Contains("not inside the shape"));

  // A sequence: frame indices, points outside the cage, cancellation.
  REQUIRE(hsi_scene_set_sampling(s, 2000, 0) == HSI_OK);
  CHECK(hsi_scene_set_sampling(s, 5, 0) == HSI_ERROR_INVALID_ARGUMENT);
  hsi_interpolator* it = nullptr;
  REQUIRE(hsi_interpolator_create(s, nullptr, &it) == HSI_OK);
  hsi_scene_destroy(s);  // the interpolator keeps what it needs
  hsi_sequence* seq = nullptr;
  auto cancel_at_2 = [](uint32_t frame, uint32_t, const hsi_frame_report*, void*) -> int { return frame == 1; };
  CHECK(hsi_interpolator_sequence(it, 4, cancel_at_2, nullptr, &seq) == HSI_ERROR_CANCELLED);
  CHECK(seq == nullptr);
  double t0, t1;
  REQUIRE(hsi_interpolator_time_range(it, &t0, &t1) == HSI_OK);
  REQUIRE(hsi_interpolator_frame(it, 0.5 * (t0 + t1), &seq) == HSI_OK);
  REQUIRE(hsi_sequence_frame_count(seq) == 1);
  hsi_frame_report r;
  REQUIRE(hsi_sequence_frame_report(seq, 0, &r) == HSI_OK);
  CHECK(r.certified == 1);
  CHECK(r.t == 0.5 * (t0 + t1));
  CHECK(hsi_sequence_frame_report(seq, 1, &r) == HSI_ERROR_OUT_OF_RANGE);
  CHECK_THAT(hsi_last_error(), Contains("frame 1 is past the end"));
  const double pts[4] = {handles[0], handles[1], 1e6, 0};
  double out[4];
  CHECK(hsi_sequence_evaluate(seq, 0, pts, 2, out) == HSI_ERROR_INPUT);
  CHECK_THAT(hsi_last_error(), Contains("point 1") && Contains("outside"));
  REQUIRE(hsi_sequence_evaluate(seq, 0, pts, 1, out) == HSI_OK);
  CHECK(std::isfinite(out[0]));
  std::vector<double> phi(2 * info.coefficient_count);
  CHECK(hsi_sequence_coefficients(seq, 0, phi.data(), nullptr, info.coefficient_count + 1) == HSI_ERROR_INVALID_ARGUMENT);
  REQUIRE(hsi_sequence_coefficients(seq, 0, phi.data(), nullptr, info.coefficient_count) == HSI_OK);
  size_t csv_len = 0;
  CHECK(hsi_sequence_report_csv(seq, nullptr, 0, &csv_len) == HSI_ERROR_BUFFER_TOO_SMALL);
  std::string csv(csv_len + 1, '\0');
  REQUIRE(hsi_sequence_report_csv(seq, csv.data(), csv.size(), &csv_len) == HSI_OK);
  CHECK_THAT(csv, Contains("frame,t,keyframe,certified"));
  size_t baked = 0;
  CHECK(hsi_sequence_bake_memory(seq, 1, nullptr, 0, &baked) == HSI_ERROR_BUFFER_TOO_SMALL);
  std::vector<char> bytes(baked);
  REQUIRE(hsi_sequence_bake_memory(seq, 1, bytes.data(), bytes.size(), &baked) == HSI_OK);
  CHECK(std::string(bytes.data(), 4) == "HSIB");

  // Rendering: through Vulkan where built, else a clear "unsupported".
  hsi_render_options ro;
  hsi_render_options_default(&ro);
  ro.width = ro.height = 64;
  std::vector<uint8_t> rgba(64 * 64 * 4, 0);
  const char* why = nullptr;
  const bool require_vulkan = std::getenv("HSI_REQUIRE_VULKAN") && HSI_TEST_CAPI_RENDER;
  if (require_vulkan) setenv("HSI_VULKAN_VALIDATION", "1", 1);  // any validation message fails the render
  if (hsi_render_available(&why)) {
    REQUIRE(hsi_sequence_render(seq, 0, &ro, rgba.data(), 0) == HSI_OK);
    int coloured = 0;
    for (size_t i = 0; i < rgba.size(); i += 4) coloured += !(rgba[i] == 255 && rgba[i + 1] == 255 && rgba[i + 2] == 255);
    CHECK(coloured > 200);  // the shape covers part of the white background
  } else {
    INFO(why);
    CHECK_FALSE(require_vulkan);
    CHECK(hsi_sequence_render(seq, 0, &ro, rgba.data(), 0) == HSI_ERROR_UNSUPPORTED);
  }
  hsi_sequence_destroy(seq);
  hsi_interpolator_destroy(it);
}

namespace {
struct Counting {
  long allocations = 0, live = 0;
};
void* count_alloc(size_t size, size_t alignment, void* user) {
  auto* c = static_cast<Counting*>(user);
  ++c->allocations;
  ++c->live;
  return std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment);
}
void count_release(void* p, void* user) {
  --static_cast<Counting*>(user)->live;
  std::free(p);
}
}  // namespace

TEST_CASE("C API allocator hooks see every handle", "[c_api]") {
  Counting c;
  const hsi_allocator a{count_alloc, count_release, &c};
  REQUIRE(hsi_set_allocator(&a) == HSI_OK);
  hsi_scene* s = nullptr;
  REQUIRE(hsi_scene_load_file(kScene.c_str(), &s) == HSI_OK);
  CHECK(c.live == 1);
  CHECK(hsi_set_allocator(nullptr) == HSI_ERROR_INVALID_ARGUMENT);  // a handle exists
  CHECK_THAT(hsi_last_error(), Contains("1 handle(s) still exist"));
  hsi_scene_destroy(s);
  CHECK(c.live == 0);
  CHECK(c.allocations == 1);
  REQUIRE(hsi_set_allocator(nullptr) == HSI_OK);
}

TEST_CASE("libhsi exports only the C API", "[c_api]") {
  int status = 0;
  const std::string syms = run(std::string("nm -D --defined-only ") + HSI_CAPI_LIBRARY, &status);
  REQUIRE(status == 0);
  std::istringstream in(syms);
  std::string line;
  int exported = 0;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string addr, type, name;
    if (!(ls >> addr >> type >> name) || type != "T") continue;
    INFO(name);
    CHECK((name.rfind("hsi_", 0) == 0 || name.rfind("hsib_", 0) == 0));
    ++exported;
  }
  CHECK(exported > 40);
}

TEST_CASE("C API: frame reports and the summary say which frames overlap themselves", "[c_api][overlap]") {
  hsi_scene* s = nullptr;
  REQUIRE(hsi_scene_load_file((std::string(HSI_TESTS_DIR) + "/scenes/bent_bar.json").c_str(), &s) == HSI_OK);
  hsi_interpolator* it = nullptr;
  REQUIRE(hsi_interpolator_create(s, nullptr, &it) == HSI_OK);
  hsi_scene_destroy(s);
  hsi_sequence* seq = nullptr;
  REQUIRE(hsi_interpolator_sequence(it, 3, nullptr, nullptr, &seq) == HSI_OK);
  hsi_frame_report first{}, last{};
  REQUIRE(hsi_sequence_frame_report(seq, 0, &first) == HSI_OK);
  REQUIRE(hsi_sequence_frame_report(seq, 2, &last) == HSI_OK);
  CHECK(first.overlaps == 0);
  CHECK(first.crossings == 0);
  CHECK(last.certified == 1);  // locally injective...
  CHECK(last.overlaps == 1);   // ...but not globally
  CHECK(last.crossings >= 2);
  hsi_sequence_summary sum{};
  REQUIRE(hsi_sequence_summary_get(seq, &sum) == HSI_OK);
  CHECK(sum.overlapping >= 1);
  hsi_sequence_destroy(seq);
  hsi_interpolator_destroy(it);
}

TEST_CASE("C API: frame reports carry the certificate's bounds beside the sampled values, and the summary counts unconverged frames",
          "[c_api]") {
  hsi_scene* s = nullptr;
  REQUIRE(hsi_scene_load_file((std::string(HSI_TESTS_DIR) + "/../assets/annulus.json").c_str(), &s) == HSI_OK);
  hsi_interpolation_options o;
  hsi_interpolation_options_default(&o);
  hsi_interpolator* it = nullptr;
  REQUIRE(hsi_interpolator_create(s, &o, &it) == HSI_OK);
  hsi_sequence* seq = nullptr;
  REQUIRE(hsi_interpolator_sequence(it, 5, nullptr, nullptr, &seq) == HSI_OK);
  uint32_t not_converged = 0, within_certified = 0;
  for (uint32_t f = 0; f < hsi_sequence_frame_count(seq); ++f) {
    hsi_frame_report r{};
    REQUIRE(hsi_sequence_frame_report(seq, f, &r) == HSI_OK);
    REQUIRE(r.certified == 1);
    not_converged += r.converged ? 0 : 1;
    // The certificate bounds what the samples observe: σ1 and κ from above, σ2 from below.
    CHECK(std::isfinite(r.certified_sigma1_max));
    CHECK(r.certified_sigma1_max >= r.sigma1_max);
    CHECK(r.certified_sigma2_min <= r.sigma2_min);
    CHECK(r.certified_sigma2_min > 0);
    CHECK(r.certified_conformal_max >= r.conformal_max);
    CHECK(r.certified_isometric_max >= r.isometric_max);
    CHECK(r.certified_bound_sigma1_max >= r.bound_sigma1_max);
    CHECK(r.certified_bound_excess >= 0);
    within_certified += r.certified_bound_excess == 0 ? 1 : 0;
  }
  hsi_sequence_summary sum{};
  REQUIRE(hsi_sequence_summary_get(seq, &sum) == HSI_OK);
  CHECK(sum.not_converged == not_converged);
  CHECK(sum.stops[HSI_STOP_CONVERGED] + not_converged == sum.frames);
  CHECK(sum.within_certified_bounds == within_certified);
  hsi_sequence_destroy(seq);

  // A solve cut to one iteration stops unconverged: the frame says so and the summary counts it.
  hsi_interpolator_destroy(it);
  o.max_iterations = 1;
  REQUIRE(hsi_interpolator_create(s, &o, &it) == HSI_OK);
  REQUIRE(hsi_interpolator_sequence(it, 5, nullptr, nullptr, &seq) == HSI_OK);
  REQUIRE(hsi_sequence_summary_get(seq, &sum) == HSI_OK);
  CHECK(sum.not_converged > 0);
  uint32_t flagged = 0, at_limit = 0;
  for (uint32_t f = 0; f < hsi_sequence_frame_count(seq); ++f) {
    hsi_frame_report r{};
    REQUIRE(hsi_sequence_frame_report(seq, f, &r) == HSI_OK);
    flagged += r.converged ? 0 : 1;
    // 0.4: why it stopped, consistent with converged; one iteration allowed: the limit.
    CHECK((r.stop == HSI_STOP_CONVERGED) == (r.converged == 1));
    if (!r.converged) CHECK(r.stop == HSI_STOP_ITERATION_LIMIT);
    at_limit += r.stop == HSI_STOP_ITERATION_LIMIT ? 1 : 0;
    if (!r.certified) CHECK(std::isnan(r.certified_sigma1_max));
  }
  CHECK(sum.not_converged == flagged);
  CHECK(at_limit > 0);
  CHECK(sum.stops[HSI_STOP_ITERATION_LIMIT] == at_limit);
  uint32_t by_reason = 0;
  for (int k = 0; k < HSI_STOP_COUNT; ++k) by_reason += sum.stops[k];
  CHECK(by_reason == sum.frames);
  CHECK(sum.stops[HSI_STOP_CONVERGED] + sum.not_converged == sum.frames);
  CHECK(std::string(hsi_stop_name(HSI_STOP_ITERATION_LIMIT)) == "iteration limit");
  CHECK(std::string(hsi_stop_name(HSI_STOP_START_NOT_CERTIFIED)) == "start not certified");
  CHECK(std::string(hsi_stop_name(HSI_STOP_COUNT)) == "unknown");
  CHECK(std::string(hsi_stop_name(-1)) == "unknown");
  hsi_sequence_destroy(seq);
  hsi_interpolator_destroy(it);
  hsi_scene_destroy(s);
}

TEST_CASE("C API: a batch of sequences gives the frames of hsi_interpolator_sequence, for 1 and 3 workers", "[c_api][batch]") {
  // Three sequences on two shapes, one with every interval held (its frames are the keyframes).
  std::vector<hsi_interpolator*> its;
  std::vector<uint32_t> coefficients;
  const std::vector<uint32_t> counts{5, 7, 9};
  const std::pair<const char*, hsi_timing> made[] = {
      {"two_holes", HSI_TIMING_SCENE}, {"annulus", HSI_TIMING_HOLD}, {"annulus", HSI_TIMING_LINEAR}};
  for (const auto& [name, timing] : made) {
    hsi_scene* s = nullptr;
    REQUIRE(hsi_scene_load_file((std::string(HSI_ASSETS_DIR) + "/" + name + ".json").c_str(), &s) == HSI_OK);
    REQUIRE(hsi_scene_set_sampling(s, 1000, 0) == HSI_OK);
    hsi_interpolation_options o;
    hsi_interpolation_options_default(&o);
    o.timing = timing;
    hsi_interpolator* it = nullptr;
    REQUIRE(hsi_interpolator_create(s, &o, &it) == HSI_OK);
    hsi_scene_info info{};
    REQUIRE(hsi_scene_get_info(s, &info) == HSI_OK);
    coefficients.push_back(info.coefficient_count);
    hsi_scene_destroy(s);
    its.push_back(it);
  }
  // The frames one at a time, with one OpenMP thread as each batch worker runs by default
  // (the CPU core's energy is an OpenMP sum, rounded by thread count).
  struct Frames {
    std::vector<double> coefficients;  // phi and psi of every frame
    std::vector<hsi_frame_report> reports;
  };
  const auto frames_of = [](hsi_sequence* seq, uint32_t m) {
    Frames F;
    const uint32_t n = hsi_sequence_frame_count(seq);
    for (uint32_t f = 0; f < n; ++f) {
      hsi_frame_report r{};
      REQUIRE(hsi_sequence_frame_report(seq, f, &r) == HSI_OK);
      F.reports.push_back(r);
      std::vector<double> phi(2 * m), psi(2 * m);
      REQUIRE(hsi_sequence_coefficients(seq, f, phi.data(), psi.data(), m) == HSI_OK);
      F.coefficients.insert(F.coefficients.end(), phi.begin(), phi.end());
      F.coefficients.insert(F.coefficients.end(), psi.begin(), psi.end());
    }
    return F;
  };
  std::vector<Frames> reference;
  {
#ifdef _OPENMP
    const int before = omp_get_max_threads();
    omp_set_num_threads(1);
#endif
    for (size_t k = 0; k < its.size(); ++k) {
      hsi_sequence* seq = nullptr;
      REQUIRE(hsi_interpolator_sequence(its[k], counts[k], nullptr, nullptr, &seq) == HSI_OK);
      reference.push_back(frames_of(seq, coefficients[k]));
      hsi_sequence_destroy(seq);
    }
#ifdef _OPENMP
    omp_set_num_threads(before);
#endif
  }
  int held = 0;
  for (const hsi_frame_report& r : reference[1].reports) held += r.held;
  CHECK(held > 0);

  for (uint32_t workers : {1u, 3u}) {
    INFO("workers = " << workers);
    hsi_batch_options o;
    hsi_batch_options_default(&o);
    CHECK(o.struct_size == sizeof(hsi_batch_options));
    CHECK(o.threads_per_worker == 1);
    o.workers = workers;
    std::vector<hsi_sequence*> out(its.size(), nullptr);
    std::vector<hsi_status> statuses(its.size(), HSI_ERROR_INTERNAL);
    struct Seen {
      uint64_t calls = 0, total = 0;
    } seen;
    auto count_frames = [](uint32_t, uint32_t, uint64_t, uint64_t total, const hsi_frame_report*, void* user) -> int {
      auto* s = static_cast<Seen*>(user);
      ++s->calls;
      s->total = total;
      return 0;
    };
    REQUIRE(hsi_interpolators_sequence_batch(its.data(), counts.data(), static_cast<uint32_t>(its.size()), &o, count_frames, &seen,
                                             out.data(), statuses.data()) == HSI_OK);
    CHECK(seen.calls == 21);
    CHECK(seen.total == 21);
    for (size_t k = 0; k < its.size(); ++k) {
      CHECK(statuses[k] == HSI_OK);
      REQUIRE(out[k]);
      REQUIRE(hsi_sequence_frame_count(out[k]) == counts[k]);
      const Frames F = frames_of(out[k], coefficients[k]);
      for (size_t f = 0; f < counts[k]; ++f) {
        CHECK(F.reports[f].t == reference[k].reports[f].t);
        CHECK(F.reports[f].certified == reference[k].reports[f].certified);
        CHECK(F.reports[f].held == reference[k].reports[f].held);
        CHECK(F.reports[f].iterations == reference[k].reports[f].iterations);
        CHECK(F.reports[f].energy == reference[k].reports[f].energy);
      }
      CHECK(F.coefficients == reference[k].coefficients);  // exactly
      hsi_sequence_destroy(out[k]);
    }
  }

  // Stopped by its progress callback: the unfinished sequences are cancelled, named, NULL.
  hsi_batch_options one;
  hsi_batch_options_default(&one);
  one.workers = 1;
  std::vector<hsi_sequence*> out(its.size(), nullptr);
  std::vector<hsi_status> statuses(its.size(), HSI_OK);
  auto stop_at_2 = [](uint32_t, uint32_t, uint64_t done, uint64_t, const hsi_frame_report*, void*) -> int { return done >= 2; };
  CHECK(hsi_interpolators_sequence_batch(its.data(), counts.data(), 3, &one, stop_at_2, nullptr, out.data(), statuses.data()) ==
        HSI_ERROR_CANCELLED);
  CHECK_THAT(hsi_last_error(), Contains("3 of 3 sequences failed") && Contains("sequence 0 (scene 'two_holes')") && Contains("cancelled"));
  for (size_t k = 0; k < its.size(); ++k) {
    CHECK(statuses[k] == HSI_ERROR_CANCELLED);
    CHECK(out[k] == nullptr);
  }
  // Bad arguments.
  hsi_batch_options old = one;
  old.struct_size = 4;
  CHECK(hsi_interpolators_sequence_batch(its.data(), counts.data(), 3, &old, nullptr, nullptr, out.data(), nullptr) ==
        HSI_ERROR_INVALID_ARGUMENT);
  CHECK_THAT(hsi_last_error(), Contains("struct_size"));
  const uint32_t too_few[] = {5, 1, 5};
  CHECK(hsi_interpolators_sequence_batch(its.data(), too_few, 3, nullptr, nullptr, nullptr, out.data(), nullptr) ==
        HSI_ERROR_INVALID_ARGUMENT);
  CHECK_THAT(hsi_last_error(), Contains("frame_counts[1]"));
  for (hsi_interpolator* it : its) hsi_interpolator_destroy(it);
}
