// The only translation unit that includes CGAL: exact segment-intersection search.
//
// intersecting_edges: candidate pairs come from a bounding-box hierarchy over the edges
// in their loop order, built per call: consecutive edges of a polyline make tight
// boxes, so the hierarchy is built in O(B) without sorting and a pair of disjoint
// sub-chains is dismissed by one box test. Boxes are the segments' exact coordinate
// extremes, compared closed (≤), so every pair of segments that meet is a candidate;
// each candidate is then decided by CGAL's exact predicates. The pairs found are
// therefore exactly those CGAL's box_self_intersection_d (closed boxes) found before,
// at a fraction of its time on the overlap check's ~10k-edge polylines (issue #23).
//
// LoopHierarchy: the same kind of hierarchy for the overlap check's fixed loops, built
// once and refit per search, with a static filter in front of CGAL's orientation test.
#include "cgal_geometry.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <cmath>
#include <limits>

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

using Box = LoopHierarchy::Box;

// The pairs of items (i < j) of a binary hierarchy over index ranges that may meet: both
// in one leaf, or in two nodes that `meet(a, b)` (node ids), the larger node split
// first; a node whose own pairs `skip(id)` says need no look is not entered. Nodes have
// lo, hi (the items [lo, hi)) and right (the right child; the left is id + 1; −1: a leaf).
// The one walk of intersecting_edges' per-call search and of LoopHierarchy::search.
template <class Node, class Skip, class Meet, class Candidate>
class SelfPairs {
 public:
  SelfPairs(std::span<const Node> nodes, Skip skip, Meet meet, Candidate candidate)
      : nodes_(nodes), skip_(skip), meet_(meet), candidate_(candidate) {}

  // Pairs within node id.
  void self(int id) {
    if (skip_(id)) return;
    const Node& n = nodes_[static_cast<size_t>(id)];
    if (n.right < 0) {
      for (int i = n.lo; i < n.hi; ++i)
        for (int j = i + 1; j < n.hi; ++j) candidate_(i, j);
      return;
    }
    self(id + 1);
    self(n.right);
    pair(id + 1, n.right);
  }

 private:
  // Pairs with one item in node a and one in node b (disjoint ranges, a's first).
  void pair(int a, int b) {
    if (!meet_(a, b)) return;
    const Node& A = nodes_[static_cast<size_t>(a)];
    const Node& B = nodes_[static_cast<size_t>(b)];
    const bool a_leaf = A.right < 0, b_leaf = B.right < 0;
    if (a_leaf && b_leaf) {
      for (int i = A.lo; i < A.hi; ++i)
        for (int j = B.lo; j < B.hi; ++j) candidate_(i, j);
    } else if (b_leaf || (!a_leaf && A.hi - A.lo >= B.hi - B.lo)) {
      pair(a + 1, b);
      pair(A.right, b);
    } else {
      pair(a, b + 1);
      pair(a, B.right);
    }
  }

  std::span<const Node> nodes_;
  Skip skip_;
  Meet meet_;
  Candidate candidate_;
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
      SelfPairs walk(std::span<const Node>(nodes_), [this](int) { return full(); },
                     [this](int a, int b) {
                       return !full() && nodes_[static_cast<size_t>(a)].box.meets(nodes_[static_cast<size_t>(b)].box);
                     },
                     [this](int i, int j) { candidate(i, j); });
      walk.self(0);
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

namespace {

// The sign of the orientation of (a, b, c) (+1: counter-clockwise, 0: collinear), exact:
// Shewchuk's static error bound for orient2d (ccwerrboundA, taken over |l| + |r|, which
// is never smaller than his) decides wherever the products neither underflow nor
// overflow; elsewhere, and whenever the bound cannot tell, CGAL's filtered exact
// predicate decides, so the sign is always the exact one.
int orientation(cd a, cd b, cd c) {
  const double l = (a.real() - c.real()) * (b.imag() - c.imag());
  const double r = (a.imag() - c.imag()) * (b.real() - c.real());
  const double det = l - r;
  const double mag = std::abs(l) + std::abs(r);
  constexpr double eps = 0x1p-53;
  constexpr double bound = (3 + 16 * eps) * eps;
  if (mag >= 1e-280 && mag <= 1e280) {  // the bound's relative error analysis holds here
    if (det > bound * mag) return 1;
    if (-det > bound * mag) return -1;
  }
  return static_cast<int>(CGAL::orientation(P2(a.real(), a.imag()), P2(b.real(), b.imag()), P2(c.real(), c.imag())));
}

// Lexicographic (x, then y) order of two points: −1, 0, +1 (exact on doubles).
int compare_xy(cd p, cd q) {
  if (p.real() != q.real()) return p.real() < q.real() ? -1 : 1;
  if (p.imag() != q.imag()) return p.imag() < q.imag() ? -1 : 1;
  return 0;
}

// Whether the closed segments [a0, a1] and [b0, b1] share a point (CGAL::do_intersect):
// each straddles (or touches) the other's line, or all four points lie on one line and
// their extents along it overlap.
bool segments_meet(cd a0, cd a1, cd b0, cd b1) {
  const int o1 = orientation(a0, a1, b0), o2 = orientation(a0, a1, b1);
  if (o1 * o2 > 0) return false;
  const int o3 = orientation(b0, b1, a0), o4 = orientation(b0, b1, a1);
  if (o3 * o4 > 0) return false;
  if (o1 != 0 || o2 != 0 || o3 != 0 || o4 != 0) return true;
  if (compare_xy(a1, a0) < 0) std::swap(a0, a1);
  if (compare_xy(b1, b0) < 0) std::swap(b0, b1);
  return compare_xy(a1, b0) >= 0 && compare_xy(b1, a0) >= 0;
}

// Two neighbours meeting at s, their other ends pa and pb: they share more than s
// (edges_meet's spike: CGAL's intersection of the two is a segment) exactly when the
// three points are collinear and pa, pb lie on the same side of s. A zero-length edge
// (pa or pb at s) meets the other at s alone.
bool folds_back(cd s, cd pa, cd pb) {
  const int side = compare_xy(pa, s);
  return side != 0 && side == compare_xy(pb, s) && orientation(s, pa, pb) == 0;
}

constexpr int kLeafSlots = 4;
constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

LoopHierarchy::LoopHierarchy(std::span<const int> loop_slots) {
  std::vector<int> bounds{0};  // loop k of those with slots spans [bounds[k], bounds[k + 1])
  for (int n : loop_slots) {
    if (n < 0) throw InputError("LoopHierarchy: a loop of " + std::to_string(n) + " slots");
    if (n > 0) bounds.push_back(bounds.back() + n);
  }
  slots_ = bounds.back();
  if (slots_ == 0) return;
  nodes_.reserve(static_cast<size_t>(2 * (slots_ / kLeafSlots + static_cast<int>(bounds.size())) + 2));
  build_loops(bounds, 0, static_cast<int>(bounds.size()) - 1);
}

int LoopHierarchy::build_loops(std::span<const int> bounds, int l0, int l1) {
  if (l1 - l0 == 1) return build_run(bounds[static_cast<size_t>(l0)], bounds[static_cast<size_t>(l1)]);
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back({bounds[static_cast<size_t>(l0)], bounds[static_cast<size_t>(l1)], -1, false});
  // Split between loops, at the loop boundary nearest the middle slot.
  const int mid = bounds[static_cast<size_t>(l0)] + (bounds[static_cast<size_t>(l1)] - bounds[static_cast<size_t>(l0)]) / 2;
  int m = l0 + 1;
  for (int k = l0 + 2; k < l1; ++k)
    if (std::abs(bounds[static_cast<size_t>(k)] - mid) < std::abs(bounds[static_cast<size_t>(m)] - mid)) m = k;
  build_loops(bounds, l0, m);
  const int right = build_loops(bounds, m, l1);
  nodes_[static_cast<size_t>(id)].right = right;
  return id;
}

int LoopHierarchy::build_run(int lo, int hi) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back({lo, hi, -1, true});
  if (hi - lo <= kLeafSlots) return id;
  const int mid = lo + (hi - lo) / 2;
  build_run(lo, mid);
  const int right = build_run(mid, hi);
  nodes_[static_cast<size_t>(id)].right = right;
  return id;
}

namespace {

// One search's traversal over a refit hierarchy.
class Traversal {
 public:
  using Box = LoopHierarchy::Box;
  Traversal(std::span<const LoopHierarchy::Node> nodes, std::span<const cd> points, std::span<const int> next,
            std::span<const Box> slot_box, std::span<const Box> node_box, std::span<const unsigned char> node_runs)
      : nodes_(nodes), z_(points), next_(next), slot_box_(slot_box), node_box_(node_box), node_runs_(node_runs) {}

  LoopHierarchy::Crossings found;

  // Every crossing pair; none inside a chain running strictly one way.
  void run() {
    SelfPairs walk(nodes_, [this](int id) { return node_runs_[static_cast<size_t>(id)] != 0; },
                   [this](int a, int b) { return node_box_[static_cast<size_t>(a)].meets(node_box_[static_cast<size_t>(b)]); },
                   [this](int i, int j) { candidate(i, j); });
    walk.self(0);
  }

 private:
  // Edges i < j (slots); an empty slot's box meets nothing.
  void candidate(int i, int j) {
    if (!slot_box_[static_cast<size_t>(i)].meets(slot_box_[static_cast<size_t>(j)])) return;
    const int ni = next_[static_cast<size_t>(i)], nj = next_[static_cast<size_t>(j)];
    const cd a0 = z_[static_cast<size_t>(i)], a1 = z_[static_cast<size_t>(ni)];
    const cd b0 = z_[static_cast<size_t>(j)], b1 = z_[static_cast<size_t>(nj)];
    bool hit;
    if (ni == j)
      hit = folds_back(a1, a0, b1);
    else if (nj == i)
      hit = folds_back(a0, a1, b0);
    else
      hit = segments_meet(a0, a1, b0, b1);
    if (!hit) return;
    ++found.count;
    if (found.a < 0 || i < found.a || (i == found.a && j < found.b)) found.a = i, found.b = j;
  }

  std::span<const LoopHierarchy::Node> nodes_;
  std::span<const cd> z_;
  std::span<const int> next_;
  std::span<const Box> slot_box_, node_box_;
  std::span<const unsigned char> node_runs_;
};

// The directions edge a → b runs strictly in: bit 0 +x, 1 −x, 2 +y, 3 −y (exact).
unsigned char runs(cd a, cd b) {
  return static_cast<unsigned char>((b.real() > a.real() ? 1 : 0) | (b.real() < a.real() ? 2 : 0) | (b.imag() > a.imag() ? 4 : 0) |
                                    (b.imag() < a.imag() ? 8 : 0));
}

}  // namespace

LoopHierarchy::Crossings LoopHierarchy::search(std::span<const cd> points, std::span<const int> next,
                                               Workspace& workspace) const {
  if (points.size() != static_cast<size_t>(slots_) || next.size() != static_cast<size_t>(slots_))
    throw InputError("LoopHierarchy::search: " + std::to_string(points.size()) + " points and " +
                                std::to_string(next.size()) + " edges for " + std::to_string(slots_) + " slots");
  if (nodes_.empty()) return {};
  std::vector<Box>& sb = workspace.slot_box;
  std::vector<Box>& nb = workspace.node_box;
  std::vector<unsigned char>& sr = workspace.slot_runs;
  std::vector<unsigned char>& nr = workspace.node_runs;
  sb.resize(static_cast<size_t>(slots_));  // no allocation once sized
  nb.resize(nodes_.size());
  sr.resize(sb.size());
  nr.resize(nb.size());
  for (size_t i = 0; i < sb.size(); ++i) {
    const int j = next[i];
    if (j < 0) {
      sb[i] = {kInf, -kInf, kInf, -kInf};  // meets no box
      sr[i] = 15;                          // and runs every way
      continue;
    }
    const cd a = points[i], b = points[static_cast<size_t>(j)];
    sb[i] = {std::min(a.real(), b.real()), std::max(a.real(), b.real()), std::min(a.imag(), b.imag()), std::max(a.imag(), b.imag())};
    sr[i] = runs(a, b);
  }
  for (size_t id = nodes_.size(); id-- > 0;) {  // children after parents: refit bottom-up
    const Node& n = nodes_[id];
    if (n.right < 0) {
      Box b = sb[static_cast<size_t>(n.lo)];
      unsigned char r = sr[static_cast<size_t>(n.lo)];
      for (int i = n.lo + 1; i < n.hi; ++i) {
        b = b | sb[static_cast<size_t>(i)];
        r &= sr[static_cast<size_t>(i)];
      }
      nb[id] = b;
      nr[id] = r;
    } else {
      nb[id] = nb[id + 1] | nb[static_cast<size_t>(n.right)];
      nr[id] = n.chain ? static_cast<unsigned char>(nr[id + 1] & nr[static_cast<size_t>(n.right)]) : 0;
    }
  }
  Traversal t(nodes_, points, next, sb, nb, nr);
  t.run();
  return t.found;
}

}  // namespace hsi::detail
