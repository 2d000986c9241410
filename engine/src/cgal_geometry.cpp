// The only translation unit that includes CGAL: exact segment-intersection search.
//
// Candidate pairs come from a bounding-box hierarchy over the edges in their loop
// order: consecutive edges of a polyline make tight boxes, so the hierarchy is built in
// O(B) without sorting and a pair of disjoint sub-chains is dismissed by one box test.
// Boxes are the segments' exact coordinate extremes, compared closed (≤), so every
// pair of segments that meet is a candidate; each candidate is then decided by CGAL's
// exact predicates. The pairs found are therefore exactly those CGAL's
// box_self_intersection_d (closed boxes) found before, at a fraction of its time on
// the overlap check's ~10k-edge polylines (issue #23).
#include "cgal_geometry.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>

#include <algorithm>

namespace hsi::detail {
namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P2 = K::Point_2;
using S2 = K::Segment_2;

// Whether edges a and b (segments sa, sb) count as intersecting: any common point,
// except for two neighbours of one loop, which share a vertex and count only when
// they fold back onto each other along a line (a spike). Exact predicates.
bool edges_meet(const std::vector<const Loop*>& loops, const EdgeRef& a, const EdgeRef& b, const S2& sa, const S2& sb) {
  if (a.loop == b.loop) {
    const int n = static_cast<int>(loops[static_cast<size_t>(a.loop)]->size());
    const bool neighbours = (a.edge + 1) % n == b.edge || (b.edge + 1) % n == a.edge;
    if (neighbours) {
      if (!CGAL::collinear(sa.source(), sa.target(), sb.target()) || !CGAL::collinear(sa.source(), sa.target(), sb.source()))
        return false;
      const auto inter = CGAL::intersection(sa, sb);
      return inter && boost::get<S2>(&*inter);
    }
  }
  return CGAL::do_intersect(sa, sb);
}

// Deterministic report: each pair (lower (loop, edge) first), pairs in (loop, edge) order.
std::vector<std::pair<EdgeRef, EdgeRef>> ordered(std::vector<std::pair<EdgeRef, EdgeRef>> found) {
  for (auto& p : found)
    if (std::tie(p.second.loop, p.second.edge) < std::tie(p.first.loop, p.first.edge)) std::swap(p.first, p.second);
  std::sort(found.begin(), found.end(), [](const auto& u, const auto& v) {
    return std::tie(u.first.loop, u.first.edge, u.second.loop, u.second.edge) <
           std::tie(v.first.loop, v.first.edge, v.second.loop, v.second.edge);
  });
  return found;
}

struct Box {
  double x0, x1, y0, y1;
  bool meets(const Box& o) const { return x0 <= o.x1 && o.x0 <= x1 && y0 <= o.y1 && o.y0 <= y1; }
  Box operator|(const Box& o) const {
    return {std::min(x0, o.x0), std::max(x1, o.x1), std::min(y0, o.y0), std::max(y1, o.y1)};
  }
};

// A node covers the edges [lo, hi) of the flattened list; its children split the range
// in halves (left child at index + 1, right child at `right`). Leaves hold ≤ kLeaf edges.
struct Node {
  Box box;
  int lo, hi, right;
};
constexpr int kLeaf = 4;

class Search {
 public:
  Search(const std::vector<const Loop*>& loops, size_t max_results) : loops_(loops), max_(max_results) {
    for (int l = 0; l < static_cast<int>(loops.size()); ++l) {
      const Loop& loop = *loops[static_cast<size_t>(l)];
      const int n = static_cast<int>(loop.size());
      for (int i = 0; i < n; ++i) {
        const cd a = loop[static_cast<size_t>(i)], b = loop[static_cast<size_t>((i + 1) % n)];
        refs_.push_back({l, i});
        segs_.emplace_back(P2(a.real(), a.imag()), P2(b.real(), b.imag()));
        boxes_.push_back({std::min(a.real(), b.real()), std::max(a.real(), b.real()), std::min(a.imag(), b.imag()),
                          std::max(a.imag(), b.imag())});
      }
    }
    if (!refs_.empty()) {
      nodes_.reserve(2 * refs_.size() / kLeaf + 2);
      build(0, static_cast<int>(refs_.size()));
      self(0);
    }
  }

  std::vector<std::pair<EdgeRef, EdgeRef>> found;

 private:
  int build(int lo, int hi) {
    const int id = static_cast<int>(nodes_.size());
    nodes_.push_back({boxes_[static_cast<size_t>(lo)], lo, hi, -1});
    if (hi - lo <= kLeaf) {
      Box b = boxes_[static_cast<size_t>(lo)];
      for (int i = lo + 1; i < hi; ++i) b = b | boxes_[static_cast<size_t>(i)];
      nodes_[static_cast<size_t>(id)].box = b;
      return id;
    }
    const int mid = lo + (hi - lo) / 2;
    const int left = build(lo, mid);
    const int right = build(mid, hi);
    nodes_[static_cast<size_t>(id)].right = right;
    nodes_[static_cast<size_t>(id)].box = nodes_[static_cast<size_t>(left)].box | nodes_[static_cast<size_t>(right)].box;
    return id;
  }

  bool full() const { return found.size() >= max_; }

  // Pairs within one node.
  void self(int id) {
    const Node& n = nodes_[static_cast<size_t>(id)];
    if (full()) return;
    if (n.right < 0) {
      for (int i = n.lo; i < n.hi; ++i)
        for (int j = i + 1; j < n.hi; ++j) candidate(i, j);
      return;
    }
    self(id + 1);
    self(n.right);
    pair(id + 1, n.right);
  }

  // Pairs with one edge in node a and one in node b (disjoint ranges, a's first).
  void pair(int a, int b) {
    const Node& A = nodes_[static_cast<size_t>(a)];
    const Node& B = nodes_[static_cast<size_t>(b)];
    if (full() || !A.box.meets(B.box)) return;
    const bool a_leaf = A.right < 0, b_leaf = B.right < 0;
    if (a_leaf && b_leaf) {
      for (int i = A.lo; i < A.hi; ++i)
        for (int j = B.lo; j < B.hi; ++j) candidate(i, j);
    } else if (b_leaf || (!a_leaf && A.hi - A.lo >= B.hi - B.lo)) {
      pair(a + 1, b);
      pair(A.right, b);
    } else {
      pair(a, b + 1);
      pair(a, B.right);
    }
  }

  void candidate(int i, int j) {
    if (full() || !boxes_[static_cast<size_t>(i)].meets(boxes_[static_cast<size_t>(j)])) return;
    const EdgeRef& a = refs_[static_cast<size_t>(i)];
    const EdgeRef& b = refs_[static_cast<size_t>(j)];
    if (edges_meet(loops_, a, b, segs_[static_cast<size_t>(i)], segs_[static_cast<size_t>(j)])) found.push_back({a, b});
  }

  const std::vector<const Loop*>& loops_;
  size_t max_;
  std::vector<EdgeRef> refs_;
  std::vector<S2> segs_;
  std::vector<Box> boxes_;
  std::vector<Node> nodes_;
};
}  // namespace

std::vector<std::pair<EdgeRef, EdgeRef>> intersecting_edges(const std::vector<const Loop*>& loops,
                                                            size_t max_results) {
  return ordered(Search(loops, max_results).found);
}

namespace {
struct EdgeBox : CGAL::Box_intersection_d::Box_with_handle_d<double, 2, const EdgeRef*> {
  using Base = CGAL::Box_intersection_d::Box_with_handle_d<double, 2, const EdgeRef*>;
  EdgeBox(const CGAL::Bbox_2& b, const EdgeRef* r) : Base(b, r) {}
};
}  // namespace

std::vector<std::pair<EdgeRef, EdgeRef>> intersecting_edges_box_sweep(const std::vector<const Loop*>& loops,
                                                                      size_t max_results) {
  std::vector<EdgeRef> refs;
  std::vector<S2> segs;
  for (int l = 0; l < static_cast<int>(loops.size()); ++l) {
    const Loop& loop = *loops[static_cast<size_t>(l)];
    const int n = static_cast<int>(loop.size());
    for (int i = 0; i < n; ++i) {
      const cd a = loop[static_cast<size_t>(i)], b = loop[static_cast<size_t>((i + 1) % n)];
      refs.push_back({l, i});
      segs.emplace_back(P2(a.real(), a.imag()), P2(b.real(), b.imag()));
    }
  }
  std::vector<EdgeBox> boxes;
  boxes.reserve(refs.size());
  for (size_t k = 0; k < refs.size(); ++k) boxes.emplace_back(segs[k].bbox(), &refs[k]);
  std::vector<std::pair<EdgeRef, EdgeRef>> found;
  const EdgeRef* base = refs.data();
  auto callback = [&](const EdgeBox& x, const EdgeBox& y) {
    if (found.size() >= max_results) return;
    const EdgeRef* a = x.handle();
    const EdgeRef* b = y.handle();
    if (edges_meet(loops, *a, *b, segs[static_cast<size_t>(a - base)], segs[static_cast<size_t>(b - base)])) found.push_back({*a, *b});
  };
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), callback);
  return ordered(std::move(found));
}

}  // namespace hsi::detail
