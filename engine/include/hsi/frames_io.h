// Interpolated frames on disk: a compact, versioned binary (.hsif) holding the cage
// once and then, per frame, its time, status and coefficients.
//
// Layout (little-endian), version 1:
//   char[4] "HSIF"; u32 version = 1
//   u32 L; L × { u32 count; count × (f64 x, f64 y) }      cage loops (outer first)
//   u32 N; N × (f64 x, f64 y)                               hole points ρ_i
//   u32 K (= cage vertices + N, coefficients per map); u32 F (frames)
//   F × { f64 t; u32 flags (1 certified locally injective, 2 keyframe, 4 converged,
//         8 overlaps itself: the image of the boundary crosses itself, overlap.h);
//         u32 iterations;
//         f64 energy; K × (f64 re, f64 im) φ; K × (f64 re, f64 im) ψ }
// A reader refuses a wrong magic, an unknown version, impossible sizes and a
// truncated file, naming what is wrong and at which byte.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "hsi/cage.h"
#include "hsi/harmonic_map.h"

namespace hsi {

inline constexpr uint32_t kFramesVersion = 1;

struct StoredFrame {
  double t = 0;
  bool certified = false, keyframe = false, converged = false;
  uint32_t iterations = 0;
  double energy = 0;
  HarmonicMap map;
  bool overlaps = false;  // flag 8: f(∂Ω) crosses itself at the breakpoints (overlap.h)
};

struct FrameFile {
  Cage cage;
  std::vector<StoredFrame> frames;
};

std::string encode_frames(const FrameFile& file);
FrameFile decode_frames(const std::string& bytes, const std::string& source = "frames");
void write_frames(const std::filesystem::path& path, const FrameFile& file);  // atomic (temp + rename)
FrameFile read_frames(const std::filesystem::path& path);

}  // namespace hsi
