// Harmonic shape interpolation (paper §4–5, Algorithm 1): blend the keyframes'
// pull-back metrics at the boundary samples, project onto the harmonic map space by
// certified Newton on the isometric energy, warm-started frame to frame; place each
// frame by a rigid pose interpolated across the keyframes (math.md §3).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hsi/mesh_evaluator.h"
#include "hsi/newton.h"
#include "hsi/shape_setup.h"
#include "hsi/timing.h"

namespace hsi {

// Where a sequence's frames start (InterpolationOptions::predict_start).
enum class PredictStart : std::uint8_t {
  Off,     // the previous frame's solution, with a chord step from its last exact system
  Always,  // the secant's prediction wherever two frames of the interval are known
  // The secant's where the frame before took more than one iteration (its chord step did
  // not end it: the path turns faster than one step from the previous frame follows);
  // else the previous frame's, whose chord step costs no system of its own.
  Auto
};
const char* to_string(PredictStart p);
PredictStart parse_predict_start(const std::string& name);  // one of predict_start_names()
// "off", "always", "auto": every PredictStart by its to_string name, in declaration order
// (for an option's check, e.g. CLI::IsMember(predict_start_names())).
const std::vector<std::string>& predict_start_names();
// Whether a sequence's next frame starts from the secant's prediction under `mode`, the
// solved frame before it (since the last keyframe) having taken `last_iterations` (0: none).
inline bool predicts_start(PredictStart mode, int last_iterations) {
  return mode == PredictStart::Always || (mode == PredictStart::Auto && last_iterations > 1);
}

struct InterpolationOptions {
  double tolerance = 5e-8;    // relative: NewtonOptions::tolerance (the paper's absolute 1e-7 at E = 2)
  // NewtonOptions::projected_decrement_stop: a frame whose projected system's decrement
  // is below 1 % of the tolerance is converged. Measured (issue #20, 2026-11-29, the whole
  // stress corpus on one H200, CUDA core): Delete / FullProj / PartProj 1.37 / 1.37 / 1.39
  // → 1.36 / 1.35 / 1.36 iterations per frame at 100 frames per interval, 1.72 / 1.69 /
  // 1.71 → 1.71 / 1.66 / 1.68 at 60, none at the cap, every frame certified; traced on 10
  // sequences (CPU, |G| 2,000), the frames it ended were within 1 % of the tolerance of
  // the energies the solves reached without it. Keyframe authoring keeps 0.
  double projected_decrement_stop = 0.01;
  // NewtonOptions::checked_decrement_stop: a projected decrement below the tolerance ends
  // a frame once the frame's previous full step showed how far its model understates the
  // energy (issue #20: near-rigid frames whose exact system over G never factors took a
  // second projected step worth ~3e-9 at a tolerance of 1e-7). Keyframe authoring: off.
  bool checked_decrement_stop = true;
  // NewtonOptions::chord_decrement_stop: a frame whose full chord step left the kept
  // system's decrement (scaled by that step's model error) below this share of the
  // tolerance ends there, without an exact system of its own (issue #23: most of a warm
  // frame's work). 0: never, the default: on the CPU core it saves ~40 % of the time on
  // some sequences at 500 frames per interval, but on the CUDA core a bar_holes frame is
  // slower with it and over the stress corpus it costs steps (NewtonOptions). Keyframe
  // authoring: 0.
  double chord_decrement_stop = 0;
  int max_iterations = 100;
  // FullProj, not the paper's PartProj: over the stress corpus (bench_stress, issue #20)
  // FullProj took the fewest Newton iterations per frame at 60, 100 and 500 frames per
  // keyframe interval and from cold (the paper's Table 1 setting), no frame at the
  // iteration cap where PartProj had three, and no more time per frame (its per-sample
  // 4×4 eigen-decomposition costs less than the iterations it saves). PartProj and Delete
  // remain selectable.
  HessianProjection projection = HessianProjection::FullProj;
  // NewtonOptions::exact_hessian_when_definite and free_rotation: both off is the
  // paper's plain projected Newton (which crawls on some inputs, issue #20).
  bool exact_hessian_when_definite = true;
  bool free_rotation = true;
  // NewtonOptions::escalate_after_iterations: a frame still solving after this many
  // iterations switches to FullProj (0: never).
  int escalate_after_iterations = 20;
  // NewtonOptions::exact_samples for the frames' solves: by default the core's choice
  // (NewtonCore::preferred_exact_samples: over H on the CPU, over all of G on the GPU).
  // Measured (issue #20, 2026-11-29; bench_stress on one H200, the CUDA core, 2 sequences
  // per shape, 100 frames per interval, 5,148 frames per projection): FullProj 1.71 /
  // 1.64 / 1.44 iterations per frame with Subset / SubsetThenAll / All, 7.4 / 6.4 / 5.5 ms
  // per frame with 16 solves sharing the GPU; on the bundled scenes, 1.0–1.1 iterations
  // per frame with any of them, bench_cuda's warm frame is 0.81 / 0.82 / 0.84 ms (annulus)
  // on the GPU and 5.0 / 5.5 / 8.9 ms on the CPU (16 threads). SubsetThenAll is no
  // default: whether H's exact system factors is decided by round-off near the solution,
  // and the paths then part (two_holes, 500 frames, CPU core: 1 or 2 OpenMP threads gave
  // 1.24 and 1.65 iterations per frame, equal counts in 285 frames; the CPU and CUDA
  // cores 271 of 500). With Subset or All the two thread counts agree in every frame.
  ExactSamples exact_samples = ExactSamples::Auto;
  // How each keyframe interval is travelled (timing.h): one per keyframe (the interval
  // leaving it; the last is unused), or one for all; empty: Linear everywhere (the
  // paper's linear blend of the metrics and the pose).
  std::vector<KeyTiming> timing;
  // Interpolator::sequence runs each solved frame's crossing search (the overlap check's
  // exact search, overlap.h) on a thread of its own while it solves the next frame, and
  // waits for it only once that frame's image is made (issue #23: on the CUDA core the
  // search took as long as the solve, in series). Every frame and every field is the
  // same as in series (false: as frame() does); FrameResult::parts.crossings_wait says
  // what the search still cost the caller.
  bool pipelined_overlap = true;
  // Interpolator::sequence solves each frame with chord steps from the previous frame's
  // last exact Newton system (NewtonOptions::kept_system): a warm-started frame then
  // mostly builds and factors no system at all (issue #23). false: every frame's systems
  // built at its own points, as frame() does.
  bool chord_steps = true;
  // With chord_steps: at each keyframe the sequence's chord slot is seeded with the
  // exact system at the keyframe itself (newton_seed_kept_system), so that the first
  // frame after it starts with a chord step too. false (the default): the slot starts
  // empty there, and the interval's first frame builds its own systems. Measured (issue
  // #20, one H100, the stress corpus at 100 frames per interval on the CUDA core, 46,629
  // frames per projection, every one certified and converged either way): iterations
  // Delete 62,387 → 62,273, FullProj 60,426 → 60,761, PartProj 60,722 → 60,807. The
  // frames after a keyframe then start on the same exact factor whatever the projection,
  // and the projections' totals move together: PartProj − Delete on chromium_superbomb
  // +6 → −1, on chromium_enemy01 −21 → +6 (its squash_stretch: PartProj's unseeded
  // start had led to one iteration a frame, 251 against 288; seeded all three take 288).
  // Not the default: it costs the default projection (FullProj) iterations.
  bool seed_chord_at_keyframes = false;
  // Interpolator::sequence's starts (PredictStart): the previous frame's solution, or the
  // secant through the last two solved frames of the keyframe interval extrapolated to
  // the frame's time (SecantPredictor, a first-order continuation predictor: off from
  // the frame's solution by O(h²) in the frame spacing h where the previous frame is off
  // by O(h)). A solve from the secant's start takes no chord step (NewtonOptions::
  // chord_from_start) and certifies that start itself; where it ends not certified or not
  // converged, the frame is solved again from the previous frame (the iterations of
  // both counted; FrameResult::predicted says which start the frame came from).
  // Off by default: measured (issue #20/#23, 2026-12-04, one NVIDIA H200, CUDA core) Auto
  // cut the stress corpus' iterations per frame at 100 frames per interval from 1.34 /
  // 1.30 to 1.25 / 1.20 (Delete / PartProj; FullProj 1.19), every frame certified and
  // converged, none at the cap, but bench_batch lost ~5 % of its frames per second
  // (16 workers 3,166 against 3,358, one worker 698 against 737; 1.40 against 1.58
  // iterations per frame): a predicted frame builds and factors a system at its start
  // where a chord step from the previous frame builds none.
  PredictStart predict_start = PredictStart::Off;
  // NewtonOptions::carry_all_samples, carried in the chord steps' slot (so off with
  // chord_steps off: frames then independent of each other's solves): once a frame's
  // solve moved its Hessians to all of G, the later frames of the sequence start there.
  // Auto: on the cores whose exact systems sum over G (the CUDA core).
  AllSamplesCarry carry_all_samples = AllSamplesCarry::Auto;
};

// Pose of a map: the centroid of the boundary's image (by arc length) and the
// Procrustes angle of the image against the rest boundary.
struct Pose {
  cd centroid{0, 0};
  double angle = 0;
};

// Distortion over the boundary (so over Ω, by Theorem 2): either sampled (maxima and
// minima over the certificate's breakpoints: what the map does there, not a bound) or
// certified (the certificate's bounds, proved between the breakpoints too).
struct Distortion {
  double sigma1_max = 0;     // largest singular value
  double sigma2_min = 0;     // smallest singular value
  double conformal_max = 0;  // σ1/σ2 (the paper's κ)
  double isometric_max = 0;  // symmetric Dirichlet ½(σ1² + σ1⁻² + σ2² + σ2⁻²)… per point, max
};

struct FrameResult {
  double t = 0;
  HarmonicMap map;           // the frame, posed
  Eigen::VectorXd x;         // its reduced coefficients (ModuloRigid gauge), the next warm start
  bool keyframe = false;     // t is a keyframe time: the keyframe itself
  // Solved from the secant's prediction (InterpolationOptions::predict_start), not from
  // the previous frame's solution (false too where a solve from the prediction failed
  // and the frame was solved again from the previous one).
  bool predicted = false;
  bool held = false;         // t lies in a Hold interval: the held keyframe itself (timing.h)
  bool certified = false;
  bool converged = false;
  NewtonStop stop = NewtonStop::Converged;  // why the solve stopped (a keyframe or held frame: Converged)
  CertificateResult certificate;
  int iterations = 0;
  double energy = 0;         // mean isometric energy against the blended metric (2 = exact)
  // The caller's wall clock of the frame (Interpolator::frame, or its turn in
  // Interpolator::sequence): its parts, the crossing search counted by what the caller
  // waited for it (parts.crossings_wait: all of it in series, what the next solve did not
  // hide when pipelined), so that a pipelined sequence's wall clock is about the sum of
  // its frames' ms.
  double ms = 0;
  // Where `ms` went, wall clock in ms, each part timed apart (their sum, with
  // crossings_wait in place of crossings, ≤ ms; the rest is bookkeeping: copies,
  // messages). A keyframe or held frame is the keyframe itself, its certificate and
  // overlap made at set-up: every part 0.
  struct Parts {
    double targets = 0;     // the blended metric at G (blended_metric) and its upload (NewtonCore::set_targets)
    double solve = 0;       // newton_solve: the iterations, certificates included (`timing` splits them)
    double pose = 0;        // expand(x), pose_of, interpolated_pose and transform_image
    double image = 0;       // f at the overlap check's breakpoints (the boundary's image)
    double crossings = 0;   // the crossing search over the image polylines (OverlapChecker::check_points), its own time wherever it ran
    // What the caller waited for that search: in series (frame(), or pipelined_overlap
    // off) the same as crossings; in a pipelined sequence the search runs on a thread of
    // its own while the next frame is solved, and this is only the time the sequence then
    // waited for it (~0 when the solve hid it; counted in this frame's ms).
    double crossings_wait = 0;
    double distortion = 0;  // sampled and certified distortion from the certificate
  } parts;
  Distortion distortion;     // sampled at the certificate's breakpoints (observed values, not bounds)
  // Certified bounds over ∂Ω (so over Ω): σ1 and κ upper bounds, σ2 a *lower* bound,
  // the isometric energy's upper bound derived from those two (certified_distortion()).
  // Meaningful only when `certified`; NaN otherwise.
  Distortion distortion_certified;
  Distortion bound;            // the two neighbouring keyframes' envelope of their sampled distortion
  Distortion certified_bound;  // the same keyframes' envelope of their certified bounds
  double bound_excess = 0;     // how far `distortion` leaves `bound` (relative; 0 = bounded); sampled
  // How far `distortion_certified` leaves `certified_bound` (relative; 0 = bounded);
  // NaN when the frame is not certified.
  double certified_bound_excess = 0;
  std::string message;
  NewtonResult::Timing timing;
  // Whether the image of ∂Ω crosses itself (the frame overlaps itself: locally but not
  // globally injective), sampled at the certificate's breakpoints (overlap.h). Checked
  // for keyframes and solved frames alike; it does not change `certified`.
  OverlapResult overlap;
};

// The certificate's bounds as a Distortion (valid when c.certified): σ1 ≤ sigma1_max,
// σ2 ≥ sigma2_min, σ1/σ2 ≤ conformal_max, and for the isometric energy
// ½(σ1² + σ1⁻² + σ2² + σ2⁻²), which is not monotone in σ: both σ lie in
// [sigma2_min, sigma1_max] and s² + s⁻² is convex, so each half is at most its value
// at an end of that interval: E ≤ max(g(sigma2_min), g(sigma1_max)), g(s) = s² + s⁻².
// NaN in every field when not certified.
Distortion certified_distortion(const CertificateResult& c);

// The Newton options a frame is solved with (Interpolator; the start certificate aside):
// one mapping, so that a caller replaying a frame's solve (a trace, a test) cannot miss
// an option.
NewtonOptions frame_newton_options(const InterpolationOptions& o);

// Frame times with `per_interval` equal steps between each pair of neighbouring
// keyframes, so that every keyframe time is a frame time exactly (and its frame is the
// keyframe itself): (keys − 1)·per_interval + 1 times. Throws InputError for
// per_interval < 1 or fewer than two keyframe times.
std::vector<double> frame_times(const std::vector<double>& key_times, int per_interval);
// The frame times a front-end asks for, one rule for hsi interpolate, bake, export and
// interpolate_scene: per_interval > 0: frame_times(key_times, per_interval); else
// `frames` (≥ 2) uniform over [first, last] key time, both ends exact. Throws InputError.
std::vector<double> sequence_times(const std::vector<double>& key_times, int frames, int per_interval = 0);

// Starts for a sequence's frames (InterpolationOptions::predict_start): the secant
// through the last two frames added, extrapolated to the next frame's time t,
// x_b + (t − t_b)/(t_b − t_a)·(x_b − x_a), where both lie in t's keyframe interval
// [lo, hi] (the path x(t) need not be smooth across a keyframe).
class SecantPredictor {
 public:
  // A frame solved (certified and converged), or a keyframe, at t after the others.
  void add(double t, const Eigen::VectorXd& x);
  // A frame that was not: the next predictions need two frames after it.
  void clear() { count_ = 0; }
  // Empty where fewer than two frames of [lo, hi] are known, or t is not after them.
  Eigen::VectorXd predict(double t, double lo, double hi) const;

 private:
  std::array<double, 2> t_{};  // [0] the older
  std::array<Eigen::VectorXd, 2> x_;
  int count_ = 0;
};

// Whether the frame at t is a keyframe itself (t one of key_times, or inside a Hold
// interval of `timing`): Interpolator::frame solves nothing there and ignores its warm
// start, so a sequence's frames from such a t on do not depend on the frames before it
// (batch.h solves the runs between them apart).
inline bool keyframe_itself(const std::vector<double>& key_times, const std::vector<KeyTiming>& timing, double t) {
  return std::find(key_times.begin(), key_times.end(), t) != key_times.end() ||
         interval_timing(key_times, timing, t) == KeyTiming::Hold;
}

class Interpolator {
 public:
  // keyframes: certified maps at increasing times (at least two). core: the Newton core
  // (null: the CPU one). boundary: f at setup.overlap.breakpoints().points, the image
  // every frame's overlap check tests (null: the setup's CPU evaluator; runtime's
  // make_newton_core gives one on the core's backend); InputError if made for another
  // number of points. Set-up also certifies each keyframe (on the core's backend where it
  // can: NewtonCore::certify_map, else the setup's certifier), checks its overlap and
  // certifies its reduced coefficients as a solve's start (so no frame certifies from
  // scratch: the first solved frame costs what a warm one does).
  Interpolator(const ShapeSetup& setup, std::vector<double> times, std::vector<HarmonicMap> keyframes,
               const InterpolationOptions& options = {}, std::unique_ptr<NewtonCore> core = nullptr,
               std::unique_ptr<MeshEvaluator> boundary = nullptr);
  ~Interpolator();

  double t_begin() const { return times_.front(); }
  double t_end() const { return times_.back(); }
  bool keyframe_itself(double t) const { return hsi::keyframe_itself(times_, options_.timing, t); }

  // One frame from a warm start (reduced x; empty = the nearest earlier keyframe).
  // warm_certificate: the certificate of warm_start's map when already known (the
  // previous frame's), so the solve does not certify its start again; a keyframe's own
  // coefficients (no warm start, or the x of a keyframe or held frame) start from the
  // certificate made at set-up.
  FrameResult frame(double t, const Eigen::VectorXd& warm_start = {}, const CertificateResult* warm_certificate = nullptr);
  // F frames uniform over [t_begin, t_end], each warm-started from the previous one.
  // progress(frame, i, F) is called once per frame, in order, with the complete frame;
  // with options().pipelined_overlap, a solved frame's call comes once its crossing
  // search is done, during the next frame. The frames are frame()'s, in series or not.
  std::vector<FrameResult> sequence(int frames, const std::function<void(const FrameResult&, int, int)>& progress = {});
  // Frames at the given times (increasing, within [t_begin, t_end]; e.g. frame_times()),
  // each warm-started from the previous one; progress as above.
  std::vector<FrameResult> sequence(const std::vector<double>& times,
                                    const std::function<void(const FrameResult&, int, int)>& progress = {});

  // The blended metric at every sample of G (paper §4.1; timing.h for other timings).
  std::vector<Metric> blended_metric(double t) const;
  Pose pose_of(const HarmonicMap& map) const;
  Pose interpolated_pose(double t) const;
  // Keyframe k's distortion: sampled at the certificate's breakpoints / certified bounds.
  const Distortion& keyframe_distortion(int k) const { return key_distortion_[static_cast<size_t>(k)]; }
  const Distortion& keyframe_certified_distortion(int k) const { return key_certified_[static_cast<size_t>(k)]; }
  NewtonCore& core() { return *core_; }
  const InterpolationOptions& options() const { return options_; }

 private:
  int segment(double t) const;
  Distortion measure(const CertificateResult& c) const;
  // The overlap check of a keyframe's map: f at the breakpoints, then the crossing search.
  OverlapResult overlap_of(const HarmonicMap& map);
  // f at the overlap check's breakpoints by boundary_ (or the setup's), into out.f.
  void boundary_image(const HarmonicMap& map, MapValues& out);
  // The core's targets: the blended metric at t.
  void set_core_targets(double t);
  // Seeds a sequence's chord slot with keyframe j's own exact system
  // (InterpolationOptions::seed_chord_at_keyframes).
  void seed_chord(size_t j, KeptSystem& slot);
  // frame() but for the crossing search: the image it is to search is left in `image`
  // and `search` set (a keyframe or held frame has its overlap from set-up: not set);
  // ms does not count it.
  // kept: the sequence's chord slot (InterpolationOptions::chord_steps), or null.
  // predicted: a start to solve from before warm_start (InterpolationOptions::predict_start), or null.
  FrameResult frame_before_crossings(double t, const Eigen::VectorXd& warm_start, const CertificateResult* warm_certificate,
                                     MapValues& image, bool& search, KeptSystem* kept = nullptr,
                                     const Eigen::VectorXd* predicted = nullptr);
  FrameResult frame_searched(double t, const Eigen::VectorXd& warm_start, const CertificateResult* warm_certificate,
                             KeptSystem* kept, const Eigen::VectorXd* predicted = nullptr);

  const ShapeSetup& setup_;
  std::vector<double> times_;
  std::vector<HarmonicMap> keys_;
  std::vector<Eigen::VectorXd> key_x_;
  std::vector<std::vector<Metric>> key_metrics_;
  std::vector<std::vector<Metric>> key_log_metrics_;  // metric_log of key_metrics_, when some interval is Smooth
  std::uint64_t target_token_ = 0;  // the core's copy of those sets (NewtonCore::set_target_keys)
  std::vector<Pose> key_poses_;  // angles unwrapped across keyframes
  std::vector<Distortion> key_distortion_;
  std::vector<Distortion> key_certified_;
  std::vector<CertificateResult> key_certificate_;  // of keys_[k] (a keyframe frame's certificate)
  std::vector<OverlapResult> key_overlap_;          // of keys_[k] (a keyframe frame's overlap)
  // Of expand(key_x_[k]) by the core's own stepper: what a solve started there would
  // certify first (newton_run), made once here.
  std::vector<CertificateResult> key_start_certificate_;
  InterpolationOptions options_;
  std::unique_ptr<NewtonCore> core_;
  std::unique_ptr<MeshEvaluator> boundary_;  // null: setup_.overlap's own
  // Its output, reused frame to frame: two, so that a pipelined sequence makes frame
  // i + 1's image while frame i's is searched.
  std::array<MapValues, 2> boundary_values_;
  // The crossing search's scratch: one search at a time uses it (frame(), set-up, or a
  // sequence's crossing thread while the sequence runs).
  OverlapChecker::Workspace crossing_workspace_;
  // Poses are linear in the coefficients: centroid = c_mean·φ + conj(c_mean·ψ) and the
  // Procrustes sum Σ f_i conj(w_i − w̄) = c_rot·φ + conj(c_rot_bar·ψ), with these rows
  // (sums over G of the basis rows C), so a pose costs O(m), not O(|G| m).
  Eigen::RowVectorXcd c_mean_, c_rot_, c_rot_bar_;
};

}  // namespace hsi
