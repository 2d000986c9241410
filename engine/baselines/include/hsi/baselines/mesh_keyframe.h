// A keyframe of the mesh baselines (ARAP, FFMP, GE): the rest mesh's vertices placed at
// one time. Every mesh baseline takes a list of them, at strictly increasing times.
#pragma once

#include <vector>

#include "hsi/triangulate.h"

namespace hsi::baselines {

struct MeshKeyframe {
  double time = 0;
  std::vector<cd> positions;  // one position per rest mesh vertex
};

}  // namespace hsi::baselines
