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
// Exact predicates; candidates from a box hierarchy over the edges in loop order;
// stops after max_results pairs (those found first, in loop order). Pairs in (loop,
// edge) order, the lower edge first.
std::vector<std::pair<EdgeRef, EdgeRef>> intersecting_edges(const std::vector<const Loop*>& loops,
                                                            size_t max_results = 1);
// The same pairs from CGAL's box_self_intersection_d (the search intersecting_edges
// used before issue #23, several times slower on ~10k-edge polylines): the reference
// it is tested against. Equal results whenever fewer than max_results pairs exist.
std::vector<std::pair<EdgeRef, EdgeRef>> intersecting_edges_box_sweep(const std::vector<const Loop*>& loops,
                                                                      size_t max_results = 1);

}  // namespace hsi::detail
