// The only translation unit that includes CGAL: exact segment-intersection search.
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

struct EdgeBox : CGAL::Box_intersection_d::Box_with_handle_d<double, 2, const EdgeRef*> {
  using Base = CGAL::Box_intersection_d::Box_with_handle_d<double, 2, const EdgeRef*>;
  EdgeBox(const CGAL::Bbox_2& b, const EdgeRef* r) : Base(b, r) {}
};
}  // namespace

std::vector<std::pair<EdgeRef, EdgeRef>> intersecting_edges(const std::vector<const Loop*>& loops,
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
  auto seg_of = [&](const EdgeRef* r) -> const S2& { return segs[static_cast<size_t>(r - base)]; };
  auto callback = [&](const EdgeBox& x, const EdgeBox& y) {
    if (found.size() >= max_results) return;
    const EdgeRef* a = x.handle();
    const EdgeRef* b = y.handle();
    const S2& sa = seg_of(a);
    const S2& sb = seg_of(b);
    if (a->loop == b->loop) {
      const int n = static_cast<int>(loops[static_cast<size_t>(a->loop)]->size());
      const bool neighbours = (a->edge + 1) % n == b->edge || (b->edge + 1) % n == a->edge;
      if (neighbours) {
        // Neighbours share a vertex; they intersect improperly only when collinear
        // and folding back (a spike), i.e. the intersection is a segment.
        if (!CGAL::collinear(sa.source(), sa.target(), sb.target()) ||
            !CGAL::collinear(sa.source(), sa.target(), sb.source()))
          return;
        const auto inter = CGAL::intersection(sa, sb);
        if (!inter || !boost::get<S2>(&*inter)) return;
        found.push_back({*a, *b});
        return;
      }
    }
    if (CGAL::do_intersect(sa, sb)) found.push_back({*a, *b});
  };
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), callback);
  // Deterministic report: order by (loop, edge).
  for (auto& p : found)
    if (std::tie(p.second.loop, p.second.edge) < std::tie(p.first.loop, p.first.edge)) std::swap(p.first, p.second);
  std::sort(found.begin(), found.end(), [](const auto& u, const auto& v) {
    return std::tie(u.first.loop, u.first.edge, u.second.loop, u.second.edge) <
           std::tie(v.first.loop, v.first.edge, v.second.loop, v.second.edge);
  });
  return found;
}

}  // namespace hsi::detail
