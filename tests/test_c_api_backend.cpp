// The C API's backend option (hsi_interpolation_options.backend, issue #21): cpu is
// the default and stays cpu; auto takes CUDA where it runs, else the CPU with the
// reason (hsi_interpolator_backend); cuda where it cannot run is refused, saying why.
#include <catch2/catch.hpp>

#include <filesystem>
#include <string>

#include "hsi/hsi.h"

using Catch::Matchers::Contains;

namespace {

const std::string kScene = (std::filesystem::path(HSI_ASSETS_DIR) / "two_holes.json").string();

struct Loaded {
  hsi_scene* scene = nullptr;
  Loaded() {
    REQUIRE(hsi_scene_load_file(kScene.c_str(), &scene) == HSI_OK);
    REQUIRE(hsi_scene_set_sampling(scene, 1000, 0) == HSI_OK);
  }
  ~Loaded() { hsi_scene_destroy(scene); }
};

}  // namespace

TEST_CASE("C API: backend names and availability", "[c_api][runtime]") {
  CHECK(std::string(hsi_backend_name(HSI_BACKEND_CPU)) == "cpu");
  CHECK(std::string(hsi_backend_name(HSI_BACKEND_AUTO)) == "auto");
  CHECK(std::string(hsi_backend_name(HSI_BACKEND_CUDA)) == "cuda");
  CHECK(std::string(hsi_backend_name(static_cast<hsi_backend>(3))) == "unknown backend");
  const char* why = "unchanged";
  CHECK(hsi_backend_available(HSI_BACKEND_CPU, &why) == 1);
  CHECK(hsi_backend_available(HSI_BACKEND_AUTO, nullptr) == 1);
  CHECK(hsi_backend_available(static_cast<hsi_backend>(3), &why) == 0);
  CHECK_THAT(why, Contains("unknown backend 3"));
  hsi_interpolation_options o;
  hsi_interpolation_options_default(&o);
  CHECK(o.backend == HSI_BACKEND_CPU);  // 0.1's behaviour unless a host asks
}

TEST_CASE("C API: the cpu backend", "[c_api][runtime]") {
  Loaded l;
  hsi_interpolation_options o;
  hsi_interpolation_options_default(&o);
  hsi_interpolator* interp = nullptr;
  REQUIRE(hsi_interpolator_create(l.scene, &o, &interp) == HSI_OK);
  hsi_backend_info info;
  REQUIRE(hsi_interpolator_backend(interp, &info) == HSI_OK);
  CHECK(info.requested == HSI_BACKEND_CPU);
  CHECK(info.used == HSI_BACKEND_CPU);
  CHECK(std::string(info.fallback).empty());
  CHECK(std::string(info.device).empty());
  hsi_sequence* seq = nullptr;
  REQUIRE(hsi_interpolator_sequence(interp, 3, nullptr, nullptr, &seq) == HSI_OK);
  hsi_sequence_summary sum;
  REQUIRE(hsi_sequence_summary_get(seq, &sum) == HSI_OK);
  CHECK(sum.certified == 3);
  hsi_sequence_destroy(seq);
  CHECK(hsi_interpolator_backend(nullptr, &info) == HSI_ERROR_INVALID_ARGUMENT);
  CHECK(hsi_interpolator_backend(interp, nullptr) == HSI_ERROR_INVALID_ARGUMENT);
  hsi_interpolator_destroy(interp);
}

TEST_CASE("C API: auto reports the backend used and why it fell back, cuda is refused where it cannot run", "[c_api][runtime]") {
  Loaded l;
  const char* why = nullptr;
  const bool cuda = hsi_backend_available(HSI_BACKEND_CUDA, &why) == 1;
  const std::string reason = cuda ? "" : why;
  INFO("CUDA: " << (cuda ? "available" : reason));
  if (!cuda) CHECK_FALSE(reason.empty());

  hsi_interpolation_options o;
  hsi_interpolation_options_default(&o);
  o.backend = HSI_BACKEND_AUTO;
  hsi_interpolator* interp = nullptr;
  REQUIRE(hsi_interpolator_create(l.scene, &o, &interp) == HSI_OK);
  hsi_backend_info info;
  REQUIRE(hsi_interpolator_backend(interp, &info) == HSI_OK);
  CHECK(info.requested == HSI_BACKEND_AUTO);
  if (cuda) {
    CHECK(info.used == HSI_BACKEND_CUDA);
    CHECK(std::string(info.fallback).empty());
    CHECK_FALSE(std::string(info.device).empty());
  } else {
    CHECK(info.used == HSI_BACKEND_CPU);
    CHECK(std::string(info.fallback) == reason.substr(0, sizeof info.fallback - 1));
  }
  hsi_sequence* seq = nullptr;
  REQUIRE(hsi_interpolator_sequence(interp, 3, nullptr, nullptr, &seq) == HSI_OK);
  CHECK(hsi_sequence_frame_count(seq) == 3);
  hsi_sequence_destroy(seq);
  hsi_interpolator_destroy(interp);

  o.backend = HSI_BACKEND_CUDA;
  interp = reinterpret_cast<hsi_interpolator*>(&o);  // must be reset to NULL on failure
  const hsi_status s = hsi_interpolator_create(l.scene, &o, &interp);
  if (cuda) {
    CHECK(s == HSI_OK);
  } else {
    CHECK(s == HSI_ERROR_UNSUPPORTED);
    CHECK(interp == nullptr);
    CHECK_THAT(hsi_last_error(), Contains("cuda") && Contains(reason));
  }
  hsi_interpolator_destroy(interp);

  o.backend = static_cast<hsi_backend>(3);  // past the last value (the enum's range holds 0..3)
  CHECK(hsi_interpolator_create(l.scene, &o, &interp) == HSI_ERROR_INVALID_ARGUMENT);
  CHECK_THAT(hsi_last_error(), Contains("backend 3"));
}

TEST_CASE("C API: keyframe timing (issue #26): the scene's by default, one for all when asked, bad values refused", "[c_api][timing]") {
  Loaded l;
  hsi_interpolation_options o;
  hsi_interpolation_options_default(&o);
  CHECK(o.timing == HSI_TIMING_SCENE);
  const auto frame1 = [&](hsi_timing timing, std::string* json) {
    o.timing = timing;
    hsi_interpolator* interp = nullptr;
    REQUIRE(hsi_interpolator_create(l.scene, &o, &interp) == HSI_OK);
    hsi_sequence* seq = nullptr;
    REQUIRE(hsi_interpolator_sequence(interp, 5, nullptr, nullptr, &seq) == HSI_OK);  // t = 0, 0.5, 1, 1.5, 2
    hsi_frame_report r;
    REQUIRE(hsi_sequence_frame_report(seq, 1, &r) == HSI_OK);
    size_t n = 0;
    REQUIRE(hsi_sequence_report_json(seq, nullptr, 0, &n) == HSI_ERROR_BUFFER_TOO_SMALL);
    json->assign(n + 1, '\0');
    REQUIRE(hsi_sequence_report_json(seq, json->data(), n + 1, &n) == HSI_OK);
    hsi_sequence_destroy(seq);
    hsi_interpolator_destroy(interp);
    return r;
  };
  std::string json;
  const hsi_frame_report held = frame1(HSI_TIMING_HOLD, &json);
  CHECK(held.certified == 1);
  CHECK(held.iterations == 0);  // keyframe 0 itself
  CHECK(held.energy == 2.0);
  CHECK_THAT(json, Contains("\"hold\""));
  const hsi_frame_report linear = frame1(HSI_TIMING_LINEAR, &json);
  CHECK(linear.iterations > 0);
  CHECK(linear.energy > 2.0);
  const hsi_frame_report smooth = frame1(HSI_TIMING_SMOOTH, &json);
  CHECK(smooth.certified == 1);
  CHECK_THAT(json, Contains("\"smooth\""));
  o.timing = static_cast<hsi_timing>(7);
  hsi_interpolator* interp = nullptr;
  CHECK(hsi_interpolator_create(l.scene, &o, &interp) == HSI_ERROR_INVALID_ARGUMENT);
  CHECK_THAT(hsi_last_error(), Contains("timing 7"));
}
