// Keyframes (math.md §7, CW17 point-to-point deformation): a harmonic map made by
// dragging handles, minimising the symmetric Dirichlet distortion on ∂Ω plus a
// strong positional penalty with the certified Newton solver, so every keyframe is
// locally injective by construction. Keyframes can also be imported as
// coefficients; they are certified on import.
#pragma once

#include <functional>
#include <span>

#include "hsi/newton.h"
#include "hsi/shape_setup.h"

namespace hsi {

struct KeyframeOptions {
  double lambda = 1e5;      // positional weight, relative to the shape's size squared
  int stages = 8;           // targets are approached in this many steps, as if dragged
  int stage_iterations = 30;
  NewtonOptions newton = [] {
    NewtonOptions o;
    o.max_iterations = 300;
    o.tolerance = 1e-10;
    // A drag that would fold stops short of the fold by a margin, not at round-off
    // (NewtonOptions::min_margin): the keyframe's coefficients in the interpolation's
    // reduced space are then certified too, and so are the frames next to it.
    o.min_margin = 1e-6;
    return o;
  }();
  double reach_tolerance = 1e-3;  // a target counts as reached within this fraction of the size
  // The Newton core the drag's solves run on (e.g. runtime::make_newton_core's CUDA
  // core); empty: the CPU core. The loop's decisions are the same on either; the
  // maps agree to round-off.
  std::function<std::unique_ptr<NewtonCore>(const ShapeSetup&)> make_core;
};

struct KeyframeResult {
  HarmonicMap map;
  bool certified = false;
  bool reached = false;
  double max_target_error = 0;  // in shape units
  int worst_handle = -1;
  int iterations = 0;
  double ms = 0;
  double energy = 0;            // mean symmetric Dirichlet energy on ∂Ω (2 = isometric)
  CertificateResult certificate;
  std::vector<NewtonIteration> log;  // every Newton iteration over all stages
  std::string message;
};

// Poses the shape so that handles land on targets, from a certified start map
// (e.g. the identity or the previous keyframe). Never returns a folding map:
// if the targets cannot be reached without folding, the result is the closest
// certified map and the message says so.
KeyframeResult author_keyframe(const ShapeSetup& setup, std::span<const cd> handles, std::span<const cd> targets,
                               const HarmonicMap& start, const KeyframeOptions& options = {},
                               const std::function<void(int stage, int stages)>& progress = {});

// Certifies a map given as coefficients; throws InputError naming the problem if it
// has the wrong size, breaks ψ_log = conj φ_log, or is not certified locally injective.
HarmonicMap import_keyframe(const ShapeSetup& setup, const HarmonicMap& map, const std::string& what = "keyframe");

// Positions of points under a map.
std::vector<cd> map_points(const Cage& cage, const HarmonicMap& map, std::span<const cd> points);

}  // namespace hsi

namespace hsi {

// How a user adds handles and keyframes, for messages that stop at "needs at least two
// keyframes" (hsi interpolate, hsi info, interpolate_scene).
inline constexpr const char* kHowToAddKeyframes =
    "add handles and keyframes in hsi-viewer SCENE (click the shape to add a handle, K adds a keyframe, drag a handle "
    "to pose it, Ctrl+S saves), or with hsi keyframes SCENE --handle X,Y ... --keyframe 0 --keyframe '1: X,Y ...' -o OUT.json";

// Why a point that must lie on the shape (a handle) does not: "" when p lies in the
// shape's closure (up to 1e-9 of its size), else where it lies, how far from the shape
// and the shape's bounding box, e.g. "lies outside the shape, in hole 1, 0.31 from the
// shape (1.2% of its size); a handle must be on the shape (its bounding box is (0, 0) to
// (4, 1))". The one check of a handle's place: scene files (scene_io), add_handle,
// author_keyframe.
std::string off_shape_reason(const Shape& shape, cd p);

// Adds a handle at rest point `rest`, which must lie on the shape (its closure). Every
// keyframe keeps its pose: one with coefficients gets the handle's image as its target;
// a keyframe given by targets only cannot (its map is not known yet) and is refused,
// naming it. Throws InputError.
void add_handle(Scene& scene, cd rest);

// Adds a keyframe at `time` with one target per handle (`targets` empty: the rest pose,
// targets = handles), in time order; a time that is already a keyframe's is refused.
// Returns its index. Throws InputError.
int add_keyframe(Scene& scene, double time, std::vector<cd> targets);

}  // namespace hsi

namespace hsi {

struct SceneKeyframe {
  int index = 0;
  bool solved = false;     // authored from targets now (else certified coefficients)
  bool from_rest = false;  // … starting from the rest pose (Keyframe::start), not the previous keyframe
  KeyframeResult result;   // when solved
  // Whether the keyframe's boundary image crosses itself (overlap.h): certified means
  // locally injective only, so an authored pose can still lay one part over another.
  OverlapResult overlap;
};

// Makes every keyframe of a scene a certified map, in time order: keyframes with
// coefficients are certified (re-solved from targets when `force`), the others are
// authored from their targets starting at the previous keyframe (the first, and any
// whose Keyframe::start is Rest, from the identity). Coefficients are written into
// scene.keyframes. Throws InputError for a keyframe that cannot be made certified. The
// scene's cage must be setup's cage.
std::vector<SceneKeyframe> solve_scene_keyframes(Scene& scene, const ShapeSetup& setup, const KeyframeOptions& options = {},
                                                 bool force = false,
                                                 const std::function<void(const SceneKeyframe&)>& on_keyframe = {});

}  // namespace hsi
