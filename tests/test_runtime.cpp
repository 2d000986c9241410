// runtime/ (issue #21): the one backend factory (auto | cpu | cuda) and the certifier
// factory behind the MapCertifier interface. The decision is tested on every branch
// with made-up CUDA statuses; the real one is tested for what this machine has (no GPU
// here: cuda is refused with the reason, auto falls back with it). The CPU and Vulkan
// certifiers (lavapipe without a GPU) must agree on a bundled scene's keyframes; the
// CUDA one too where a device is present ([cuda]: skipped with a warning without one).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "hsi/runtime/backend.h"
#include "hsi/runtime/certifiers.h"
#include "hsi/scene_io.h"
#include "hsi/scene_sequence.h"
#include "hsi/shape_setup.h"
#include "test_shapes.h"

using namespace hsi;
using Catch::Matchers::Contains;
using runtime::Backend;

namespace {

bool env_set(const char* name) {
  const char* env = std::getenv(name);
  return env && *env && std::string(env) != "0";
}

const std::filesystem::path kScene = std::filesystem::path(HSI_ASSETS_DIR) / "two_holes.json";

std::shared_ptr<const ShapeSetup> small_setup() {
  static Scene scene = load_scene(kScene);
  static const std::shared_ptr<const ShapeSetup> setup = scene_setup(scene, 1000, 0);
  return setup;
}

// Bounds of two certificates of the same map, relative to σ1 max (dense_certify.h states 1e-9).
constexpr double kBoundTol = 1e-9;
double worst_bound_difference(const CertificateResult& a, const CertificateResult& b) {
  const double scale = std::max(a.observed_sigma1_max, 1e-300);
  auto rel = [&](double x, double y, double s) { return x == y ? 0.0 : std::abs(x - y) / std::max({s, std::abs(y), 1e-300}); };
  return std::max({rel(a.min_margin, b.min_margin, scale), rel(a.sigma1_max, b.sigma1_max, scale),
                   rel(a.sigma2_min, b.sigma2_min, scale), rel(a.k_max, b.k_max, 1.0),
                   rel(a.observed_sigma1_max, b.observed_sigma1_max, scale),
                   rel(a.observed_sigma2_min, b.observed_sigma2_min, scale), rel(a.observed_k_max, b.observed_k_max, 1.0)});
}

// The certifier `name` against the CPU reference through the interface, on every
// keyframe of the scene and on a naive blend of two (folded: both verdicts exercised).
void check_against_cpu(MapCertifier& other) {
  const Scene scene = load_scene(kScene);
  const Cage cage = scene_cage(scene);
  const BoundarySamples samples = sample_boundary(scene.shape, scene.samples);
  const std::unique_ptr<MapCertifier> cpu = runtime::make_certifier("cpu", scene.shape, cage, samples);
  std::vector<HarmonicMap> maps;
  for (const Keyframe& k : scene.keyframes)
    if (k.coefficients) maps.push_back(*k.coefficients);
  REQUIRE(maps.size() >= 2);
  maps.push_back({0.5 * (maps[0].phi - maps[1].phi), 0.5 * (maps[0].psi - maps[1].psi)});
  int certified = 0, rejected = 0;
  for (size_t i = 0; i < maps.size(); ++i) {
    INFO(other.name() << " vs cpu, map " << i);
    const CertificateResult c = cpu->certify(maps[i]), g = other.certify(maps[i]);
    CHECK(g.certified == c.certified);
    CHECK(g.reason == c.reason);
    CHECK(g.winding == c.winding);
    CHECK(g.fail_loop == c.fail_loop);
    CHECK(g.fail_edge == c.fail_edge);
    CHECK(g.segments == c.segments);
    CHECK(worst_bound_difference(g, c) <= kBoundTol);
    (c.certified ? certified : rejected)++;
  }
  CHECK(certified == static_cast<int>(maps.size()) - 1);  // the keyframes
  CHECK(rejected == 1);                                   // the blend through zero folds
}

}  // namespace

TEST_CASE("backend names parse, and a bad name is refused with the valid ones", "[runtime]") {
  CHECK(runtime::backend_names() == std::vector<std::string>{"auto", "cpu", "cuda"});
  for (const std::string& n : runtime::backend_names()) CHECK(runtime::to_string(runtime::parse_backend(n)) == n);
  CHECK(runtime::parse_backend("cpu") == Backend::Cpu);
  CHECK(runtime::parse_backend("cuda") == Backend::Cuda);
  CHECK(runtime::parse_backend("auto") == Backend::Auto);
  for (const char* bad : {"gpu", "CPU", "", "vulkan"}) {
    INFO(bad);
    CHECK_THROWS_WITH(runtime::parse_backend(bad), Contains("'" + std::string(bad) + "'") && Contains("auto, cpu, cuda"));
    CHECK_THROWS_AS(runtime::parse_backend(bad), InputError);
  }
  CHECK_THAT(runtime::kBackendHelp, Contains("auto") && Contains("cpu") && Contains("cuda"));
}

TEST_CASE("the backend decision: cpu is cpu, cuda or an error with the reason, auto falls back with it", "[runtime]") {
  const runtime::CudaStatus none{false, "no CUDA device (cudaGetDeviceCount: cudaErrorNoDevice)"};
  const runtime::CudaStatus gpu{true, "NVIDIA H100 (sm_90)"};
  for (const runtime::CudaStatus& s : {none, gpu}) {
    const runtime::BackendChoice c = runtime::choose_backend(Backend::Cpu, s);
    CHECK(c.used == Backend::Cpu);
    CHECK(c.fallback.empty());
    CHECK(c.device.empty());
  }
  CHECK_THROWS_AS(runtime::choose_backend(Backend::Cuda, none), runtime::BackendUnavailable);
  CHECK_THROWS_WITH(runtime::choose_backend(Backend::Cuda, none), "--backend cuda: " + none.detail);
  const runtime::BackendChoice cuda = runtime::choose_backend(Backend::Cuda, gpu);
  CHECK(cuda.used == Backend::Cuda);
  CHECK(cuda.device == gpu.detail);
  CHECK(cuda.fallback.empty());

  const runtime::BackendChoice fell = runtime::choose_backend(Backend::Auto, none);
  CHECK(fell.requested == Backend::Auto);
  CHECK(fell.used == Backend::Cpu);
  CHECK(fell.fallback == none.detail);
  CHECK_THAT(runtime::describe(fell), Contains("cpu") && Contains(none.detail));
  const runtime::BackendChoice took = runtime::choose_backend(Backend::Auto, gpu);
  CHECK(took.used == Backend::Cuda);
  CHECK(took.fallback.empty());
  CHECK(runtime::describe(took) == "cuda (" + gpu.detail + ")");
}

TEST_CASE("the backend factory on this machine", "[runtime]") {
  const auto setup = small_setup();
  const runtime::CudaStatus cuda = runtime::cuda_status();
  INFO("CUDA: " << (cuda.available ? "available, " : "unavailable: ") << cuda.detail);
  CHECK_FALSE(cuda.detail.empty());  // always says something

  runtime::NewtonCoreChoice cpu = runtime::make_newton_core(*setup, Backend::Cpu);
  REQUIRE(cpu.core);
  CHECK(std::string(cpu.core->name()) == "cpu");
  CHECK(cpu.choice.used == Backend::Cpu);
  CHECK(cpu.choice.fallback.empty());

  runtime::NewtonCoreChoice automatic = runtime::make_newton_core(*setup, Backend::Auto);
  REQUIRE(automatic.core);
  CHECK(std::string(automatic.core->name()) == runtime::to_string(automatic.choice.used));
  if (cuda.available) {
    CHECK(automatic.choice.used == Backend::Cuda);
    runtime::NewtonCoreChoice c = runtime::make_newton_core(*setup, Backend::Cuda);
    CHECK(std::string(c.core->name()) == "cuda");
  } else {
    CHECK(automatic.choice.used == Backend::Cpu);
    CHECK(automatic.choice.fallback == cuda.detail);  // the reason, for the caller to print
    CHECK_THROWS_AS(runtime::make_newton_core(*setup, Backend::Cuda), runtime::BackendUnavailable);
    CHECK_THROWS_WITH(runtime::make_newton_core(*setup, Backend::Cuda), Contains(cuda.detail));
  }
  // Whatever was picked solves: the same energy at the identity as the CPU's.
  const Eigen::VectorXd v = setup->map_space.T() * setup->map_space.reduce(identity_map(setup->cage)).x;
  cpu.core->set_coefficients(v);
  automatic.core->set_coefficients(v);
  CHECK(automatic.core->energy() == Approx(cpu.core->energy()).epsilon(1e-12));
}

TEST_CASE("the CUDA wait: a bad name refused; each name set where CUDA runs, else why not", "[runtime]") {
  CHECK_THROWS_AS(runtime::set_cuda_wait("busy"), InputError);
  CHECK_THROWS_WITH(runtime::set_cuda_wait(""), Contains("auto, spin, yield, block"));
  const runtime::CudaStatus cuda = runtime::cuda_status();
  for (const char* name : {"yield", "block", "spin", "auto"}) {  // auto last: the process's default again
    INFO(name);
    const std::string why = runtime::set_cuda_wait(name);
    if (cuda.available) CHECK(why.empty());
    else CHECK_FALSE(why.empty());
  }
  if (cuda.available) {  // a core made after it still solves
    const auto setup = small_setup();
    runtime::NewtonCoreChoice c = runtime::make_newton_core(*setup, Backend::Cuda);
    const Eigen::VectorXd v = setup->map_space.T() * setup->map_space.reduce(identity_map(setup->cage)).x;
    c.core->set_coefficients(v);
    CHECK(std::isfinite(c.core->energy()));
  }
}

TEST_CASE("certifier names, a bad name refused, unavailable ones saying why", "[runtime][certify]") {
  const auto& names = runtime::certifier_names();
  CHECK(std::vector<std::string_view>(names.begin(), names.end()) == std::vector<std::string_view>{"cpu", "cuda", "vulkan"});
  const Shape s = test::annulus();
  const Cage cage = build_cage(s);
  const BoundarySamples g = sample_boundary(s, 500);
  CHECK_THROWS_AS(runtime::make_certifier("opencl", s, cage, g), InputError);
  CHECK_THROWS_WITH(runtime::make_certifier("opencl", s, cage, g), Contains("'opencl'") && Contains("cpu, cuda, vulkan"));
  CHECK_THROWS_AS(runtime::certifier_available("opencl"), InputError);
  std::string why = "unchanged";
  CHECK(runtime::certifier_available("cpu", &why));
  CHECK(why.empty());
  for (const char* name : {"cuda", "vulkan"}) {
    INFO(name);
    if (runtime::certifier_available(name, &why)) {
      CHECK(std::string(runtime::make_certifier(name, s, cage, g)->name()) == name);
    } else {
      CHECK_FALSE(why.empty());
      CHECK_THROWS_AS(runtime::make_certifier(name, s, cage, g), runtime::BackendUnavailable);
      CHECK_THROWS_WITH(runtime::make_certifier(name, s, cage, g), Contains(why));
    }
  }
}

TEST_CASE("the CPU certifier through the interface is the reference itself", "[runtime][certify]") {
  const Scene scene = load_scene(kScene);
  const Cage cage = scene_cage(scene);
  const BoundarySamples samples = sample_boundary(scene.shape, scene.samples);
  const Certifier reference(scene.shape, cage, samples);
  const std::unique_ptr<MapCertifier> cpu = runtime::make_certifier("cpu", scene.shape, cage, samples);
  CHECK(std::string(cpu->name()) == "cpu");
  for (const Keyframe& k : scene.keyframes) {
    const CertificateResult a = reference.certify(*k.coefficients), b = cpu->certify(*k.coefficients);
    CHECK(a.certified == b.certified);
    CHECK(a.sigma1_max == b.sigma1_max);
    CHECK(a.min_margin == b.min_margin);
    CHECK(a.subdivisions == b.subdivisions);
  }
}

TEST_CASE("Vulkan and CPU certifiers agree through the interface", "[runtime][certify][vulkan]") {
  std::string why;
  if (!runtime::certifier_available("vulkan", &why)) {
    if (env_set("HSI_REQUIRE_VULKAN") && why.find("built without") == std::string::npos)
      FAIL("HSI_REQUIRE_VULKAN is set but: " << why);
    WARN("skipped: " << why);
    return;
  }
  const Scene scene = load_scene(kScene);
  const Cage cage = scene_cage(scene);
  runtime::CertifierOptions o;
  o.vulkan_validation = true;
  std::unique_ptr<MapCertifier> vulkan =
      runtime::make_certifier("vulkan", scene.shape, cage, sample_boundary(scene.shape, scene.samples), o);
  CHECK(std::string(vulkan->name()) == "vulkan");
  check_against_cpu(*vulkan);
  INFO(runtime::validation_messages(*vulkan));
  CHECK(runtime::validation_messages(*vulkan).empty());
}

TEST_CASE("CUDA and CPU certifiers agree through the interface", "[runtime][certify][cuda]") {
  std::string why;
  if (!runtime::certifier_available("cuda", &why)) {
    WARN("skipped: " << why);
    return;
  }
  const Scene scene = load_scene(kScene);
  const Cage cage = scene_cage(scene);
  std::unique_ptr<MapCertifier> cuda = runtime::make_certifier("cuda", scene.shape, cage, sample_boundary(scene.shape, scene.samples));
  CHECK(std::string(cuda->name()) == "cuda");
  check_against_cpu(*cuda);
}
