// The range of |G| (boundary samples) every front-end accepts: scene files, the CLI's and
// the viewer's --samples. One place, so that a scene valid in one is valid in all.
#pragma once

namespace hsi {

inline constexpr int kMinSamples = 100;
inline constexpr int kMaxSamples = 10'000'000;

}  // namespace hsi
