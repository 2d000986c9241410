// Shared by the benchmarks: a bundled scene made ready for interpolation (its cage,
// the per-shape setup at the chosen |G| and r, and its keyframes as certified maps).
#pragma once

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "hsi/interpolation.h"
#include "hsi/keyframes.h"

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

// Where the frames' time went (FrameResult::parts): the first solved frame apart (what
// set-up left to it) and the mean of each part over the warm frames (every solved frame
// but the first; keyframes and held frames are not solved).
struct FrameParts {
  int warm = 0;
  double first_ms = 0, mean_ms = 0;
  FrameResult::Parts first, mean;
  double rest() const {  // mean ms outside the parts
    return mean_ms - (mean.targets + mean.solve + mean.pose + mean.image + mean.crossings + mean.distortion);
  }
};

inline FrameParts frame_parts(const std::vector<FrameResult>& frames) {
  FrameParts p;
  bool first = true;
  for (const FrameResult& f : frames) {
    if (f.keyframe || f.held) continue;
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
    p.mean.distortion += f.parts.distortion;
  }
  const double w = std::max(p.warm, 1);
  p.mean_ms /= w;
  for (double* d : {&p.mean.targets, &p.mean.solve, &p.mean.pose, &p.mean.image, &p.mean.crossings, &p.mean.distortion}) *d /= w;
  return p;
}

}  // namespace hsi::bench
