// Scene files: a shape, its cage, its texture, handles and keyframes, as JSON.
//
// Format (version 2; version 1 is read too: the same without "timing"; coordinates in
// any unit, y up):
// {
//   "hsi_scene": 2,                              // required format version (1 or 2)
//   "name": "annulus",                           // optional
//   "shape": { "outer": [[x, y], ...],           // required, ≥ 3 vertices, any orientation
//              "holes": [[[x, y], ...], ...] },  // optional
//   "texture": "annulus.png",                    // optional, relative to the scene file
//   "texture_rect": [x0, y0, x1, y1],            // optional: the source rectangle the texture
//                                                //   covers (default: the shape's bounding box)
//   "texture_filter": "nearest",                 // optional: "linear" (default, bilinear) or
//                                                //   "nearest" (crisp texels: pixel art); written
//                                                //   only when "nearest"
//   "cage": { "clearance": 0.06,                 // optional: automatic cage options, or
//             "max_vertices_per_loop": 32,
//             "loops": [[[x, y], ...], ...],     //   a user cage: one loop per shape loop, any
//             "hole_points": [[x, y], ...] },    //   orientation, and one point per hole (both or neither)
//   "samples": 10000,                            // optional |G|
//   "hessian_ratio": 0.2,                        // optional r
//   "handles": [[x, y], ...],                    // optional handle positions on the shape
//   "keyframes": [ { "time": 0.0,                // keyframes, in increasing time
//                    "targets": [[x, y], ...],   //   one per handle, and/or
//                    "layout": "full",           //   optional: "full" (default) or "reduced"
//                    "phi": [[re, im], ...],     //   coefficients over the user cage
//                    "psi": [[re, im], ...],
//                    "timing": "smooth",         //   optional (version 2): how the interval leaving this
//                                                //   keyframe is travelled: "linear" (default, the
//                                                //   paper's), "smooth" (C¹ through the keyframes),
//                                                //   "ease" (in and out), "hold" (timing.h)
//                    "start": "rest" } ]         //   optional (version 2): where authoring this keyframe
//                                                //   from its targets starts: "previous" (default: the
//                                                //   previous keyframe's map, so a part turned over
//                                                //   several keyframes keeps its turns) or "rest" (the
//                                                //   identity: the pose depends on the targets alone)
// }
// Any other key is refused, naming its JSON path and the nearest known key (a misspelt
// "sample" must not silently fall back to the default).
//
// Keyframe coefficients (the map f(w) = Σ C_j φ_j + conj(Σ C_j ψ_j), harmonic_map.h)
// need a user cage and index it as the file gives it, loop by loop in the order of
// "cage.loops", each loop's vertices in the order written; φ and ψ have the same
// length and layout, one [re, im] pair per column:
//   "full" (m + N columns): every vertex of cage loop 0 (the outer loop), then every
//     vertex of loop 1, ..., of loop N, then one log|w − ρ_i| column per hole i (its ψ
//     entry must equal conj of its φ entry).
//   "reduced" (m_0 + Σ_{k≥1} (m_k − 2) + N columns, the CW17 family's layout): every
//     vertex of the outer loop, then each hole loop without its first two vertices
//     (they carry only the null directions a + b w of that loop: map_space.h), then
//     one log column per hole. Read as full with those columns 0: the same map.
// A count that fits neither is refused naming both counts. Loops are stored in the
// normal orientation (outer counter-clockwise, holes clockwise): a loop given the
// other way round is reversed on loading, and its coefficients with it, so every
// coefficient stays with its vertex and the map is the same either way. Saved scenes
// hold the normalized cage and full coefficients.
//
// Every error names the file, the JSON path and, for syntax errors, line and column.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "hsi/cage.h"
#include "hsi/harmonic_map.h"
#include "hsi/texture_filter.h"
#include "hsi/timing.h"

namespace hsi {

// The version written: 1 when every keyframe's timing is linear (so files without
// timing keep their version), 2 otherwise. Both are read.
inline constexpr int kSceneVersion = 2;

struct Keyframe {
  double time = 0;
  std::vector<cd> targets;             // one per handle (may be empty if coefficients given)
  std::optional<HarmonicMap> coefficients;
  KeyTiming timing = KeyTiming::Linear;  // the interval leaving this keyframe (timing.h)
  // Where solve_scene_keyframes starts authoring it from its targets ("start"): the
  // previous keyframe's map (keyframe 0: the identity), or the rest pose, the identity.
  // From the previous keyframe a pose far from it can end folded over itself although
  // the same targets reached from rest give an undistorted map (a part turned 115° in
  // one keyframe and back in the next stays twisted over the body).
  enum class Start : std::uint8_t { Previous, Rest } start = Start::Previous;
};

struct Scene {
  std::string name;
  Shape shape;                          // normalized orientation after loading
  std::filesystem::path texture;        // absolute or relative to base_dir; empty if none
  std::optional<std::array<double, 4>> texture_rect;
  TextureFilter texture_filter = TextureFilter::Linear;  // how the texture is sampled where drawn
  CageOptions cage_options;
  std::optional<Cage> cage;             // user-given cage
  int samples = 10000;
  double hessian_ratio = 0.2;
  std::vector<cd> handles;
  std::vector<Keyframe> keyframes;
  std::filesystem::path base_dir;       // directory of the scene file
  std::string source;                   // where it was read from (the path), for messages; may be empty

  std::filesystem::path texture_path() const;  // resolved against base_dir
  // The world rectangle [x0, y0, x1, y1] the texture covers: texture_rect, or the rest
  // shape's bounding box when the scene gives none.
  std::array<double, 4> texture_rect_or_bounds() const;
};

// An InputError raised while working on `scene` after it was loaded (its cage, its
// keyframes), re-thrown with the scene's source in front so a message names the file:
// "walk.json: keyframe 1 is not locally injective: …". Used as
//   try { … } catch (const InputError& e) { rethrow_in_scene(scene, e); }
[[noreturn]] void rethrow_in_scene(const Scene& scene, const InputError& error);

// Parses and validates (shape, cage if given, keyframe sizes). Throws InputError.
Scene parse_scene(const std::string& json_text, const std::filesystem::path& base_dir,
                  const std::string& source_name = "scene");
Scene load_scene(const std::filesystem::path& path);
std::string scene_to_json(const Scene& scene);
// Writes atomically (temporary file, then rename), so a failed write leaves no partial file.
void save_scene(const Scene& scene, const std::filesystem::path& path);

// The cage a scene uses: its user cage (checked), or one built from its options.
Cage scene_cage(const Scene& scene);

}  // namespace hsi
