// Export of an interpolated sequence as an animated glTF 2.0 binary (.glb): the
// shape's triangulation (hsi/triangulate.h) with its texture embedded, posed as the
// first frame, and one morph target per further sampled frame (POSITION deltas),
// played by a weights animation whose keys are one-hot: LINEAR interpolation
// blends neighbouring frames, so at most two targets are active at a time (what
// three.js, Babylon.js, Blender, Unity and Godot all play back). The animation's
// extras.frames lists, per key, the frame index, t and its flags (certified,
// keyframe, converged), and "stop": why its Newton solve stopped, by name
// ("converged", "iteration limit", ...: to_string(NewtonStop); "not recorded" where the
// frames do not say).
#pragma once

#include <string>

#include "hsi/frames_io.h"
#include "hsi/scene_io.h"

namespace hsi {

struct GltfOptions {
  int mesh_vertices = 2000;         // triangulation resolution (about this many vertices)
  int max_frames = 61;              // frames sampled into the animation (first and last always)
  double seconds_per_time_unit = 1; // animation time = (t − t_begin) × this
  bool step = false;                // STEP instead of LINEAR keys
  bool allow_uncertified = false;   // refuse (InputError) a sequence with uncertified frames
};

struct GltfStats {
  int vertices = 0, triangles = 0, targets = 0;
  bool textured = false;
  size_t bytes = 0;
};

// The .glb bytes. Throws InputError if the frames do not fit the scene's shape and
// cage, a frame is not certified (unless allowed), or the texture is not a PNG.
std::string encode_glb(const Scene& scene, const FrameFile& frames, const GltfOptions& options = {}, GltfStats* stats = nullptr);
void write_glb(const std::filesystem::path& path, const Scene& scene, const FrameFile& frames, const GltfOptions& options = {},
               GltfStats* stats = nullptr);  // atomic

}  // namespace hsi
