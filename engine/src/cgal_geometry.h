// Geometry chores done with CGAL's exact predicates (kept to one translation unit,
// cgal_geometry.cpp, so that builds stay fast).
#pragma once

#include <algorithm>
#include <span>
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

// A box hierarchy built once over closed loops of fixed slots (the overlap check's
// breakpoints, issue #23): a balanced tree over contiguous runs of each loop's slots,
// then a balanced tree over the loops, stored flat. Per search only the boxes are
// refit bottom-up (O(slots)) from that search's points and edges, then the tree is
// traversed: a node's pairs are its children's own and the pairs between its two
// children, a pair of nodes dismissed by one closed box test, and a node within one
// loop whose edges all run strictly one way in x (or all in y) has none of its own: its
// chain is the graph of a function over disjoint intervals, so only neighbours meet,
// at their shared point, without folding back. Each candidate pair of
// edges is decided exactly, as edges_meet in intersecting_edges decides it (a static
// floating-point filter on each orientation, CGAL's exact predicate where it cannot
// tell). Slots are numbered loop by loop.
class LoopHierarchy {
 public:
  // loop_slots[l]: the slots of loop l (the slots of loop 0 first, then loop 1, ...).
  explicit LoopHierarchy(std::span<const int> loop_slots);

  struct Box {
    double x0, x1, y0, y1;  // closed; empty (x0 > x1) for a slot without an edge
    bool meets(const Box& o) const { return x0 <= o.x1 && o.x0 <= x1 && y0 <= o.y1 && o.y0 <= y1; }
    Box operator|(const Box& o) const {
      return {std::min(x0, o.x0), std::max(x1, o.x1), std::min(y0, o.y0), std::max(y1, o.y1)};
    }
  };
  struct Node {
    int lo, hi;  // the slots [lo, hi)
    int right;   // the right child (the left one is this node + 1); −1: a leaf
    bool chain;  // its slots lie on one loop (one run of consecutive edges)
  };
  // Scratch of one search (the boxes of the slots and nodes, and the directions every
  // edge of a node runs strictly in: bits +x, −x, +y, −y), sized on first use and reused
  // after: one per thread.
  struct Workspace {
    std::vector<Box> slot_box, node_box;
    std::vector<unsigned char> slot_runs, node_runs;
  };
  // Intersecting pairs of edges: how many, and the first in slot order (a < b).
  struct Crossings {
    long count = 0;
    int a = -1, b = -1;
  };
  // Slot i is the edge from points[i] to points[next[i]] (next[i] < 0: slot i holds no
  // edge this time; next stays within i's loop). Two edges count when they share any
  // point, except two neighbours (one's end is the other's start), which count only
  // when they fold back onto each other along a line.
  Crossings search(std::span<const cd> points, std::span<const int> next, Workspace& workspace) const;

  int slots() const { return slots_; }

 private:
  int build_loops(std::span<const int> loop_begin, int l0, int l1);
  int build_run(int lo, int hi);

  int slots_ = 0;
  std::vector<Node> nodes_;  // pre-order: children after their parent
};

}  // namespace hsi::detail
