// Baking a sequence for playback in a game: the .hsib format (layout, and the tiny
// C runtime that plays it back, in hsi/baked_runtime.h). The cage and hole points
// are stored once, then per frame its reduced coefficients x (ModuloRigid gauge)
// and its pose, with a fixed sparse matrix that expands x into per-row weights.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>

#include "hsi/frames_io.h"

namespace hsi {

struct BakeOptions {
  bool single_precision = true;  // per-frame coefficients as f32 (≈1e-7 of the shape's size), else f64
  // k: the blends (1 − s) f_i + s f_{i+1} at s = j/k, 0 < j < k, of every interval
  // between two certified frames are certified with the engine's certificate (and
  // checked for overlaps); intervals where all pass are flagged so the runtime may
  // blend there. 0 or 1: no blends certified (the runtime plays nearest frames).
  int blend_substeps = 4;
  int certificate_samples = 2000;  // |G| of the boundary samples that break ∂Ω for those certificates
  int mesh_vertices = 2000;        // the stored triangulation of the shape, about this many vertices
  std::optional<std::array<double, 4>> texture_rect = std::nullopt;  // x0 y0 x1 y1 the texture covers (default: the shape's bounding box)
};

// Bakes posed frames (e.g. those of hsi interpolate) over their cage, with the
// shape's outline and triangulation; the shape gives the bounding box recorded in
// the header. Throws InputError for a frame whose coefficients do not fit the cage
// or break ψ_log = conj φ_log.
std::string encode_baked(const Shape& shape, const FrameFile& frames, const BakeOptions& options = {});
void write_baked(const std::filesystem::path& path, const Shape& shape, const FrameFile& frames,
                 const BakeOptions& options = {});  // atomic (temp + rename)

}  // namespace hsi
