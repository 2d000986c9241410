// Keyframe timing (issue #26): the log-Euclidean metric maps, the timing weights, and
// sequences through three keyframes whose velocity is continuous in Smooth mode and
// jumps in Linear mode, every blended metric positive definite, keyframes exact.
#include <catch2/catch.hpp>

#include <Eigen/Eigenvalues>
#include <random>

#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/scene_io.h"
#include "hsi/newton.h"
#include "hsi/shape_setup.h"
#include "hsi/timing.h"
#include "test_shapes.h"

using namespace hsi;
using Catch::Matchers::Contains;

namespace {

Eigen::Matrix2d as_matrix(const Metric& m) { return (Eigen::Matrix2d() << m(0), m(1), m(1), m(2)).finished(); }

// Reference log through a numerical eigendecomposition.
Metric reference_log(const Metric& m) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(as_matrix(m));
  const Eigen::Matrix2d l = es.eigenvectors() * es.eigenvalues().array().log().matrix().asDiagonal() * es.eigenvectors().transpose();
  return {l(0, 0), l(0, 1), l(1, 1)};
}

// Three keyframes at uneven times: the first is NOT the identity (sheared and turned),
// the second twists the hole against the rim, the third turns everything by 150°.
struct TimedScene {
  std::unique_ptr<ShapeSetup> setup;
  std::vector<double> times{0.0, 0.7, 2.0};
  std::vector<HarmonicMap> maps;
  TimedScene() {
    const Shape s = test::annulus(1.0, 0.4, 96);
    setup = std::make_unique<ShapeSetup>(s, build_cage(s), 1500, 0.2);
    std::vector<cd> handles, first, twist, turned;
    for (int k = 0; k < 6; ++k) {
      const cd u = std::polar(1.0, k * std::numbers::pi / 3);
      handles.push_back(0.93 * u);
      handles.push_back(0.5 * u);
    }
    const cd rot0 = std::polar(1.0, 0.4), rot = std::polar(1.0, std::numbers::pi / 5);
    for (const cd& p : handles) first.push_back(rot0 * cd(1.3 * p.real() + 0.2 * p.imag(), 0.8 * p.imag()) + cd(3, 1));
    for (size_t i = 0; i < handles.size(); ++i) twist.push_back(i % 2 ? rot * handles[i] : handles[i]);
    const cd turn = std::polar(1.0, 150 * std::numbers::pi / 180);
    for (const cd& p : twist) turned.push_back(turn * p + cd(-2, 0.5));
    HarmonicMap start = identity_map(setup->cage);
    for (const auto* targets : {&first, &twist, &turned}) {
      const KeyframeResult k = author_keyframe(*setup, handles, *targets, start);
      REQUIRE(k.certified);
      REQUIRE(k.reached);
      maps.push_back(k.map);
      start = k.map;
    }
  }
};

TimedScene& timed_scene() {
  static TimedScene scene;
  return scene;
}

// The posed coefficients of the frame at t, as one vector.
Eigen::VectorXcd coefficients_at(Interpolator& I, double t) {
  const FrameResult f = I.frame(t);
  REQUIRE(f.certified);
  REQUIRE(f.converged);
  Eigen::VectorXcd v(f.map.phi.size() + f.map.psi.size());
  v << f.map.phi, f.map.psi;
  return v;
}

// Left and right second-order one-sided derivatives of the posed coefficients at t.
std::pair<Eigen::VectorXcd, Eigen::VectorXcd> one_sided_velocity(Interpolator& I, double t, double h) {
  const Eigen::VectorXcd x0 = coefficients_at(I, t);
  const Eigen::VectorXcd left = (3 * x0 - 4 * coefficients_at(I, t - h) + coefficients_at(I, t - 2 * h)) / (2 * h);
  const Eigen::VectorXcd right = (-3 * x0 + 4 * coefficients_at(I, t + h) - coefficients_at(I, t + 2 * h)) / (2 * h);
  return {left, right};
}

}  // namespace

TEST_CASE("metric log and exp: closed forms against an eigendecomposition, inverse of each other", "[timing]") {
  std::mt19937 rng(26);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 3000; ++trial) {
    // Pull-back metrics of random locally injective Jacobians over six orders of scale,
    // from nearly conformal (|b| ≪ |a|: the series branch) to κ ≈ 2·10⁶.
    const double scale = std::pow(10.0, 3 * U(rng));
    const cd a = scale * std::polar(1.0, 3 * U(rng));
    const double ratio = trial % 3 == 0 ? 1e-7 * std::abs(U(rng)) : trial % 3 == 1 ? 0.99 * std::abs(U(rng)) : 1 - 1e-6 * std::abs(U(rng)) - 1e-9;
    const cd b = ratio * std::abs(a) * std::polar(1.0, 3 * U(rng));
    const Metric m = pullback_metric(a, b);
    // From the Jacobian: the log's eigenvalues are 2 ln(|a| ± |b|) to rounding at any κ.
    const Metric l = metric_log(a, b);
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(as_matrix(l));
    CHECK(es.eigenvalues()(1) == Approx(2 * std::log(std::abs(a) + std::abs(b))).margin(1e-12));
    CHECK(es.eigenvalues()(0) == Approx(2 * std::log(std::abs(a) - std::abs(b))).margin(1e-12));
    CHECK((metric_exp(l) - m).norm() <= 1e-12 * m.norm());
    // From the metric's entries: as accurate as the entries allow (the smaller eigenvalue
    // carries an error of eps times the larger: ~eps·κ² relative), checked where κ ≤ 200.
    if (trial % 3 != 2) {
      CHECK((metric_log(m) - l).norm() <= 1e-10 * (1 + l.norm()));
      CHECK((l - reference_log(m)).norm() <= 1e-10 * (1 + l.norm()));
      CHECK((metric_exp(metric_log(m)) - m).norm() <= 1e-11 * m.norm());
    }
  }
  // exp of any symmetric matrix is positive definite (what keeps Smooth blends valid).
  for (int trial = 0; trial < 2000; ++trial) {
    const Metric s{5 * U(rng), 5 * U(rng), 5 * U(rng)};
    const Metric e = metric_exp(s);
    CHECK(e(0) > 0);
    CHECK(e(0) * e(2) - e(1) * e(1) > 0);
    CHECK((metric_log(e) - s).norm() <= 1e-10 * (1 + s.norm()));
  }
  CHECK(metric_log(Metric(1, 0, 1)).norm() == 0);
  CHECK_THROWS_WITH(metric_log(Metric(1, 2, 1)), Contains("not positive definite"));
}

TEST_CASE("timing weights: partition of unity, keyframes exact, velocity continuous only where both sides are smooth", "[timing]") {
  const std::vector<double> times{0.0, 0.7, 2.0, 2.5};
  const Eigen::Vector4d V(0.3, 1.7, -0.4, 0.9);  // bends at every interior keyframe
  const auto value = [&](const std::vector<KeyTiming>& timing, double t) {
    const std::vector<double> w = key_weights(times, timing, t);
    return Eigen::Map<const Eigen::VectorXd>(w.data(), 4).dot(V);
  };
  const auto velocity_jump = [&](const std::vector<KeyTiming>& timing, double t) {
    const double h = 1e-6;
    return (value(timing, t + h) - value(timing, t)) / h - (value(timing, t) - value(timing, t - h)) / h;
  };
  using K = KeyTiming;
  for (const std::vector<K>& timing : std::vector<std::vector<K>>{{}, {K::Smooth}, {K::Ease}, {K::Hold}, {K::Smooth, K::Linear, K::Ease, K::Hold}}) {
    for (double t = 0; t <= 2.5; t += 0.01) {
      const std::vector<double> w = key_weights(times, timing, t);
      double sum = 0;
      for (double x : w) sum += x;
      CHECK(sum == Approx(1).margin(1e-14));
    }
    for (size_t k = 0; k < times.size(); ++k) CHECK(value(timing, times[k]) == Approx(V(static_cast<Eigen::Index>(k))).margin(1e-14));
  }
  // Linear: (1 − u, u), the paper's blend.
  const std::vector<double> w = key_weights(times, {}, 1.35);
  CHECK(w[1] == Approx(0.5).margin(1e-15));
  CHECK(w[2] == Approx(0.5).margin(1e-15));
  // Smooth: C¹ at the interior keyframes; Linear: a jump there (these values bend).
  for (double tk : {0.7, 2.0}) {
    CHECK(std::abs(velocity_jump({K::Smooth}, tk)) < 1e-4);
    CHECK(std::abs(velocity_jump({}, tk)) > 0.1);
    CHECK(std::abs(velocity_jump({K::Ease}, tk)) < 1e-4);  // zero speed on both sides
  }
  // Smooth into Linear at 0.7: the curve keeps going but its velocity jumps there.
  CHECK(std::abs(velocity_jump({K::Smooth, K::Linear, K::Smooth, K::Smooth}, 0.7)) > 0.1);
  // Hold: the keyframe's value until the next keyframe's time.
  CHECK(value({K::Hold}, 1.99) == V(1));
  CHECK(value({K::Hold}, 2.0) == V(2));
  CHECK_THROWS_WITH(key_weights(times, {K::Smooth, K::Linear}, 1.0), Contains("2 timings for 4 keyframes"));
  CHECK(parse_key_timing("smooth") == K::Smooth);
  CHECK_FALSE(parse_key_timing("bezier"));
}

TEST_CASE("smooth timing: metrics positive definite, keyframes exact, velocity continuous at the interior keyframe", "[timing]") {
  TimedScene& S = timed_scene();
  InterpolationOptions smooth;
  smooth.timing = {KeyTiming::Smooth};
  smooth.tolerance = 1e-14;  // the velocity is compared at h = 1e-3: solve far below it
  Interpolator I(*S.setup, S.times, S.maps, smooth);
  // Every sample's blended metric positive definite on a fine grid (the Hermite weights
  // are negative in places: a linear blend with them could leave the cone).
  for (double t = 0; t <= 2.0; t += 0.02)
    for (const Metric& m : I.blended_metric(t)) {
      REQUIRE(m(0) > 0);
      REQUIRE(m(0) * m(2) - m(1) * m(1) > 0);
    }
  // At a keyframe time the blended metric is the keyframe's (exp ∘ log to rounding) and
  // the frame is the keyframe, exactly.
  const std::vector<Metric> m1 = I.blended_metric(0.7);
  Interpolator L(*S.setup, S.times, S.maps);
  const std::vector<Metric> l1 = L.blended_metric(0.7);
  for (size_t i = 0; i < m1.size(); ++i) CHECK((m1[i] - l1[i]).norm() <= 1e-12 * l1[i].norm());
  const FrameResult k1 = I.frame(0.7);
  CHECK(k1.keyframe);
  CHECK((k1.map.phi - S.maps[1].phi).norm() == 0);

  const double h = 1e-3;
  const auto [left, right] = one_sided_velocity(I, 0.7, h);
  const double speed = std::max(left.norm(), right.norm());
  INFO("smooth: |v+ − v−| / |v| = " << (left - right).norm() / speed);
  CHECK((left - right).norm() <= 0.01 * speed);

  InterpolationOptions linear;
  linear.tolerance = 1e-14;
  Interpolator J(*S.setup, S.times, S.maps, linear);
  const auto [lleft, lright] = one_sided_velocity(J, 0.7, h);
  INFO("linear: |v+ − v−| / |v| = " << (lleft - lright).norm() / std::max(lleft.norm(), lright.norm()));
  CHECK((lleft - lright).norm() >= 0.2 * std::max(lleft.norm(), lright.norm()));
}

TEST_CASE("linear timing given explicitly gives the same frames as none; hold frames are the held keyframe", "[timing]") {
  TimedScene& S = timed_scene();
  Interpolator none(*S.setup, S.times, S.maps);
  InterpolationOptions lin;
  lin.timing = {KeyTiming::Linear, KeyTiming::Linear, KeyTiming::Linear};
  Interpolator linear(*S.setup, S.times, S.maps, lin);
  for (double t : {0.3, 1.1}) {
    const FrameResult a = none.frame(t), b = linear.frame(t);
    CHECK(a.iterations == b.iterations);
    CHECK((a.map.phi - b.map.phi).norm() == 0);
    CHECK((a.map.psi - b.map.psi).norm() == 0);
  }
  InterpolationOptions hold;
  hold.timing = {KeyTiming::Smooth, KeyTiming::Hold, KeyTiming::Linear};
  Interpolator H(*S.setup, S.times, S.maps, hold);
  const std::vector<FrameResult> seq = H.sequence(21);
  int held = 0;
  for (const FrameResult& f : seq) {
    CHECK(f.certified);
    CHECK(f.converged);
    if (f.t > 0.7 && f.t < 2.0) {
      CHECK(f.held);
      CHECK((f.map.phi - S.maps[1].phi).norm() == 0);
      ++held;
    } else {
      CHECK_FALSE(f.held);
    }
  }
  CHECK(held > 10);
  CHECK((seq.back().map.phi - S.maps[2].phi).norm() == 0);
}

TEST_CASE("scene files carry keyframe timing (version 2) and refuse what they cannot mean", "[timing][scene_io]") {
  const std::string shape = R"("shape": {"outer": [[0,0],[4,0],[4,3],[0,3]]}, "handles": [[1,1],[3,2]])";
  const std::string keys = R"("keyframes": [{"time": 0, "targets": [[1,1],[3,2]], "timing": "smooth"},
                                            {"time": 1, "targets": [[1,1],[3,2.5]], "timing": "ease"},
                                            {"time": 2, "targets": [[1,1],[3,2]]}])";
  const Scene s = parse_scene("{\"hsi_scene\": 2, " + shape + ", " + keys + "}", ".");
  REQUIRE(s.keyframes.size() == 3);
  CHECK(s.keyframes[0].timing == KeyTiming::Smooth);
  CHECK(s.keyframes[1].timing == KeyTiming::Ease);
  CHECK(s.keyframes[2].timing == KeyTiming::Linear);
  const std::string written = scene_to_json(s);
  CHECK_THAT(written, Contains("\"hsi_scene\": 2"));
  CHECK(parse_scene(written, ".").keyframes[1].timing == KeyTiming::Ease);
  CHECK_THROWS_WITH(parse_scene("{\"hsi_scene\": 1, " + shape + ", " + keys + "}", "."),
                    Contains("keyframes[0].timing") && Contains("needs \"hsi_scene\": 2"));
  CHECK_THROWS_WITH(parse_scene("{\"hsi_scene\": 2, " + shape + R"(, "keyframes": [{"time": 0, "targets": [[1,1],[3,2]], "timing": "bezier"}]})", "."),
                    Contains("unknown timing \"bezier\"") && Contains("linear, smooth, ease, hold"));
  // Without timing a scene keeps version 1 when written, so existing files do not change.
  Scene plain = s;
  for (Keyframe& k : plain.keyframes) k.timing = KeyTiming::Linear;
  CHECK_THAT(scene_to_json(plain), Contains("\"hsi_scene\": 1"));
}

// NewtonCore::set_target_keys / blend_targets: the interpolator's per-frame targets as a
// blend of the keyframes' metric sets kept by the core (the CUDA core keeps them on the
// GPU). The default blend must set exactly what set_targets of the host blend sets, and
// a token from before newer sets must be refused, not blend the wrong keyframes.
TEST_CASE("a core's target blend sets the blended metrics and refuses a stale token", "[timing]") {
  const Scene scene = load_scene(std::filesystem::path(HSI_ASSETS_DIR) / "annulus.json");
  const auto setup = make_shape_setup(scene, 600, 0.2);
  const size_t G = setup->G.points.size();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  auto random_sets = [&](int K, bool logs) {
    std::vector<std::vector<Metric>> sets(static_cast<size_t>(K), std::vector<Metric>(G));
    for (auto& set : sets)
      for (Metric& m : set) {
        const double a = u(rng), b = u(rng), c = u(rng);
        m = logs ? Metric(a, b, c) : Metric(1 + a, 0.5 * b, 1 + c);  // positive definite
      }
    return sets;
  };
  const auto keys = random_sets(3, false), logs = random_sets(3, true);
  const std::vector<double> w{0.25, 0, 0.75}, ws{-0.1, 0.6, 0.5};
  auto blended = [&](const std::vector<std::vector<Metric>>& sets, const std::vector<double>& wt, bool exponential) {
    std::vector<Metric> m(G, Metric::Zero());
    for (size_t j = 0; j < wt.size(); ++j)
      if (wt[j] != 0)
        for (size_t i = 0; i < G; ++i) m[i] += wt[j] * sets[j][i];
    if (exponential)
      for (Metric& mi : m) mi = metric_exp(mi);
    return m;
  };
  const auto a = make_cpu_newton_core(setup->D_G, setup->H), b = make_cpu_newton_core(setup->D_G, setup->H);
  const Eigen::VectorXd v = setup->metric_space.T() * setup->metric_space.reduce(identity_map(setup->cage)).x;
  a->set_coefficients(v);
  b->set_coefficients(v);
  const std::uint64_t token = a->set_target_keys(keys, logs);
  for (const bool exponential : {false, true}) {
    const auto& wt = exponential ? ws : w;
    REQUIRE(a->blend_targets(token, wt, exponential));
    b->set_targets(blended(exponential ? logs : keys, wt, exponential));
    CHECK(a->energy() == b->energy());
    CHECK(a->gradient() == b->gradient());
  }
  CHECK_THROWS_WITH(a->blend_targets(token, std::vector<double>{1, 0}, false), Catch::Contains("2 weights for 3 metric sets"));
  const std::uint64_t newer = a->set_target_keys(random_sets(2, false), {});
  CHECK(newer != token);
  CHECK_FALSE(a->blend_targets(token, w, false));
  CHECK_FALSE(b->blend_targets(newer, std::vector<double>{1, 0}, false));  // another core's token
  CHECK(a->blend_targets(newer, std::vector<double>{0.5, 0.5}, false));
}

TEST_CASE("scene files carry a keyframe's authoring start (version 2) and refuse what they cannot mean", "[scene_io][keyframes]") {
  const std::string shape = R"("shape": {"outer": [[0,0],[4,0],[4,3],[0,3]]}, "handles": [[1,1],[3,2]])";
  const std::string keys = R"("keyframes": [{"time": 0, "targets": [[1,1],[3,2]]},
                                            {"time": 1, "targets": [[1,1],[3,2.5]], "start": "rest"},
                                            {"time": 2, "targets": [[1,1],[3,2]], "start": "previous"}])";
  const Scene s = parse_scene("{\"hsi_scene\": 2, " + shape + ", " + keys + "}", ".");
  REQUIRE(s.keyframes.size() == 3);
  CHECK(s.keyframes[0].start == Keyframe::Start::Previous);
  CHECK(s.keyframes[1].start == Keyframe::Start::Rest);
  CHECK(s.keyframes[2].start == Keyframe::Start::Previous);
  const std::string written = scene_to_json(s);
  CHECK_THAT(written, Contains("\"hsi_scene\": 2") && Contains("\"start\": \"rest\""));
  const Scene again = parse_scene(written, ".");
  CHECK(again.keyframes[1].start == Keyframe::Start::Rest);
  CHECK(again.keyframes[2].start == Keyframe::Start::Previous);
  CHECK_THROWS_WITH(parse_scene("{\"hsi_scene\": 1, " + shape + ", " + keys + "}", "."),
                    Contains("keyframes[1].start") && Contains("needs \"hsi_scene\": 2"));
  CHECK_THROWS_WITH(parse_scene("{\"hsi_scene\": 2, " + shape + R"(, "keyframes": [{"time": 0, "targets": [[1,1],[3,2]], "start": "identity"}]})", "."),
                    Contains("keyframes[0].start") && Contains("expected \"previous\" or \"rest\", got \"identity\""));
  CHECK_THROWS_WITH(parse_scene("{\"hsi_scene\": 2, " + shape + R"(, "keyframes": [{"time": 0, "targets": [[1,1],[3,2]], "start": 1}]})", "."),
                    Contains("keyframes[0].start") && Contains("expected \"previous\" or \"rest\""));
  // Only authoring from targets starts somewhere: on a keyframe of coefficients alone it means nothing.
  CHECK_THROWS_WITH(parse_scene(R"({"hsi_scene": 2, "shape": {"outer": [[0,0],[4,0],[4,3],[0,3]]}, "keyframes": [{"time": 0, "start": "rest"}]})", "."),
                    Contains("keyframes[0].start") && Contains("gives no \"targets\""));
  // Without a start of rest (and without timing) a scene keeps version 1 when written.
  Scene plain = s;
  for (Keyframe& k : plain.keyframes) k.start = Keyframe::Start::Previous;
  CHECK_THAT(scene_to_json(plain), Contains("\"hsi_scene\": 1") && !Contains("\"start\""));
}
