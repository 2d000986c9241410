// Harmonic shape interpolation (paper §4–5): metric blending, keyframe
// reproduction, pose, certified warm-started sequences, the frames file.
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <set>
#include <thread>

#include "hsi/frames_io.h"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "test_shapes.h"

using namespace hsi;
using Catch::Matchers::Contains;

namespace {

// An annulus whose hole is twisted by 30° against its rim, posed by handles, and then
// the whole thing turned by 100° and moved: large rotation plus a real deformation.
struct TwistScene {
  std::unique_ptr<ShapeSetup> setup;
  std::vector<double> times{0.0, 1.0, 2.0};
  std::vector<HarmonicMap> maps;
  TwistScene() {
    const Shape s = test::annulus(1.0, 0.45, 128);
    setup = std::make_unique<ShapeSetup>(s, build_cage(s), 2000, 0.2);
    std::vector<cd> handles, twist, turned;
    for (int k = 0; k < 6; ++k) {
      const cd u = std::polar(1.0, k * std::numbers::pi / 3);
      handles.push_back(0.93 * u);  // on the rim
      handles.push_back(0.52 * u);  // near the hole
    }
    const cd rot = std::polar(1.0, std::numbers::pi / 6);
    for (size_t i = 0; i < handles.size(); ++i) twist.push_back(i % 2 ? rot * handles[i] : handles[i]);
    const cd turn = std::polar(1.0, 100 * std::numbers::pi / 180);
    for (const cd& p : twist) turned.push_back(turn * p + cd(1.5, -0.5));
    maps.push_back(identity_map(setup->cage));
    const KeyframeResult k1 = author_keyframe(*setup, handles, twist, maps.back());
    REQUIRE(k1.certified);
    REQUIRE(k1.reached);
    maps.push_back(k1.map);
    const KeyframeResult k2 = author_keyframe(*setup, handles, turned, maps.back());
    REQUIRE(k2.certified);
    REQUIRE(k2.reached);
    maps.push_back(k2.map);
  }
};

TwistScene& twist_scene() {
  static TwistScene scene;
  return scene;
}

double max_dist(const VectorXcd& a, const VectorXcd& b) { return (a - b).cwiseAbs().maxCoeff(); }

}  // namespace

TEST_CASE("blended metric is linear between the neighbouring keyframes", "[interpolation]") {
  TwistScene& S = twist_scene();
  Interpolator I(*S.setup, S.times, S.maps);
  const auto m0 = I.blended_metric(0.0), m1 = I.blended_metric(1.0), m2 = I.blended_metric(2.0);
  const auto mq = I.blended_metric(0.25), m15 = I.blended_metric(1.5);
  for (size_t i = 0; i < m0.size(); i += 97) {
    CHECK((mq[i] - (0.75 * m0[i] + 0.25 * m1[i])).norm() < 1e-12);
    CHECK((m15[i] - (0.5 * m1[i] + 0.5 * m2[i])).norm() < 1e-12);
  }
  // Keyframe 1's metric is its own pull-back metric (Eq. 5).
  const MapValues v = evaluate_map(evaluate_basis(S.setup->cage, S.setup->G.points, kBasisD), S.maps[1]);
  CHECK((m1[5] - pullback_metric(v.f_z(5), v.fzbar_conj(5))).norm() < 1e-12);
}

TEST_CASE("a setup's shared backend data: made once while held, made anew once let go, per key, nothing kept on a throw", "[interpolation]") {
  const Shape s = test::annulus(1.0, 0.45, 32);
  const ShapeSetup setup(s, build_cage(s), 200, 0.2);
  std::atomic<int> made{0};
  auto make = [&] {
    ++made;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));  // others ask meanwhile
    return std::static_pointer_cast<void>(std::make_shared<int>(made.load()));
  };
  std::vector<std::shared_ptr<void>> held(6);
  {
    std::vector<std::thread> pool;
    for (size_t t = 0; t < held.size(); ++t) pool.emplace_back([&, t] { held[t] = setup.shared_backend_data("a", make); });
    for (std::thread& t : pool) t.join();
  }
  CHECK(made.load() == 1);  // a batch's workers making cores side by side: one upload
  for (const auto& h : held) CHECK(h == held.front());
  const std::shared_ptr<void> other = setup.shared_backend_data("b", make);  // another key: its own
  CHECK(made.load() == 2);
  CHECK(other != held.front());
  const std::weak_ptr<void> first = held.front();
  held.clear();
  CHECK(first.expired());  // the setup does not keep it alive
  const std::shared_ptr<void> again = setup.shared_backend_data("a", make);
  CHECK(made.load() == 3);
  CHECK(*std::static_pointer_cast<int>(again) == 3);
  CHECK_THROWS_WITH(setup.shared_backend_data("c", []() -> std::shared_ptr<void> { throw InputError("no device"); }), "no device");
  CHECK(setup.shared_backend_data("c", make) != nullptr);  // the failure kept nothing
  CHECK(made.load() == 4);
}

TEST_CASE("the setup's interpolation rows are the basis at G, evaluated once for every thread", "[interpolation]") {
  const Shape s = test::annulus(1.0, 0.45, 64);
  const ShapeSetup setup(s, build_cage(s), 500, 0.2);
  // Many threads ask at once (a batch's workers building interpolators): one evaluation,
  // the same rows for all.
  std::vector<const InterpolationRows*> seen(6, nullptr);
  {
    std::vector<std::thread> pool;
    for (size_t t = 0; t < seen.size(); ++t) pool.emplace_back([&, t] { seen[t] = &setup.interpolation_rows(); });
    for (std::thread& t : pool) t.join();
  }
  for (const InterpolationRows* r : seen) CHECK(r == seen.front());
  const InterpolationRows& rows = *seen.front();
  const BasisRows fresh = evaluate_basis(setup.cage, setup.G.points, kBasisC | kBasisD);
  CHECK(rows.D.D == fresh.D);  // bit for bit: the rows each Interpolator evaluated before
  CHECK(rows.D.C.size() == 0);
  REQUIRE(rows.c_mean.size() == fresh.C.cols());
  // The pose's sums, from their definition.
  cd mean_w = 0;
  for (const cd& w : setup.G.points) mean_w += w;
  mean_w /= static_cast<double>(setup.G.size());
  for (Eigen::Index j = 0; j < fresh.C.cols(); ++j) {
    cd m = 0, r = 0, rb = 0;
    for (Eigen::Index i = 0; i < fresh.C.rows(); ++i) {
      const cd u = setup.G.points[static_cast<size_t>(i)] - mean_w;
      m += fresh.C(i, j);
      r += std::conj(u) * fresh.C(i, j);
      rb += u * fresh.C(i, j);
    }
    m /= static_cast<double>(setup.G.size());
    CHECK(std::abs(rows.c_mean(j) - m) <= 1e-12 * (1 + std::abs(m)));
    CHECK(std::abs(rows.c_rot(j) - r) <= 1e-10 * (1 + std::abs(r)));
    CHECK(std::abs(rows.c_rot_bar(j) - rb) <= 1e-10 * (1 + std::abs(rb)));
  }
}

TEST_CASE("pose of a rigid motion of the identity is that motion", "[interpolation]") {
  TwistScene& S = twist_scene();
  Interpolator I(*S.setup, S.times, S.maps);
  const Pose p0 = I.pose_of(identity_map(S.setup->cage));
  const Pose p = I.pose_of(transform_image(S.setup->cage, identity_map(S.setup->cage), std::polar(1.0, 0.8), cd(2, 1)));
  CHECK(p.angle - p0.angle == Approx(0.8).margin(1e-12));
  CHECK(std::abs(p.centroid - (std::polar(1.0, 0.8) * p0.centroid + cd(2, 1))) < 1e-12);
}

TEST_CASE("keyframes are reproduced at their times", "[interpolation]") {
  TwistScene& S = twist_scene();
  Interpolator I(*S.setup, S.times, S.maps);
  const auto pts = test::interior_points(S.setup->shape, 500);
  const BasisRows rows = evaluate_basis(S.setup->cage, pts, kBasisC);
  for (size_t k = 0; k < S.times.size(); ++k) {
    const FrameResult f = I.frame(S.times[k]);
    CHECK(f.keyframe);
    CHECK(f.certified);
    CHECK(max_dist(evaluate_map(rows, f.map).f, evaluate_map(rows, S.maps[k]).f) < 1e-8);
  }
  // The solver itself lands on keyframe 1 when its metric is the target (t just
  // below 1, started away from it), up to the pose it is given.
  const FrameResult near = I.frame(1.0 - 1e-9, I.frame(0.5).x);
  CHECK(near.certified);
  CHECK(near.energy == Approx(2.0).margin(1e-6));
  CHECK(max_dist(evaluate_map(rows, near.map).f, evaluate_map(rows, S.maps[1]).f) < 2e-3);
}

TEST_CASE("a warm-started sequence is certified, converges in few iterations and follows the pose", "[interpolation]") {
  TwistScene& S = twist_scene();
  Interpolator I(*S.setup, S.times, S.maps);
  int calls = 0;
  const auto frames = I.sequence(41, [&](const FrameResult&, int i, int n) {
    CHECK(i == calls++);
    CHECK(n == 41);
  });
  REQUIRE(frames.size() == 41);
  double iters = 0;
  int solved = 0;
  for (const FrameResult& f : frames) {
    INFO("t = " << f.t << ": " << f.message);
    CHECK(f.certified);
    CHECK(f.converged);
    if (!f.keyframe) {
      iters += f.iterations;
      ++solved;
    }
  }
  CHECK(frames.front().keyframe);
  CHECK(frames[20].keyframe);  // t = 1
  CHECK(frames.back().keyframe);
  INFO("mean iterations " << iters / solved);
  CHECK(iters / solved <= 6);
  // No drift or spin: each frame's pose is the interpolated one, and the poses move
  // continuously through the 100° turn.
  for (size_t i = 1; i < frames.size(); ++i) {
    const Pose p = I.pose_of(frames[i].map), want = I.interpolated_pose(frames[i].t);
    CHECK(std::abs(p.centroid - want.centroid) < 1e-9);
    CHECK(std::remainder(p.angle - want.angle, 2 * std::numbers::pi) == Approx(0).margin(1e-9));
    CHECK(std::abs(p.angle - I.pose_of(frames[i - 1].map).angle) < 0.2);
  }
}

TEST_CASE("a frame that cannot be certified is reported as such, never as good", "[interpolation]") {
  TwistScene& S = twist_scene();
  Interpolator I(*S.setup, S.times, S.maps);
  // A folded warm start: the solver refuses to move from it and says so.
  const Eigen::VectorXd folded = S.setup->metric_space.reduce(affine_map(S.setup->cage, 1.0, 1.4, 0.0)).x;
  const FrameResult f = I.frame(0.5, folded);
  CHECK_FALSE(f.certified);
  CHECK_FALSE(f.converged);
  CHECK_THAT(f.message, Contains("folds") || Contains("not certified"));
}

TEST_CASE("interpolation refuses bad keyframes", "[interpolation]") {
  TwistScene& S = twist_scene();
  CHECK_THROWS_WITH(Interpolator(*S.setup, {0.0}, {S.maps[0]}), Contains("at least two keyframes"));
  CHECK_THROWS_WITH(Interpolator(*S.setup, {1.0, 0.0}, {S.maps[0], S.maps[1]}), Contains("must increase"));
  CHECK_THROWS_WITH(Interpolator(*S.setup, {0.0, 1.0}, {S.maps[0], affine_map(S.setup->cage, 1.0, 1.3, 0.0)}),
                    Contains("keyframe 1 is not locally injective"));
}

TEST_CASE("frames file round-trips and refuses damaged files", "[interpolation][frames_io]") {
  TwistScene& S = twist_scene();
  FrameFile f;
  f.cage = S.setup->cage;
  f.frames.push_back({0.0, true, true, true, 0, 2.0, S.maps[0]});
  f.frames.push_back({0.5, false, false, true, 3, 2.1, S.maps[1]});
  const std::string bytes = encode_frames(f);
  const FrameFile g = decode_frames(bytes);
  REQUIRE(g.frames.size() == 2);
  CHECK(g.cage.loops == f.cage.loops);
  CHECK(g.frames[1].map.phi == f.frames[1].map.phi);
  CHECK_FALSE(g.frames[1].certified);
  CHECK(g.frames[0].keyframe);
  CHECK(g.frames[1].iterations == 3);
  CHECK_THROWS_WITH(decode_frames("XXXX" + bytes.substr(4)), Contains("not an hsi frames file"));
  std::string v3 = bytes;
  v3[4] = 3;  // version 2 is current (stop reasons), 1 still read
  CHECK_THROWS_WITH(decode_frames(v3), Contains("unsupported frames version 3"));
  // Truncated at every length: always a clear error, never a crash.
  for (size_t cut = 0; cut < bytes.size(); cut += 7) CHECK_THROWS_AS(decode_frames(bytes.substr(0, cut)), InputError);
  CHECK_THROWS_WITH(decode_frames(bytes.substr(0, bytes.size() - 5)), Contains("truncated"));
  CHECK_THROWS_WITH(decode_frames(bytes + "junk"), Contains("trailing bytes"));
}

TEST_CASE("a frame's parts are each timed and sum to at most its total", "[interpolation]") {
  TwistScene& S = twist_scene();
  Interpolator I(*S.setup, S.times, S.maps);
  const auto frames = I.sequence(9);
  for (const FrameResult& f : frames) {
    const FrameResult::Parts& p = f.parts;
    INFO("t = " << f.t);
    // The crossing search runs beside the next solve (pipelined_overlap): counted in ms
    // by what the sequence waited for it.
    const double sum = p.targets + p.solve + p.pose + p.image + p.crossings_wait + p.distortion;
    CHECK(sum <= f.ms);
    CHECK(p.crossings_wait >= 0);
    if (f.keyframe) {  // the keyframe itself, made at set-up: nothing timed
      CHECK(sum == 0);
      continue;
    }
    CHECK(p.targets > 0);
    CHECK(p.solve > 0);
    CHECK(p.pose > 0);
    CHECK(p.image > 0);
    CHECK(p.crossings > 0);
    CHECK(p.distortion > 0);
    CHECK(p.solve >= f.timing.energy_gradient + f.timing.hessian + f.timing.solve + f.timing.certificate);
  }
  // frame(): in series, the search all waited for.
  const FrameResult one = I.frame(0.5);
  CHECK(one.parts.crossings > 0);
  CHECK(one.parts.crossings_wait == one.parts.crossings);
  CHECK(one.parts.targets + one.parts.solve + one.parts.pose + one.parts.image + one.parts.crossings + one.parts.distortion <=
        one.ms);
}

TEST_CASE("frames are those of the plain frame loop: set-up certificates and the cached image change no result",
          "[interpolation]") {
  // The reference: each solved frame by newton_solve on a fresh CPU core, its start
  // certified by the solve itself after a keyframe (as before issue #23), the pose as
  // documented, the overlap from the dense basis product at the breakpoints.
  TwistScene& S = twist_scene();
  const ShapeSetup& setup = *S.setup;
  InterpolationOptions io;
  io.predict_start = PredictStart::Auto;  // the replay below covers the predicted starts too
  io.seed_chord_at_keyframes = GENERATE(false, true);  // and the chord slot seeded at keyframes
  INFO("seed_chord_at_keyframes " << io.seed_chord_at_keyframes);
  Interpolator I(setup, S.times, S.maps, io, nullptr,
                 make_cpu_mesh_evaluator(setup.cage, setup.overlap.breakpoints().points));  // injected: as the default
  const auto frames = I.sequence(9);
  const auto dflt = Interpolator(setup, S.times, S.maps, io).sequence(9);
  auto core = make_cpu_newton_core(setup.D_G, setup.H);
  const MatrixXcd C = evaluate_basis(setup.cage, setup.overlap.breakpoints().points, kBasisC).C;
  const CertificateResult* previous = nullptr;
  KeptSystem kept;  // the sequence's chord slot (InterpolationOptions::chord_steps), seeded at keyframes
  SecantPredictor predictor;  // InterpolationOptions::predict_start (Auto)
  int last_iterations = 0, predicted = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    const FrameResult& f = frames[i];
    INFO("frame " << i << ", t = " << f.t);
    const size_t k = f.t <= S.times[1] ? 0 : 1;
    const Eigen::VectorXd p = last_iterations > 1 ? predictor.predict(f.t, S.times[k], S.times[k + 1]) : Eigen::VectorXd();
    predictor.add(f.t, f.x);  // (every frame here is certified and converged: checked below)
    CHECK(f.x == dflt[i].x);
    CHECK(f.overlap.crossings == dflt[i].overlap.crossings);
    const VectorXcd dense = C * f.map.phi + (C * f.map.psi).conjugate();
    const OverlapResult o = setup.overlap.check_points(std::span<const cd>(dense.data(), static_cast<size_t>(dense.size())));
    CHECK(f.overlap.checked);
    CHECK(f.overlap.crossings == o.crossings);
    CHECK(f.overlap.points == o.points);
    if (f.keyframe) {
      const CertificateResult c = setup.certifier.certify(f.map);
      CHECK(f.certificate.certified == c.certified);
      CHECK(f.certificate.sigma1_max == c.sigma1_max);
      CHECK(f.certificate.observed_sigma1_max == c.observed_sigma1_max);
      previous = nullptr;
      kept = KeptSystem{};
      last_iterations = 0;
      if (io.seed_chord_at_keyframes && i + 1 < frames.size()) {  // the keyframe's own exact system
        core->set_targets(I.blended_metric(f.t));
        CHECK(newton_seed_kept_system(*core, setup.metric_space, f.x, frame_newton_options(io), kept));
      }
      continue;
    }
    core->set_targets(I.blended_metric(f.t));
    NewtonOptions no = frame_newton_options(io);
    no.start_certificate = previous;
    no.kept_system = &kept;
    CHECK(f.predicted == (p.size() > 0));
    if (p.size()) {  // from the secant's start, certified by the solve, no chord step
      no.start_certificate = nullptr;
      no.chord_from_start = false;
      ++predicted;
    }
    const NewtonResult n = newton_solve(*core, setup.metric_space, &setup.certifier, nullptr, p.size() ? p : frames[i - 1].x, no);
    REQUIRE(n.certified);
    REQUIRE(n.converged);
    last_iterations = n.iterations;
    CHECK(f.x == n.x);
    CHECK(f.iterations == n.iterations);
    CHECK(f.energy == n.energy);
    CHECK(f.certified == n.certified);
    CHECK(f.certificate.sigma1_max == n.certificate.sigma1_max);
    CHECK(f.certificate.sigma2_min == n.certificate.sigma2_min);
    CHECK(f.certificate.conformal_max == n.certificate.conformal_max);
    CHECK(f.certificate.observed_sigma1_max == n.certificate.observed_sigma1_max);
    CHECK(f.certificate.observed_sigma2_min == n.certificate.observed_sigma2_min);
    CHECK(f.certificate.observed_isometric_max == n.certificate.observed_isometric_max);
    CHECK(f.distortion.sigma1_max == n.certificate.observed_sigma1_max);
    CHECK(f.distortion_certified.sigma1_max == certified_distortion(n.certificate).sigma1_max);
    CHECK(f.distortion_certified.isometric_max == certified_distortion(n.certificate).isometric_max);
    const HarmonicMap canon = setup.metric_space.expand(n.x);
    const Pose have = I.pose_of(canon), want = I.interpolated_pose(f.t);
    const cd rot = std::polar(1.0, want.angle - have.angle);
    const HarmonicMap posed = transform_image(setup.cage, canon, rot, want.centroid - rot * have.centroid);
    CHECK(f.map.phi == posed.phi);
    CHECK(f.map.psi == posed.psi);
    previous = &f.certificate;
  }
  CHECK(predicted > 0);  // the replay above covers the predicted path too
  // The first solved frame started from keyframe 0's set-up certificate, as a frame
  // asked for alone does.
  CHECK(I.frame(frames[1].t).x == frames[1].x);
  // An evaluator for other points is refused.
  const std::vector<cd> few{cd(0.1, 0.1), cd(0.2, 0.1)};
  CHECK_THROWS_WITH(Interpolator(setup, S.times, S.maps, {}, nullptr, make_cpu_mesh_evaluator(setup.cage, few)),
                    Contains("boundary evaluator is made for 2 points"));
}

namespace {

// The CPU core, whose steppers' certificates a test script can refuse: stepper i (in
// the order they are made: the interpolator's set-up makes one per keyframe, then each
// solve one) refuses the certificate at step 0 if i is in refuse_start, and every
// certificate if i is in refuse_all.
// The CPU core with every call forwarded: the test cores below override what they watch.
class ForwardingCore : public NewtonCore {
 public:
  explicit ForwardingCore(const ShapeSetup& s) : inner_(make_cpu_newton_core(s.D_G, s.H)) {}
  int n() const override { return inner_->n(); }
  void set_targets(const std::vector<Metric>& g) override { inner_->set_targets(g); }
  void set_coefficients(const Eigen::VectorXd& v) override { inner_->set_coefficients(v); }
  double energy() override { return inner_->energy(); }
  Eigen::VectorXd gradient() override { return inner_->gradient(); }
  Eigen::MatrixXd hessian(HessianProjection p, bool exact, bool all) override { return inner_->hessian(p, exact, all); }
  void set_direction(const Eigen::VectorXd& dv) override { inner_->set_direction(dv); }
  double max_safe_step() override { return inner_->max_safe_step(); }
  double energy_at(double s) override { return inner_->energy_at(s); }
  ExactSamples preferred_exact_samples() const override { return inner_->preferred_exact_samples(); }

 protected:
  std::unique_ptr<NewtonCore> inner_;
};

class RefusingCore final : public ForwardingCore {
 public:
  RefusingCore(const ShapeSetup& s, std::set<int> refuse_start, std::set<int> refuse_all)
      : ForwardingCore(s), refuse_start_(std::move(refuse_start)), refuse_all_(std::move(refuse_all)) {}
  const char* name() const override { return "refusing cpu"; }
  std::unique_ptr<NewtonStepper> make_stepper(const MapSpace& space, const Certifier* certifier, const QuadraticTerm* quad) override {
    const int i = made_++;
    return std::make_unique<Stepper>(make_host_stepper(*inner_, space, certifier, quad), refuse_start_.count(i) > 0,
                                     refuse_all_.count(i) > 0);
  }

 private:
  struct Stepper final : NewtonStepper {
    Stepper(std::unique_ptr<NewtonStepper> in, bool start, bool all) : inner(std::move(in)), refuse_start(start), refuse_all(all) {}
    double start(const Eigen::VectorXd& x0) override { return inner->start(x0); }
    void linearize(const HessianChoice& c) override { inner->linearize(c); }
    NewtonSystem solve(double ridge) override { return inner->solve(ridge); }
    void trial_energies(std::span<const double> s, std::span<double> e) override { inner->trial_energies(s, e); }
    CertificateResult certify(double step, bool full) override {
      if (refuse_all || (refuse_start && step == 0)) {
        CertificateResult c;
        c.reason = "refused by the test";
        return c;
      }
      return inner->certify(step, full);
    }
    void accept(double step) override { inner->accept(step); }
    Eigen::VectorXd x() override { return inner->x(); }
    std::unique_ptr<NewtonStepper> inner;
    bool refuse_start, refuse_all;
  };
  std::set<int> refuse_start_, refuse_all_;
  int made_ = 0;
};

}  // namespace

// A keyframe whose reduced coefficients the certificate refuses (a keyframe authored at
// the fold limit, its margin at round-off: grid_6/bend_steps in the stress corpus), and
// the frames after it that no certified step can leave it for. Such a frame is flagged;
// the next one starts from the keyframe's coefficients again, with their own certificate
// (not the posed keyframe's, which passes: every frame after a failed one was reported
// certified after 0 iterations), and once a certified step exists the solve takes it
// (NewtonOptions::from_uncertified_start).
TEST_CASE("frames after a keyframe whose coefficients are not certified are flagged until a certified step leaves it",
          "[interpolation]") {
  TwistScene& S = twist_scene();
  // Set-up makes steppers 0, 1, 2 (one per keyframe); the solves of frames 1, 2, 3 make 3, 4, 5.
  Interpolator I(*S.setup, S.times, S.maps, {}, std::make_unique<RefusingCore>(*S.setup, std::set<int>{0}, std::set<int>{3, 4}));
  const std::vector<FrameResult> f = I.sequence(11);  // t = 0, 0.2, 0.4, ...
  REQUIRE(f.size() == 11);
  CHECK(f[0].keyframe);
  CHECK(f[0].certified);
  for (int i : {1, 2}) {
    INFO("frame " << i << ": " << f[static_cast<size_t>(i)].message);
    CHECK_FALSE(f[static_cast<size_t>(i)].certified);
    CHECK(f[static_cast<size_t>(i)].stop == NewtonStop::StartNotCertified);
    CHECK(f[static_cast<size_t>(i)].iterations == 0);
  }
  // Frame 3 starts from keyframe 0's coefficients, refused at step 0, and leaves them.
  INFO("frame 3: " << f[3].message);
  CHECK(f[3].certified);
  CHECK(f[3].converged);
  CHECK(f[3].iterations >= 1);
  for (size_t i = 4; i < f.size(); ++i) {
    INFO("frame " << i << ": " << f[i].message);
    CHECK(f[i].certified);
    CHECK(f[i].converged);
  }
}

namespace {
// The CPU core, certifying maps itself (NewtonCore::certify_map): the setup's certificate,
// marked, or a refusal; counting the calls.
class CertifyingCore final : public ForwardingCore {
 public:
  CertifyingCore(const ShapeSetup& s, bool refuse) : ForwardingCore(s), setup_(s), refuse_(refuse) {}
  const char* name() const override { return "certifying cpu"; }
  std::optional<CertificateResult> certify_map(const Certifier& certifier, const HarmonicMap& map) override {
    ++calls;
    CHECK(&certifier == &setup_.certifier);
    CertificateResult c;
    if (refuse_) {
      c.reason = "refused by the core";
      return c;
    }
    c = certifier.certify(map);
    c.subdivisions = -7;  // the mark
    return c;
  }
  int calls = 0;

 private:
  const ShapeSetup& setup_;
  bool refuse_;
};
}  // namespace

// Keyframes are certified on the core's backend where it can (the CUDA core's device
// certifier, issue #23: the host's certificate was most of an Interpolator's set-up), and
// its verdict is the one that counts: its certificate is the keyframe frame's, its
// refusal refuses the keyframe.
TEST_CASE("an Interpolator certifies its keyframes on the core where the core can", "[interpolation]") {
  TwistScene& S = twist_scene();
  {
    auto core = std::make_unique<CertifyingCore>(*S.setup, false);
    CertifyingCore* c = core.get();
    Interpolator I(*S.setup, S.times, S.maps, {}, std::move(core));
    CHECK(c->calls == static_cast<int>(S.maps.size()));
    for (size_t k = 0; k < S.times.size(); ++k) {
      const FrameResult f = I.frame(S.times[k]);
      CHECK(f.keyframe);
      CHECK(f.certified);
      CHECK(f.certificate.subdivisions == -7);
    }
  }
  try {
    Interpolator I(*S.setup, S.times, S.maps, {}, std::make_unique<CertifyingCore>(*S.setup, true));
    FAIL("a keyframe the core refused was accepted");
  } catch (const InputError& e) {
    CHECK_THAT(e.what(), Catch::Matchers::Contains("keyframe 0 is not locally injective: refused by the core"));
  }
  // The CPU core certifies nothing itself: the host does.
  std::unique_ptr<NewtonCore> cpu = make_cpu_newton_core(S.setup->D_G, S.setup->H);
  CHECK_FALSE(cpu->certify_map(S.setup->certifier, S.maps[0]).has_value());
}

namespace {
// The CPU core, counting the Hessians asked of it.
class CountingCore final : public ForwardingCore {
 public:
  using ForwardingCore::ForwardingCore;
  const char* name() const override { return "counting cpu"; }
  Eigen::MatrixXd hessian(HessianProjection p, bool exact, bool all) override {
    ++hessians;
    return inner_->hessian(p, exact, all);
  }
  int hessians = 0;
};

// A sequence of `frames` frames of the twist scene with these options on a CountingCore,
// and the Hessians its solves asked for (the set-up's not counted).
std::vector<FrameResult> counted_sequence(TwistScene& S, const InterpolationOptions& o, int frames, int& hessians) {
  auto core = std::make_unique<CountingCore>(*S.setup);
  CountingCore* counting = core.get();
  Interpolator I(*S.setup, S.times, S.maps, o, std::move(core));
  const int before = counting->hessians;  // set-up's
  std::vector<FrameResult> f = I.sequence(frames);
  hessians = counting->hessians - before;
  return f;
}

// Two runs of the same sequence under options that should not change its frames beyond
// the tolerance: each frame of `a` certified and converged, keyframes where `b` has them
// and reproduced exactly, the other frames at the energy and σ1 of `b`'s (within the
// tolerance of the same minimiser; not the same x: the cage has modes that barely move
// the boundary). Returns the solved frames' iterations, a's and b's.
std::pair<int, int> check_same_frames(const std::vector<FrameResult>& a, const std::vector<FrameResult>& b) {
  REQUIRE(a.size() == b.size());
  std::pair<int, int> iterations{0, 0};
  for (size_t i = 0; i < a.size(); ++i) {
    INFO("frame " << i << ": " << a[i].message);
    CHECK(a[i].certified);
    CHECK(a[i].converged);
    CHECK(a[i].keyframe == b[i].keyframe);
    if (a[i].keyframe) {
      CHECK(a[i].x == b[i].x);
      continue;
    }
    iterations.first += a[i].iterations;
    iterations.second += b[i].iterations;
    CHECK(std::abs(a[i].energy - b[i].energy) <= 1e-6 * b[i].energy);
    CHECK(std::abs(a[i].distortion.sigma1_max - b[i].distortion.sigma1_max) <= 1e-3 * b[i].distortion.sigma1_max);
  }
  return iterations;
}
}  // namespace

TEST_CASE("a sequence with chord steps builds fewer Hessians, takes no more iterations and gives the frames of one without",
          "[interpolation][chord][long]") {
  TwistScene& S = twist_scene();
  auto run = [&](bool chord, int& hessians) {
    InterpolationOptions o;
    o.chord_steps = chord;
    o.predict_start = PredictStart::Off;  // chord steps alone (a predicted start takes none)
    return counted_sequence(S, o, 81, hessians);
  };
  int with = 0, without = 0;
  const std::vector<FrameResult> a = run(true, with), b = run(false, without);
  REQUIRE(a.size() == b.size());
  INFO("Hessians over the sequence: " << with << " with chord steps, " << without << " without");
  // A frame's first step builds none (where its chord step passes Armijo in full: 103
  // Hessians against 162 when this was written, 78 frames solved).
  CHECK(with + static_cast<int>(a.size()) / 2 <= without);
  const auto [chord_iterations, plain_iterations] = check_same_frames(a, b);
  for (size_t i = 0; i < a.size(); ++i) {  // … and the same conformal distortion
    INFO("frame " << i);
    if (!a[i].keyframe)
      CHECK(std::abs(a[i].distortion.conformal_max - b[i].distortion.conformal_max) <= 1e-3 * b[i].distortion.conformal_max);
  }
  INFO("iterations: " << chord_iterations << " with chord steps, " << plain_iterations << " without");
  CHECK(chord_iterations <= plain_iterations);
}

TEST_CASE("a dense sequence with the chord decrement stop builds fewer Hessians and gives the frames of one without",
          "[interpolation][chord][long]") {
  TwistScene& S = twist_scene();
  auto run = [&](double share, int& hessians) {
    InterpolationOptions o;
    o.chord_decrement_stop = share;
    o.predict_start = PredictStart::Off;
    o.exact_samples = ExactSamples::All;  // as on the CUDA core
    return counted_sequence(S, o, 241, hessians);
  };
  int with = 0, without = 0;
  const std::vector<FrameResult> a = run(0.01, with), b = run(0, without);
  REQUIRE(a.size() == b.size());
  INFO("Hessians over the sequence: " << with << " with the stop, " << without << " without");
  const auto [iterations_with, iterations_without] = check_same_frames(a, b);
  int stopped = 0;
  for (const FrameResult& f : a) stopped += f.message.find("chord decrement") != std::string::npos;
  INFO("frames ended by the chord decrement: " << stopped << "; iterations " << iterations_with << " with the stop, "
                                               << iterations_without << " without");
  CHECK(stopped > 0);
  // Each stop skips the exact system's Hessian; a frame after one may take a step more
  // (236 against 250 Hessians, 24 stops, 136 against 126 iterations when this was written).
  CHECK(with < without);
  CHECK(iterations_with <= iterations_without + static_cast<int>(a.size()) / 10);
}

TEST_CASE("a keyframe seeds the chord slot with its own exact system, and the next frame starts with a chord step",
          "[interpolation][chord]") {
  TwistScene& S = twist_scene();
  const ShapeSetup& setup = *S.setup;
  InterpolationOptions io;
  Interpolator I(setup, S.times, S.maps, io);
  auto core = make_cpu_newton_core(setup.D_G, setup.H);
  for (const size_t j : {size_t{0}, size_t{1}}) {
    INFO("keyframe " << j);
    const Eigen::VectorXd xk = I.frame(S.times[j]).x;
    core->set_targets(I.blended_metric(S.times[j]));
    KeptSystem slot;
    slot.all_samples = true;  // (replaced: a seed starts the slot afresh)
    REQUIRE(newton_seed_kept_system(*core, setup.metric_space, xk, frame_newton_options(io), slot));
    CHECK(!slot.empty());
    CHECK(!slot.all_samples);
    CHECK(slot.order >= setup.metric_space.dim());
    // The first frame after the keyframe, from the keyframe's coefficients: with the seed
    // its first step is a chord step (no system built at the start), and it reaches the
    // same minimiser, in no more iterations, as the solve without one.
    const double t = S.times[j] + 0.05;
    core->set_targets(I.blended_metric(t));
    NewtonOptions no = frame_newton_options(io);
    no.kept_system = &slot;
    const NewtonResult seeded = newton_solve(*core, setup.metric_space, &setup.certifier, nullptr, xk, no);
    KeptSystem empty;
    no.kept_system = &empty;
    const NewtonResult plain = newton_solve(*core, setup.metric_space, &setup.certifier, nullptr, xk, no);
    INFO(seeded.message << " / " << plain.message);
    REQUIRE(seeded.converged);
    REQUIRE(seeded.certified);
    REQUIRE(plain.converged);
    CHECK(seeded.iterations <= plain.iterations);
    CHECK(std::abs(seeded.energy - plain.energy) <= 1e-6 * plain.energy);
    if (j == 0) {  // the twist: a chord step, then the frame's own systems
      REQUIRE(!seeded.log.empty());
      CHECK(seeded.log[0].chord);
      CHECK(!plain.log[0].chord);
    } else {  // keyframe 1 to 2 is a rigid motion, the metric does not move: nothing to step
      CHECK(seeded.iterations == 0);
      CHECK(seeded.message.find("chord decrement below") != std::string::npos);
    }
  }
  // A start whose energy is not finite seeds nothing.
  {
    core->set_targets(I.blended_metric(S.times[0]));
    const Eigen::Index dim = I.frame(S.times[0]).x.size();
    KeptSystem slot;
    CHECK(!newton_seed_kept_system(*core, setup.metric_space, Eigen::VectorXd::Constant(dim, std::numeric_limits<double>::quiet_NaN()),
                                   frame_newton_options(io), slot));
    CHECK(slot.empty());
  }
}

TEST_CASE("a sequence seeded at its keyframes takes no more iterations and gives the frames of one without",
          "[interpolation][chord][long]") {
  TwistScene& S = twist_scene();
  auto run = [&](bool seed, int& hessians) {
    InterpolationOptions o;
    o.seed_chord_at_keyframes = seed;
    o.predict_start = PredictStart::Off;
    return counted_sequence(S, o, 41, hessians);
  };
  int with = 0, without = 0;
  const std::vector<FrameResult> a = run(true, with), b = run(false, without);
  const auto [all_with, all_without] = check_same_frames(a, b);
  int first_with = 0, first_without = 0;  // the frames right after a keyframe
  for (size_t i = 1; i < a.size(); ++i)
    if (a[i - 1].keyframe && !a[i].keyframe) {
      first_with += a[i].iterations;
      first_without += b[i].iterations;
    }
  INFO("iterations of the frames after a keyframe: " << first_with << " seeded, " << first_without << " not; all: " << all_with
                                                      << " / " << all_without << "; Hessians " << with << " / " << without);
  // The seed is one exact system per keyframe; the first frames' chord steps and the
  // frames of the rigid interval (keyframe 1 to 2: nothing to step, ended on the chord's
  // decrement) build none (45 against 62 Hessians, 41 against 40 iterations when this
  // was written: these frames are 0.05 apart, the first one from the identity to a
  // twist takes 3 either way).
  CHECK(first_with <= first_without);
  CHECK(with < without);
  CHECK(all_with <= all_without + static_cast<int>(a.size()) / 10);
}

TEST_CASE("the secant predictor extrapolates the last two frames of an interval and nothing else", "[interpolation][predict]") {
  SecantPredictor p;
  const Eigen::Vector3d a(1, 2, 3), b(2, 0, 3.5);
  CHECK(p.predict(2, 0, 5).size() == 0);  // nothing known
  p.add(0, a);
  CHECK(p.predict(2, 0, 5).size() == 0);  // one frame
  p.add(1, b);
  const Eigen::VectorXd x = p.predict(3, 0, 5);
  REQUIRE(x.size() == 3);
  CHECK((x - (b + 2 * (b - a))).norm() <= 1e-15);  // a line is continued exactly
  CHECK(p.predict(1, 0, 5).size() == 0);     // not after the frames
  CHECK(p.predict(3, 0.5, 5).size() == 0);   // the older frame lies in another interval
  CHECK(p.predict(3, 0, 0.9).size() == 0);   // the newer one too
  const Eigen::Vector3d c(4, -2, 4);
  p.add(2, c);  // the older is dropped
  CHECK((p.predict(2.5, 0, 5) - (c + 0.5 * (c - b))).norm() <= 1e-15);
  p.clear();
  CHECK(p.predict(2.5, 0, 5).size() == 0);
  CHECK(predict_start_names() == std::vector<std::string>{"off", "always", "auto"});
  CHECK(predicts_start(PredictStart::Always, 0));
  CHECK_FALSE(predicts_start(PredictStart::Auto, 1));
  CHECK(predicts_start(PredictStart::Auto, 2));
  CHECK_FALSE(predicts_start(PredictStart::Off, 9));
  CHECK(parse_predict_start("always") == PredictStart::Always);
  CHECK(to_string(parse_predict_start("off")) == std::string("off"));
  CHECK_THROWS_WITH(parse_predict_start("secant"), Contains("unknown start prediction 'secant'"));
}

TEST_CASE("frames started from the secant's prediction take fewer iterations to the same minimisers", "[interpolation][predict][long]") {
  TwistScene& S = twist_scene();
  auto run = [&](PredictStart mode) {
    InterpolationOptions o;
    o.predict_start = mode;
    return Interpolator(*S.setup, S.times, S.maps, o).sequence(41);
  };
  const std::vector<FrameResult> off = run(PredictStart::Off), always = run(PredictStart::Always), autom = run(PredictStart::Auto);
  REQUIRE(off.size() == always.size());
  int it_off = 0, it_always = 0, it_auto = 0, predicted = 0;
  for (size_t i = 0; i < off.size(); ++i) {
    INFO("frame " << i << ", t = " << off[i].t << ": " << always[i].message);
    for (const auto* f : {&always[i], &autom[i]}) {
      CHECK(f->certified);
      CHECK(f->converged);
    }
    CHECK_FALSE(off[i].predicted);
    if (off[i].keyframe) {
      CHECK(always[i].x == off[i].x);  // keyframes reproduced exactly
      CHECK(autom[i].x == off[i].x);
      CHECK_FALSE(always[i].predicted);
      continue;
    }
    // Auto predicts only after a solved frame of more than one iteration.
    if (autom[i].predicted) CHECK((!autom[i - 1].keyframe && autom[i - 1].iterations > 1));
    // Always predicts wherever the interval has two frames before this one.
    const bool two_before = i >= 2 && !off[i - 1].keyframe;
    CHECK(always[i].predicted == two_before);
    predicted += always[i].predicted;
    it_off += off[i].iterations;
    it_always += always[i].iterations;
    it_auto += autom[i].iterations;
    CHECK(std::abs(always[i].energy - off[i].energy) <= 1e-6 * off[i].energy);
    CHECK(std::abs(always[i].distortion.conformal_max - off[i].distortion.conformal_max) <= 1e-3 * off[i].distortion.conformal_max);
  }
  INFO("iterations: " << it_off << " off, " << it_always << " always, " << it_auto << " auto; " << predicted << " frames predicted");
  CHECK(predicted >= 30);
  CHECK(it_always < it_off);
  CHECK(it_auto < it_off);
}
