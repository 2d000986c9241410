// Shared by the benchmarks: a bundled scene made ready for interpolation (its cage,
// the per-shape setup at the chosen |G| and r, and its keyframes as certified maps).
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "hsi/batch.h"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/overlap.h"

namespace hsi::bench {

struct Loaded {
  std::string name;
  Scene scene;
  std::unique_ptr<ShapeSetup> setup;
  std::vector<double> times;
  std::vector<HarmonicMap> maps;
};

inline Loaded load(const std::string& path, int samples, double ratio) {
  Loaded L;
  L.scene = load_scene(path);
  L.name = L.scene.name.empty() ? path : L.scene.name;
  if (!L.scene.cage) L.scene.cage = build_cage(L.scene.shape, L.scene.cage_options);
  L.setup = make_shape_setup(L.scene, samples, ratio);
  solve_scene_keyframes(L.scene, *L.setup);
  for (const Keyframe& k : L.scene.keyframes) {
    L.times.push_back(k.time);
    L.maps.push_back(*k.coefficients);
  }
  return L;
}

// Every scene of `folder` (*.json, in name order) with two or more keyframes, loaded;
// a file that fails to load is named on stderr (with `tag`) and left out.
inline std::vector<Loaded> load_folder(const std::string& folder, int samples, double ratio, const char* tag) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(folder))
    if (e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::vector<Loaded> scenes;
  for (const auto& f : files) {
    try {
      Loaded L = load(f.string(), samples, ratio);
      if (L.times.size() >= 2) scenes.push_back(std::move(L));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: %s left out: %s\n", tag, f.string().c_str(), e.what());
    }
  }
  return scenes;
}

// Sequence `repeat` of scene L as bench_batch makes its batch (named "<scene> #<repeat>",
// the scene's keyframe timings): even repeats F frames uniform over the keyframes'
// range (interior keyframe times mostly missed: one run), odd ones every keyframe time a
// frame and about F frames in all (a run per interval).
inline BatchSequence batch_sequence(const Loaded& L, int repeat, int F) {
  BatchSequence q;
  q.name = L.name + " #" + std::to_string(repeat);
  q.setup = L.setup.get();
  q.key_times = L.times;
  q.keyframes = L.maps;
  for (const Keyframe& k : L.scene.keyframes) q.options.timing.push_back(k.timing);
  const int intervals = static_cast<int>(L.times.size()) - 1;
  q.times = repeat % 2 == 0 ? sequence_times(L.times, F) : frame_times(L.times, std::max(1, (F - 1) / intervals));
  return q;
}

// Where the frames' time went (FrameResult::parts): the first solved frame apart (what
// set-up left to it) and the mean of each part over the warm frames (every solved frame
// but the first; keyframes and held frames are not solved). wall_ms: the sequence's
// wall clock over its solved frames, when the caller timed it (what a frame costs with
// the crossing search beside the next solve).
struct FrameParts {
  int warm = 0, solved = 0;
  double first_ms = 0, mean_ms = 0, wall_ms = 0;
  FrameResult::Parts first, mean;
  double rest() const {  // mean ms outside the parts (the crossing search counted by the caller's wait for it)
    return mean_ms - (mean.targets + mean.solve + mean.pose + mean.image + mean.crossings_wait + mean.distortion);
  }
};

// sequence_ms: the wall clock of the Interpolator::sequence call that made `frames` (0: not timed).
inline FrameParts frame_parts(const std::vector<FrameResult>& frames, double sequence_ms = 0) {
  FrameParts p;
  bool first = true;
  for (const FrameResult& f : frames) {
    if (f.keyframe || f.held) continue;
    ++p.solved;
    if (first) {
      first = false;
      p.first_ms = f.ms;
      p.first = f.parts;
      continue;
    }
    ++p.warm;
    p.mean_ms += f.ms;
    p.mean.targets += f.parts.targets;
    p.mean.solve += f.parts.solve;
    p.mean.pose += f.parts.pose;
    p.mean.image += f.parts.image;
    p.mean.crossings += f.parts.crossings;
    p.mean.crossings_wait += f.parts.crossings_wait;
    p.mean.distortion += f.parts.distortion;
  }
  const double w = std::max(p.warm, 1);
  p.mean_ms /= w;
  for (double* d : {&p.mean.targets, &p.mean.solve, &p.mean.pose, &p.mean.image, &p.mean.crossings, &p.mean.crossings_wait,
                    &p.mean.distortion})
    *d /= w;
  p.wall_ms = sequence_ms / std::max(p.solved, 1);
  return p;
}

// The overlap check's crossing search alone (issue #23), ms per call, on the images of
// `frames`' maps (at most `images` of them, spread over the sequence): the hierarchy kept
// by the checker (check_points with one workspace) and the reference search made per
// call (check_points_reference), each image searched `reps` times after one untimed
// call; `same`: every result equal.
struct CrossingSearchTimes {
  int images = 0, points = 0, overlapping = 0;
  double kept_ms = 0, reference_ms = 0;
  bool same = true;
};

inline CrossingSearchTimes time_crossing_search(const ShapeSetup& setup, const std::vector<FrameResult>& frames, int images,
                                                int reps) {
  using Clock = std::chrono::steady_clock;
  CrossingSearchTimes t;
  std::vector<VectorXcd> f;
  const size_t step = std::max<size_t>(1, frames.size() / static_cast<size_t>(std::max(images, 1)));
  for (size_t i = 0; i < frames.size() && static_cast<int>(f.size()) < images; i += step) f.push_back(setup.overlap.image(frames[i].map));
  if (f.empty()) return t;
  t.images = static_cast<int>(f.size());
  t.points = static_cast<int>(f.front().size());
  OverlapChecker::Workspace w;
  const auto span_of = [](const VectorXcd& v) { return std::span<const cd>(v.data(), static_cast<size_t>(v.size())); };
  for (const VectorXcd& v : f) {
    const OverlapResult a = setup.overlap.check_points(span_of(v), w), b = setup.overlap.check_points_reference(span_of(v));
    t.same = t.same && a.checked == b.checked && a.crossings == b.crossings && a.loop_a == b.loop_a && a.edge_a == b.edge_a &&
             a.loop_b == b.loop_b && a.edge_b == b.edge_b && a.point == b.point;
    t.overlapping += b.overlaps();
  }
  int sink = 0;
  auto t0 = Clock::now();
  for (int r = 0; r < reps; ++r)
    for (const VectorXcd& v : f) sink += setup.overlap.check_points(span_of(v), w).crossings;
  t.kept_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count() / (reps * t.images);
  t0 = Clock::now();
  for (int r = 0; r < reps; ++r)
    for (const VectorXcd& v : f) sink += setup.overlap.check_points_reference(span_of(v)).crossings;
  t.reference_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count() / (reps * t.images);
  if (sink < 0) t.same = false;  // keeps the calls observable
  return t;
}

}  // namespace hsi::bench
