// hsi compare, stage 2: Fig. 8 alignment. The methods place a frame differently (ours by an
// interpolated rigid pose, CCW16 from an anchor point and its mean rotation), so CCW16 is
// compared with ours as is and after the best rigid motion (hsi::rigid_fit).
#pragma once

#include <limits>
#include <span>
#include <vector>

#include "hsi/domain.h"

namespace hsi::compare {

// max |a_i − b_i| as given, and after the best rigid motion of a onto b, both / size.
struct Gap {
  double raw = 0, rigid = 0;
};
Gap point_gap(std::span<const cd> a, std::span<const cd> b, double size);

// One CCW16 variant's distance to our frames (relative to the size): the largest over
// the side-by-side times as is and after rigid alignment, and over the whole sequence.
struct Fig8 {
  double raw = 0, rigid = 0;
  double sequence_rigid = std::numeric_limits<double>::quiet_NaN(), sequence_t = std::numeric_limits<double>::quiet_NaN();
  double between_keyframes_rigid = std::numeric_limits<double>::quiet_NaN();  // the same without the keyframes' frames
};
// `at_snapshots`: the gaps at the side-by-side times; `distance`: the rigid gap per frame
// at times `t`, `keyframe` marking the keyframes' own frames (where ours and CCW16 (log
// derivatives) reproduce the keyframe exactly: the interpolation lies between them).
Fig8 fig8(std::span<const Gap> at_snapshots, const std::vector<double>& distance, const std::vector<double>& t,
          const std::vector<bool>& keyframe);

}  // namespace hsi::compare
