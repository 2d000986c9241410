// Least-squares rigid fit of point lists (hsi/rigid_fit.h).
#include "hsi/rigid_fit.h"

#include <string>

namespace hsi {

RigidMotion rigid_fit(std::span<const cd> from, std::span<const cd> to) {
  if (from.empty() || from.size() != to.size())
    throw InputError("rigid fit: " + std::to_string(from.size()) + " points to carry onto " + std::to_string(to.size()) +
                     " (the lists must be as long as each other and not empty)");
  RigidMotion m;
  for (size_t i = 0; i < from.size(); ++i) {
    m.from_centroid += from[i];
    m.to_centroid += to[i];
  }
  m.from_centroid /= static_cast<double>(from.size());
  m.to_centroid /= static_cast<double>(to.size());
  cd s = 0;
  for (size_t i = 0; i < from.size(); ++i) s += (to[i] - m.to_centroid) * std::conj(from[i] - m.from_centroid);
  m.rotation = std::abs(s) > 0 ? s / std::abs(s) : cd(1, 0);
  return m;
}

}  // namespace hsi
