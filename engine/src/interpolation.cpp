// Metric blending, projection by certified Newton, pose interpolation (paper §4–5).
#include "hsi/interpolation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <limits>
#include <mutex>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <sstream>
#include <thread>
#include <utility>

#include "hsi/stopwatch.h"

namespace hsi {

using Clock = std::chrono::steady_clock;

Interpolator::Interpolator(const ShapeSetup& setup, std::vector<double> times, std::vector<HarmonicMap> keyframes,
                           const InterpolationOptions& options, std::unique_ptr<NewtonCore> core,
                           std::unique_ptr<MeshEvaluator> boundary)
    : setup_(setup),
      times_(std::move(times)),
      keys_(std::move(keyframes)),
      options_(options),
      core_(std::move(core)),
      boundary_(std::move(boundary)) {
  if (keys_.size() < 2) throw InputError("interpolation needs at least two keyframes (got " + std::to_string(keys_.size()) + ")");
  if (keys_.size() != times_.size()) throw InputError("interpolation: keyframe times and maps differ in number");
  for (size_t k = 1; k < times_.size(); ++k)
    if (!(times_[k] > times_[k - 1])) throw InputError("interpolation: keyframe times must increase");
  if (!options_.timing.empty() && options_.timing.size() != 1 && options_.timing.size() != keys_.size())
    throw InputError("interpolation: " + std::to_string(options_.timing.size()) + " keyframe timings for " +
                     std::to_string(keys_.size()) + " keyframes (give one per keyframe, or one for all)");
  if (!core_) core_ = make_cpu_newton_core(setup_.D_G, setup_.H);
  if (boundary_ && boundary_->size() != setup_.overlap.breakpoints().size())
    throw InputError("interpolation: the boundary evaluator is made for " + std::to_string(boundary_->size()) +
                     " points; the overlap check has " + std::to_string(setup_.overlap.breakpoints().size()) + " breakpoints");
  const InterpolationRows& rows = setup_.interpolation_rows();  // evaluated once per shape
  c_mean_ = rows.c_mean;
  c_rot_ = rows.c_rot;
  c_rot_bar_ = rows.c_rot_bar;
  const BasisRows& D = rows.D;
  for (size_t k = 0; k < keys_.size(); ++k) {
    std::optional<CertificateResult> on_core = core_->certify_map(setup_.certifier, keys_[k]);
    const CertificateResult c = on_core ? std::move(*on_core) : setup_.certifier.certify(keys_[k]);
    if (!c.certified) throw InputError("keyframe " + std::to_string(k) + " is not locally injective: " + c.reason);
    key_distortion_.push_back(measure(c));
    key_certified_.push_back(certified_distortion(c));
    key_certificate_.push_back(c);
    key_overlap_.push_back(overlap_of(keys_[k]));
    key_x_.push_back(setup_.metric_space.reduce(keys_[k]).x);
    const MapValues v = evaluate_map(D, keys_[k]);
    key_metrics_.push_back(pullback_metrics(v.f_z, v.fzbar_conj));  // Eq. 5
    if (std::find(options_.timing.begin(), options_.timing.end(), KeyTiming::Smooth) != options_.timing.end()) {
      std::vector<Metric> l(key_metrics_.back().size());
      for (Eigen::Index i = 0; i < v.f_z.size(); ++i) l[static_cast<size_t>(i)] = metric_log(v.f_z(i), v.fzbar_conj(i));
      key_log_metrics_.push_back(std::move(l));
    }
    Pose p = pose_of(keys_[k]);
    if (k > 0) {  // unwrap: the nearest turn to the previous keyframe's angle
      const double prev = key_poses_.back().angle;
      p.angle = prev + std::remainder(p.angle - prev, 2 * std::numbers::pi);
    }
    key_poses_.push_back(p);
  }
  // What a solve started at keyframe k certifies first (newton_run: the start's full
  // certificate), made by the core's own stepper as newton_solve makes it, so that the
  // first frame after a keyframe does not certify from scratch. The targets only give
  // the start an energy; every solve sets its own.
  for (size_t k = 0; k < keys_.size(); ++k) {
    std::unique_ptr<NewtonStepper> st = core_->make_stepper(setup_.metric_space, &setup_.certifier, nullptr);
    if (!st) st = make_host_stepper(*core_, setup_.metric_space, &setup_.certifier, nullptr);
    core_->set_targets(key_metrics_[k]);
    (void)st->start(key_x_[k]);
    key_start_certificate_.push_back(st->certify(0, true));
  }
}

Interpolator::~Interpolator() = default;

int Interpolator::segment(double t) const {
  int k = 0;
  while (k + 2 < static_cast<int>(times_.size()) && t > times_[static_cast<size_t>(k) + 1]) ++k;
  return k;
}

std::vector<Metric> Interpolator::blended_metric(double t) const {
  // Linear, Ease, Hold: M_g = Σ w_j M_j (the paper's (1 − t) M⁰ + t M¹ when Linear), a
  // convex combination, so positive definite. Smooth: exp(Σ w_j log M_j), positive
  // definite for any weights (the Hermite weights can be negative).
  const std::vector<double> w = key_weights(times_, options_.timing, t);
  const bool smooth = interval_timing(times_, options_.timing, t) == KeyTiming::Smooth;
  const auto& keys = smooth ? key_log_metrics_ : key_metrics_;
  std::vector<Metric> m(key_metrics_.front().size(), Metric::Zero());
  for (size_t j = 0; j < w.size(); ++j)
    if (w[j] != 0)
      for (size_t i = 0; i < m.size(); ++i) m[i] += w[j] * keys[j][i];
  if (smooth)
    for (Metric& mi : m) mi = metric_exp(mi);
  return m;
}

Pose Interpolator::pose_of(const HarmonicMap& map) const {
  // f_i = (C φ)_i + conj((C ψ)_i); Σ conj(u_i) = 0, so Σ (f_i − f̄) conj(u_i) = Σ f_i conj(u_i).
  // A translation c of the image adds c to the outer loop's φ_j (the outer Cauchy
  // coordinates sum to 1): take it out exactly before the sums, whose rows reproduce
  // constants only to rounding, or a shape far from the origin (|c| ~ 1e6) gets a
  // pose off by ~1e-4 of its size.
  const Eigen::Index outer = static_cast<Eigen::Index>(setup_.cage.loops.front().size());
  const cd ref = map.phi.head(outer).mean();
  VectorXcd phi = map.phi;
  phi.head(outer).array() -= ref;
  const cd cf = ref + (c_mean_ * phi).value() + std::conj((c_mean_ * map.psi).value());
  const cd s = (c_rot_ * phi).value() + std::conj((c_rot_bar_ * map.psi).value());
  return {cf, std::arg(s)};
}

Pose Interpolator::interpolated_pose(double t) const {
  // The pose follows the metrics' timing: the same weights over the keyframes' poses
  // (angles unwrapped, so a blend of angles turns the short way between neighbours).
  const std::vector<double> w = key_weights(times_, options_.timing, t);
  Pose p;
  for (size_t j = 0; j < w.size(); ++j) {
    p.centroid += w[j] * key_poses_[j].centroid;
    p.angle += w[j] * key_poses_[j].angle;
  }
  return p;
}

Distortion Interpolator::measure(const CertificateResult& c) const {
  Distortion d;
  d.sigma1_max = c.observed_sigma1_max;
  d.sigma2_min = c.observed_sigma2_min;
  d.conformal_max = (1 + c.observed_k_max) / (1 - c.observed_k_max);
  d.isometric_max = c.observed_isometric_max;
  return d;
}

Distortion certified_distortion(const CertificateResult& c) {
  if (!c.certified || !(c.sigma2_min > 0)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan, nan};
  }
  const auto g = [](double s) { return s * s + 1 / (s * s); };
  return {c.sigma1_max, c.sigma2_min, c.conformal_max, std::max(g(c.sigma2_min), g(c.sigma1_max))};
}

namespace {
std::span<const cd> points_of(const MapValues& v) { return {v.f.data(), static_cast<size_t>(v.f.size())}; }

// The two keyframes' envelope: the larger σ1, κ, E; the smaller σ2.
Distortion envelope(const Distortion& a, const Distortion& b) {
  return {std::max(a.sigma1_max, b.sigma1_max), std::min(a.sigma2_min, b.sigma2_min), std::max(a.conformal_max, b.conformal_max),
          std::max(a.isometric_max, b.isometric_max)};
}
// How far d leaves the envelope b, relative (0 = within; NaN when d is).
double excess(const Distortion& d, const Distortion& b) {
  if (std::isnan(d.sigma1_max)) return std::numeric_limits<double>::quiet_NaN();
  return std::max({0.0, d.sigma1_max / b.sigma1_max - 1, b.sigma2_min / d.sigma2_min - 1, d.conformal_max / b.conformal_max - 1,
                   d.isometric_max / b.isometric_max - 1});
}
}  // namespace

void Interpolator::boundary_image(const HarmonicMap& map, MapValues& out) {
  if (boundary_) {
    boundary_->evaluate(map, out);
  } else {
    setup_.overlap.image(map, out);
  }
}

OverlapResult Interpolator::overlap_of(const HarmonicMap& map) {
  boundary_image(map, boundary_values_[0]);
  return setup_.overlap.check_points(points_of(boundary_values_[0]), crossing_workspace_);
}

namespace {

// The crossing search of one frame at a time on a thread of its own, kept for one
// sequence: the sequence hands it a frame's image and solves the next frame while it
// searches. What the search throws is rethrown to the sequence by wait().
class CrossingThread {
 public:
  CrossingThread(const OverlapChecker& checker, OverlapChecker::Workspace& workspace)
      : checker_(checker), workspace_(workspace), thread_([this] { run(); }) {}
  CrossingThread(const CrossingThread&) = delete;
  CrossingThread& operator=(const CrossingThread&) = delete;
  ~CrossingThread() {  // a search under way is finished (its image outlives this), its result dropped
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }

  // Starts the search of `image`, which must stay unchanged until wait() returns.
  void submit(std::span<const cd> image) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      image_ = image;
      submitted_ = true;
    }
    wake_.notify_all();
  }

  // The submitted search's result, and its own time in ms.
  OverlapResult wait(double& search_ms) {
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait(lock, [&] { return done_; });
    done_ = false;
    search_ms = ms_;
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
    return result_;
  }

 private:
  void run() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [&] { return stop_ || submitted_; });
      if (stop_) return;
      submitted_ = false;
      const std::span<const cd> image = image_;
      lock.unlock();
      OverlapResult r;
      std::exception_ptr error;
      const auto t0 = Clock::now();
      try {
        r = checker_.check_points(image, workspace_);
      } catch (...) {
        error = std::current_exception();
      }
      const double ms = ms_since(t0);
      lock.lock();
      result_ = r;
      error_ = error;
      ms_ = ms;
      done_ = true;
      wake_.notify_all();
    }
  }

  const OverlapChecker& checker_;
  OverlapChecker::Workspace& workspace_;
  std::mutex mutex_;
  std::condition_variable wake_;  // both ways: a search submitted or stop (to the thread), a search done (to the caller)
  std::span<const cd> image_;
  bool submitted_ = false, done_ = false, stop_ = false;
  OverlapResult result_;
  std::exception_ptr error_;
  double ms_ = 0;
  std::thread thread_;  // last: started once the rest is made
};

}  // namespace

FrameResult Interpolator::frame(double t, const Eigen::VectorXd& warm_start, const CertificateResult* warm_certificate) {
  return frame_searched(t, warm_start, warm_certificate, nullptr);
}

FrameResult Interpolator::frame_searched(double t, const Eigen::VectorXd& warm_start, const CertificateResult* warm_certificate,
                                         KeptSystem* kept, const Eigen::VectorXd* predicted) {
  const auto t0 = Clock::now();
  bool search = false;
  FrameResult r = frame_before_crossings(t, warm_start, warm_certificate, boundary_values_[0], search, kept, predicted);
  if (search) {
    const auto tp = Clock::now();
    r.overlap = setup_.overlap.check_points(points_of(boundary_values_[0]), crossing_workspace_);
    r.parts.crossings = r.parts.crossings_wait = ms_since(tp);
    r.ms = ms_since(t0);
  }
  return r;
}

void Interpolator::set_core_targets(double t) {
  // The keyframes' metric sets live in the core (on the GPU for the CUDA core): per
  // frame only the weights travel. Given again if the core has had other sets since.
  const std::vector<double> w = key_weights(times_, options_.timing, t);
  const bool smooth = interval_timing(times_, options_.timing, t) == KeyTiming::Smooth;
  if (!core_->blend_targets(target_token_, w, smooth)) {
    target_token_ = core_->set_target_keys(key_metrics_, key_log_metrics_);
    if (!core_->blend_targets(target_token_, w, smooth)) throw std::logic_error("the Newton core did not keep the keyframes' metrics");
  }
}

void Interpolator::seed_chord(size_t j, KeptSystem& slot) {
  set_core_targets(times_[j]);  // keyframe j's own metric: key_x_[j] is its minimiser
  newton_seed_kept_system(*core_, setup_.metric_space, key_x_[j], frame_newton_options(options_), slot);
}

FrameResult Interpolator::frame_before_crossings(double t, const Eigen::VectorXd& warm_start,
                                                 const CertificateResult* warm_certificate, MapValues& image, bool& search,
                                                 KeptSystem* kept, const Eigen::VectorXd* predicted) {
  const auto t0 = Clock::now();
  search = false;
  FrameResult r;
  r.t = t;
  const int k = segment(t);
  r.bound = envelope(key_distortion_[static_cast<size_t>(k)], key_distortion_[static_cast<size_t>(k) + 1]);
  r.certified_bound = envelope(key_certified_[static_cast<size_t>(k)], key_certified_[static_cast<size_t>(k) + 1]);
  // Keyframe j itself, exactly: at its own time (the blended metric is the keyframe's
  // own, whose minimiser it is, energy 2) and through a Hold interval that leaves it.
  const auto keyframe_itself = [&](size_t j, std::string message) {
    r.certified = r.converged = true;
    r.map = keys_[j];
    r.x = key_x_[j];
    r.energy = 2.0;
    r.certificate = key_certificate_[j];  // made at set-up, as the overlap
    r.distortion = key_distortion_[j];
    r.overlap = key_overlap_[j];
    r.distortion_certified = key_certified_[j];
    r.bound_excess = excess(r.distortion, r.bound);  // 0: j is one of the envelope's keyframes
    r.certified_bound_excess = excess(r.distortion_certified, r.certified_bound);
    r.message = std::move(message);
    r.ms = ms_since(t0);
    return r;
  };
  for (size_t j = 0; j < times_.size(); ++j)
    if (t == times_[j]) {
      r.keyframe = true;
      return keyframe_itself(j, "keyframe " + std::to_string(j));
    }
  // In a Hold interval t < t_k+1 (t_k+1 itself is its keyframe, above): keyframe k held.
  if (interval_timing(times_, options_.timing, t) == KeyTiming::Hold) {
    r.held = true;
    return keyframe_itself(static_cast<size_t>(k), "keyframe " + std::to_string(k) + " held");
  }
  auto tp = Clock::now();
  set_core_targets(t);
  r.parts.targets = ms_since(tp);
  NewtonOptions no = frame_newton_options(options_);
  const Eigen::VectorXd& x0 = warm_start.size() ? warm_start : key_x_[static_cast<size_t>(k)];
  const CertificateResult* start = warm_start.size() ? warm_certificate : nullptr;
  for (size_t j = 0; !start && j < key_x_.size(); ++j)  // a keyframe's own coefficients: its start certificate
    if (x0.size() == key_x_[j].size() && x0 == key_x_[j]) start = &key_start_certificate_[j];
  if (start) no.start_certificate = start;  // certified or not (NewtonOptions::from_uncertified_start)
  no.kept_system = kept;
  tp = Clock::now();
  NewtonResult n;
  if (predicted && predicted->size() == x0.size()) {
    // The secant's start (InterpolationOptions::predict_start), certified by the solve
    // itself; where that solve fails, the previous frame's start as without it.
    NewtonOptions np = no;
    np.start_certificate = nullptr;
    np.chord_from_start = false;
    n = newton_solve(*core_, setup_.metric_space, &setup_.certifier, nullptr, *predicted, np);
    r.predicted = n.certified && n.converged;
    if (!r.predicted) {
      NewtonResult w = newton_solve(*core_, setup_.metric_space, &setup_.certifier, nullptr, x0, no);
      w.iterations += n.iterations;
      w.timing += n.timing;
      n = std::move(w);
    }
  } else {
    n = newton_solve(*core_, setup_.metric_space, &setup_.certifier, nullptr, x0, no);
  }
  r.parts.solve = ms_since(tp);
  r.x = n.x;
  r.iterations = n.iterations;
  r.energy = n.energy;
  r.converged = n.converged;
  r.stop = n.stop;
  r.certified = n.certified;
  r.certificate = n.certificate;
  r.timing = n.timing;
  r.message = n.message;
  // Pose: move the solution's centroid and Procrustes angle onto the interpolated pose.
  tp = Clock::now();
  const HarmonicMap canon = setup_.metric_space.expand(n.x);
  const Pose have = pose_of(canon), want = interpolated_pose(t);
  const cd rot = std::polar(1.0, want.angle - have.angle);
  r.map = transform_image(setup_.cage, canon, rot, want.centroid - rot * have.centroid);
  r.parts.pose = ms_since(tp);
  // The posed map is checked (a crossing is invariant under its rigid motion, so the
  // canonical map would do as well, but the point reported is where the frame is drawn).
  tp = Clock::now();
  boundary_image(r.map, image);
  r.parts.image = ms_since(tp);
  search = true;
  tp = Clock::now();
  r.distortion = measure(n.certificate);
  r.distortion_certified = certified_distortion(n.certificate);
  r.bound_excess = excess(r.distortion, r.bound);
  r.certified_bound_excess = excess(r.distortion_certified, r.certified_bound);
  r.parts.distortion = ms_since(tp);
  r.ms = ms_since(t0);
  return r;
}

std::vector<FrameResult> Interpolator::sequence(int frames, const std::function<void(const FrameResult&, int, int)>& progress) {
  return sequence(sequence_times({t_begin(), t_end()}, frames), progress);
}

std::vector<FrameResult> Interpolator::sequence(const std::vector<double>& times,
                                                const std::function<void(const FrameResult&, int, int)>& progress) {
  for (size_t i = 0; i < times.size(); ++i)
    if (!(times[i] >= t_begin() && times[i] <= t_end()) || (i > 0 && !(times[i] > times[i - 1])))
      throw InputError("frame times must increase within the keyframes' range [" + std::to_string(t_begin()) + ", " +
                       std::to_string(t_end()) + "]; time " + std::to_string(i) + " is " + std::to_string(times[i]));
  const int frames = static_cast<int>(times.size());
  std::vector<FrameResult> out;
  out.reserve(times.size());
  Eigen::VectorXd warm;
  CertificateResult warm_certificate;
  // `warm` is a keyframe's own coefficients (the last certified frame was a keyframe or
  // held one): its certificate is then the posed keyframe's, not of expand(warm), and
  // frame() takes the start certificate made at set-up instead. Kept across frames that
  // failed: they do not move the warm start, and the frame after them must not pair the
  // keyframe's coefficients with the posed keyframe's certificate (a keyframe at the fold
  // limit whose reduced coefficients the certificate refuses: every frame after a failed
  // one was reported certified without a step, bench_stress grid_6/bend_steps).
  bool warm_is_key = false;
  // The last exact Newton system of the frames since the last keyframe, for the next
  // frame's chord steps (InterpolationOptions::chord_steps).
  KeptSystem kept;
  KeptSystem* const chord = options_.chord_steps ? &kept : nullptr;
  SecantPredictor predictor;  // InterpolationOptions::predict_start
  Eigen::VectorXd prediction;
  int last_iterations = 0;  // of the last solved frame (PredictStart::Auto)
  // Pipelined: solved frame i's crossing search runs on `crossings` while frame i + 1 is
  // solved and its image made (into the other of the two image buffers); then the
  // sequence waits for frame i's search, completes frame i and calls progress for it.
  std::optional<CrossingThread> crossings;
  int pending = -1;  // the solved frame whose search is under way
  int buffer = 0;    // the image buffer the next solved frame's image goes to
  const auto complete = [&](int p) {
    const auto tw = Clock::now();
    double search_ms = 0;
    const OverlapResult o = crossings->wait(search_ms);
    const double waited = ms_since(tw);
    FrameResult& f = out[static_cast<size_t>(p)];
    f.overlap = o;
    f.parts.crossings = search_ms;
    f.parts.crossings_wait = waited;
    f.ms += waited;
    if (progress) progress(f, p, frames);
  };
  for (int i = 0; i < frames; ++i) {
    const double t = times[static_cast<size_t>(i)];
    // Crossing into a new keyframe segment keeps the warm start: frames are continuous.
    // A solved frame's certificate is of its canonical map expand(x): reusable as the
    // next solve's start (a keyframe's, or a held one's, is of the posed map: frame()
    // takes the keyframe's start certificate made at set-up instead).
    const CertificateResult* start = warm.size() == 0 || warm_is_key ? nullptr : &warm_certificate;
    const Eigen::VectorXd* predicted = nullptr;
    if (predicts_start(options_.predict_start, last_iterations) && !keyframe_itself(t)) {
      const size_t k = static_cast<size_t>(segment(t));
      prediction = predictor.predict(t, times_[k], times_[k + 1]);
      if (prediction.size()) predicted = &prediction;
    }
    bool search = false;
    if (options_.pipelined_overlap)
      out.push_back(frame_before_crossings(t, warm, start, boundary_values_[static_cast<size_t>(buffer)], search, chord, predicted));
    else
      out.push_back(frame_searched(t, warm, start, chord, predicted));
    if (out.back().certified) {
      warm = out.back().x;
      warm_certificate = out.back().certificate;
      warm_is_key = out.back().keyframe || out.back().held;
    }
    if (options_.predict_start != PredictStart::Off) {  // (Off: no history kept)
      if (out.back().certified && out.back().converged)
        predictor.add(t, out.back().x);
      else
        predictor.clear();
    }
    if (out.back().keyframe || out.back().held) {
      // The frames after a keyframe (or a held one) depend on nothing before it, so that
      // a sequence cut there (batch.h's runs) solves them alike: no chord system or move
      // to all of G carried across it, and no predicted start until two frames of its
      // interval are known (the predictor keeps to the interval itself).
      kept = KeptSystem{};
      last_iterations = 0;
      // …but the keyframe's own exact system, for the next frame's chord step
      // (InterpolationOptions::seed_chord_at_keyframes).
      if (chord && options_.seed_chord_at_keyframes && out.back().keyframe && i + 1 < frames)
        for (size_t j = 0; j < times_.size(); ++j)
          if (t == times_[j]) seed_chord(j, kept);
    } else {
      last_iterations = out.back().iterations;
    }
    if (pending >= 0) complete(std::exchange(pending, -1));
    if (search) {
      if (!crossings) crossings.emplace(setup_.overlap, crossing_workspace_);
      crossings->submit(points_of(boundary_values_[static_cast<size_t>(buffer)]));
      buffer ^= 1;
      pending = i;
    } else if (progress) {
      progress(out.back(), i, frames);
    }
  }
  if (pending >= 0) complete(pending);
  return out;
}

const char* to_string(PredictStart p) {
  switch (p) {
    case PredictStart::Off: return "off";
    case PredictStart::Always: return "always";
    case PredictStart::Auto: return "auto";
  }
  return "?";
}

namespace {
constexpr std::array kPredictStarts{PredictStart::Off, PredictStart::Always, PredictStart::Auto};
}  // namespace

const std::vector<std::string>& predict_start_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (PredictStart p : kPredictStarts) v.emplace_back(to_string(p));
    return v;
  }();
  return names;
}

PredictStart parse_predict_start(const std::string& name) {
  for (PredictStart p : kPredictStarts)
    if (name == to_string(p)) return p;
  throw InputError("unknown start prediction '" + name + "' (off, always or auto)");
}

void SecantPredictor::add(double t, const Eigen::VectorXd& x) {
  if (count_ == 2) {
    t_[0] = t_[1];
    x_[0].swap(x_[1]);
  }
  const size_t i = count_ == 2 ? 1 : static_cast<size_t>(count_++);
  t_[i] = t;
  x_[i] = x;
}

Eigen::VectorXd SecantPredictor::predict(double t, double lo, double hi) const {
  if (count_ < 2 || !(t_[0] >= lo && t_[1] <= hi && t_[0] < t_[1] && t > t_[1]) || x_[0].size() != x_[1].size()) return {};
  const double s = (t - t_[1]) / (t_[1] - t_[0]);
  return x_[1] + s * (x_[1] - x_[0]);
}

NewtonOptions frame_newton_options(const InterpolationOptions& o) {
  NewtonOptions no;
  no.tolerance = o.tolerance;
  no.projected_decrement_stop = o.projected_decrement_stop;
  no.checked_decrement_stop = o.checked_decrement_stop;
  no.chord_decrement_stop = o.chord_decrement_stop;
  no.max_iterations = o.max_iterations;
  no.projection = o.projection;
  no.exact_hessian_when_definite = o.exact_hessian_when_definite;
  no.free_rotation = o.free_rotation;
  no.escalate_after_iterations = o.escalate_after_iterations;
  no.exact_samples = o.exact_samples;
  no.carry_all_samples = o.carry_all_samples;
  return no;
}

std::vector<double> frame_times(const std::vector<double>& key_times, int per_interval) {
  if (per_interval < 1) throw InputError("frames per interval must be at least 1 (got " + std::to_string(per_interval) + ")");
  if (key_times.size() < 2) throw InputError("frame times need at least two keyframes");
  std::vector<double> out;
  for (size_t k = 0; k + 1 < key_times.size(); ++k)
    for (int i = 0; i < per_interval; ++i)  // i = 0 is the keyframe time itself, exactly
      out.push_back(i == 0 ? key_times[k] : key_times[k] + (key_times[k + 1] - key_times[k]) * i / per_interval);
  out.push_back(key_times.back());
  return out;
}

std::vector<double> sequence_times(const std::vector<double>& key_times, int frames, int per_interval) {
  if (per_interval > 0) return frame_times(key_times, per_interval);
  if (frames < 2) throw InputError("a sequence needs at least 2 frames (got " + std::to_string(frames) + ")");
  if (key_times.empty()) throw InputError("frame times need keyframes");
  const double t0 = key_times.front(), t1 = key_times.back();
  std::vector<double> times;
  for (int i = 0; i < frames; ++i) times.push_back(i == frames - 1 ? t1 : t0 + (t1 - t0) * i / (frames - 1));
  return times;
}

}  // namespace hsi
