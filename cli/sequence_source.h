// Where hsi bake and hsi export get their frames: an interpolation run now (with a
// progress line), or the frames of an earlier hsi interpolate (cmd_bake.cpp).
#pragma once

#include <memory>
#include <string>

#include "hsi/scene_sequence.h"

namespace hsi::cli {

// FROM is a .hsif file or a folder holding frames.hsif; its cage must be the scene's.
FrameFile frames_from(const std::string& from, Scene& scene);
// core / setup: as interpolate_scene takes them (null: the CPU core, the scene's setup).
SceneSequence interpolate_with_progress(Scene& scene, const SceneSequenceOptions& options, const char* tag,
                                        std::unique_ptr<NewtonCore> core = nullptr, std::shared_ptr<const ShapeSetup> setup = nullptr);

}  // namespace hsi::cli
