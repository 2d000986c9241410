// Shared by the benchmarks: a bundled scene made ready for interpolation (its cage,
// the per-shape setup at the chosen |G| and r, and its keyframes as certified maps).
#pragma once

#include <memory>
#include <string>
#include <vector>

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

}  // namespace hsi::bench
