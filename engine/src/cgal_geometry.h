// Geometry chores done with CGAL's exact predicates (kept to one translation unit,
// cgal_geometry.cpp, so that builds stay fast).
#pragma once

#include <utility>
#include <vector>

#include "hsi/domain.h"

namespace hsi::detail {

struct EdgeRef {
  int loop;  // index into the loops span
  int edge;  // edge i joins vertex i to vertex i+1 (cyclic)
};

// Pairs of edges that intersect, other than neighbours of one loop meeting at
// their shared vertex (a neighbour pair that folds back onto itself is reported).
// Exact predicates; stops after max_results pairs.
std::vector<std::pair<EdgeRef, EdgeRef>> intersecting_edges(const std::vector<const Loop*>& loops,
                                                            size_t max_results = 1);

}  // namespace hsi::detail
