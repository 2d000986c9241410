// A scene interpolated end to end (keyframes made certified, then the warm-started
// sequence) and its report as JSON and CSV: the flow that hsi bake, hsi export and
// the C API share.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hsi/frames_io.h"
#include "hsi/interpolation.h"

namespace hsi {

struct SceneSequenceOptions {
  int frames = 500;            // uniform over the keyframes' time range (≥ 2)
  int frames_per_interval = 0; // > 0: instead of `frames`, this many steps between neighbouring
                               // keyframes, every keyframe time a frame (sequence_times)
  int samples = 0;             // |G|; 0: the scene's
  double hessian_ratio = 0;    // r; 0: the scene's
  InterpolationOptions interpolation;
};

struct SceneSequence {
  std::shared_ptr<const ShapeSetup> setup;
  std::vector<FrameResult> frames;
  double total_s = 0;  // wall-clock time of the sequence
  InterpolationOptions options;  // what the frames were solved with (recorded in the report)

  int uncertified() const;
  FrameFile frame_file() const;  // cage + posed maps, as hsi interpolate writes them
};

// The keyframes' timings as InterpolationOptions::timing takes them: one per keyframe,
// or empty when every one is Linear (the paper's blend).
std::vector<KeyTiming> scene_timings(const Scene& scene);

// Gives the scene a cage if it has none, then the setup for its sample settings
// (samples, ratio override the scene's when positive).
std::shared_ptr<const ShapeSetup> scene_setup(Scene& scene, int samples = 0, double hessian_ratio = 0);

// Needs two or more keyframes (InputError otherwise); keyframes given by targets are
// solved and their coefficients written into scene.keyframes. The scene's keyframe
// timings apply unless options.interpolation.timing gives some. `core` = nullptr: the
// CPU Newton core. Frames that cannot be certified are reported in the result, not thrown.
SceneSequence interpolate_scene(Scene& scene, const SceneSequenceOptions& options = {},
                                const std::function<void(const FrameResult&, int, int)>& progress = {},
                                std::unique_ptr<NewtonCore> core = nullptr,
                                std::shared_ptr<const ShapeSetup> setup = nullptr);

struct SequenceSummary {
  int frames = 0, certified = 0, uncertified = 0, within_bounds = 0;
  double mean_iterations = 0, mean_ms = 0, max_ms = 0, total_s = 0, max_bound_excess = 0;
  int overlapping = 0;  // frames whose boundary image crosses itself (FrameResult::overlap)
  // Frames whose Newton solve stopped at its iteration limit (or otherwise) without
  // meeting the tolerance, certified or not (FrameResult::converged false).
  int not_converged = 0;
  // The frames counted by why their solve stopped, indexed by NewtonStop (FrameResult::stop;
  // [Converged] counts the converged frames, keyframes included).
  std::array<int, kNewtonStopCount> stops{};
  // within_bounds / max_bound_excess compare the *sampled* distortion with the
  // keyframes' sampled values; these compare certified bounds with certified bounds
  // (certified frames only: an uncertified frame has no certified bound).
  int within_certified_bounds = 0;
  double max_certified_bound_excess = 0;
};
SequenceSummary summarize(const std::vector<FrameResult>& frames, double total_s);
// The summary as its reports name it (report_json's "summary"; hsi compare's rows of
// Tables 1-2), one field set for every report: counts are `integer` (written without a
// fraction), times and excesses not.
struct SummaryField {
  std::string name;
  double value = 0;
  bool integer = false;
};
std::vector<SummaryField> summary_fields(const SequenceSummary& s);

// The per-frame report (the fields of hsi interpolate's report.json: time, keyframe,
// certified, iterations, energy, ms, distortion and its bound, certificate, overlap), the
// solver options, plus a summary. `scene_path` is only recorded.
std::string report_json(const Scene& scene, const SceneSequence& sequence, const std::string& scene_path = "");
// One line per frame, a header line first; RFC 4180, '.' decimals.
std::string report_csv(const SceneSequence& sequence);

}  // namespace hsi
