// Baking a sequence for playback in a game: the .hsib format (layout, and the tiny
// C runtime that plays it back, in hsi/baked_runtime.h). The cage and hole points
// are stored once, then per frame its reduced coefficients x (ModuloRigid gauge)
// and its pose, with a fixed sparse matrix that expands x into per-row weights.
#pragma once

#include <filesystem>
#include <string>

#include "hsi/frames_io.h"

namespace hsi {

struct BakeOptions {
  bool single_precision = true;  // per-frame coefficients as f32 (≈1e-7 of the shape's size), else f64
};

// Bakes posed frames (e.g. those of hsi interpolate) over their cage; the shape
// gives the bounding box recorded in the header. Throws InputError for a frame
// whose coefficients do not fit the cage or break ψ_log = conj φ_log.
std::string encode_baked(const Shape& shape, const FrameFile& frames, const BakeOptions& options = {});
void write_baked(const std::filesystem::path& path, const Shape& shape, const FrameFile& frames,
                 const BakeOptions& options = {});  // atomic (temp + rename)

}  // namespace hsi
