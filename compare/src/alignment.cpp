// Fig. 8: CCW16 against ours as is and after rigid alignment (hsi/compare/alignment.h).
#include "hsi/compare/alignment.h"

#include <algorithm>
#include <cmath>

#include "format.h"
#include "hsi/rigid_fit.h"

namespace hsi::compare {

Gap point_gap(std::span<const cd> a, std::span<const cd> b, double size) {
  Gap g;
  const RigidMotion m = rigid_fit(a, b);
  for (size_t i = 0; i < a.size(); ++i) {
    g.raw = std::max(g.raw, std::abs(a[i] - b[i]));
    g.rigid = std::max(g.rigid, std::abs(m.residual(a[i], b[i])));
  }
  g.raw /= size;
  g.rigid /= size;
  return g;
}

Fig8 fig8(std::span<const Gap> at_snapshots, const std::vector<double>& distance, const std::vector<double>& t,
          const std::vector<bool>& keyframe) {
  Fig8 f;
  for (const Gap& g : at_snapshots) {
    f.raw = std::max(f.raw, g.raw);
    f.rigid = std::max(f.rigid, g.rigid);
  }
  if (distance.empty()) return f;
  f.sequence_rigid = max_of(distance);
  f.sequence_t = t[static_cast<size_t>(std::max_element(distance.begin(), distance.end()) - distance.begin())];
  std::vector<double> between;
  for (size_t i = 0; i < distance.size(); ++i)
    if (!keyframe[i]) between.push_back(distance[i]);
  if (!between.empty()) f.between_keyframes_rigid = max_of(between);
  return f;
}

}  // namespace hsi::compare
