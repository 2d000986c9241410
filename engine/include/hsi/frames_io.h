// Interpolated frames on disk: a compact, versioned binary (.hsif) holding the cage
// once and then, per frame, its time, status and coefficients.
//
// Layout (little-endian), version 2:
//   char[4] "HSIF"; u32 version = 2
//   u32 L; L × { u32 count; count × (f64 x, f64 y) }      cage loops (outer first)
//   u32 N; N × (f64 x, f64 y)                               hole points ρ_i
//   u32 K (= cage vertices + N, coefficients per map); u32 F (frames)
//   F × { f64 t; u32 flags; u32 iterations;
//         f64 energy; K × (f64 re, f64 im) φ; K × (f64 re, f64 im) ψ }
// The flags word:
//   bits 0..3   1 certified locally injective, 2 keyframe, 4 converged, 8 overlaps
//               itself (the image of the boundary crosses itself, overlap.h)
//   bits 4..7   0
//   bits 8..15  why the frame's Newton solve stopped: a NewtonStop value (newton.h; the
//               C API's hsi_stop numbers them alike: 0 converged, 1 iteration limit,
//               2 stagnated, 3 certificate refused, 4 no decrease, 5 not factored,
//               6 start folds, 7 start not certified), or 255 (kFramesStopNotRecorded)
//               for a frame whose reason is not known (read from a version 1 file, not
//               converged). 0 exactly when flag 4 is set.
//   bits 16..31 0
// Version 1 (still read) is the same but for the flags word, which held bits 0..3 only:
// its frames read as stop Converged where flag 4 is set, not recorded (StoredFrame::stop
// empty) where it is not.
// A reader refuses a wrong magic, an unknown version, impossible sizes, a truncated
// file, unknown flag bits and an unknown stop code or one that contradicts flag 4,
// naming what is wrong, the frame, and at which byte.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "hsi/cage.h"
#include "hsi/harmonic_map.h"
#include "hsi/newton.h"

namespace hsi {

inline constexpr uint32_t kFramesVersion = 2;
// Bits 8..15 of a version 2 frame's flags: the stop reason is not known.
inline constexpr uint32_t kFramesStopNotRecorded = 255;

struct StoredFrame {
  double t = 0;
  bool certified = false, keyframe = false, converged = false;
  uint32_t iterations = 0;
  double energy = 0;
  HarmonicMap map;
  bool overlaps = false;  // flag 8: f(∂Ω) crosses itself at the breakpoints (overlap.h)
  // Why the frame's Newton solve stopped (FrameResult::stop; a keyframe or held frame:
  // Converged). Empty: not recorded, and `converged` alone says what is known: a
  // converged frame is stored as Converged, another as not recorded (kFramesStopNotRecorded;
  // a version 1 file's frames read back so). NewtonStop has no "unknown" of its own.
  // When given, converged == (*stop == NewtonStop::Converged): writers refuse a frame
  // where they disagree (stored_stop).
  std::optional<NewtonStop> stop = std::nullopt;
};

// The stop reason a file stores for frame `index`: `stop`, or Converged for a converged
// frame that does not say; empty when not recorded. Throws InputError naming the frame
// when `stop` and `converged` disagree.
std::optional<NewtonStop> stored_stop(const StoredFrame& frame, size_t index);
// to_string(*stop), or "not recorded" when empty.
const char* stop_name(const std::optional<NewtonStop>& stop);
// The frames that did not converge counted by why (stored_stop), in NewtonStop's order,
// those not recorded last: "3 iteration limit, 1 stagnated"; "" when every frame converged.
std::string stop_counts(const std::vector<StoredFrame>& frames);
// The same over stored stops (stored_stop's values; Converged is not counted).
std::string stop_counts(const std::vector<std::optional<NewtonStop>>& stops);

struct FrameFile {
  Cage cage;
  std::vector<StoredFrame> frames;
};

std::string encode_frames(const FrameFile& file);
FrameFile decode_frames(const std::string& bytes, const std::string& source = "frames");
void write_frames(const std::filesystem::path& path, const FrameFile& file);  // atomic (temp + rename)
FrameFile read_frames(const std::filesystem::path& path);

}  // namespace hsi
