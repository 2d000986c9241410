// Global overlap (issue #20): does the image of the shape's boundary cross itself?
//
// A certified frame is locally injective (certificate.h), but a harmonic map can
// still fold one part of the shape over another (a jaw drawn over a leg): the map is
// then not globally injective and two layers of the shape cover the same place. For
// a locally injective map on Ω that is the case exactly when the image of ∂Ω is not
// a set of disjoint simple loops, so that is what is looked for here.
//
// What is checked, exactly: f is evaluated at the boundary breakpoints, i.e. the
// shape's polygon vertices plus the boundary samples G (the points the certificate
// breaks ∂Ω at, certificate_segments()), and the image polylines through these
// points, one closed polyline per loop, are tested for intersections with exact
// orientation predicates (CGAL, via cgal_geometry.h): any two segments of any loops
// (a loop against itself, the outer loop against a hole, hole against hole), other
// than the two neighbours of one loop meeting at their shared point (those are
// reported only when they fold back onto each other along a line). A touching counts
// like a crossing. Tolerance: an image point within 1e-9 of the image's size (its
// bounding box's diagonal) of the last one kept on its loop is merged into it: a
// sample a hair's width from a polygon vertex gives a segment whose image round-off
// can fold back on its neighbours (seen on bar_holes: one "crossing" of two edges at
// their shared corner in a certified frame), and nothing visible is that small. Candidate pairs come from a hierarchy of bounding
// boxes over each loop's segments in their order (exact coordinate extremes,
// compared closed, so no intersecting pair is missed), each decided by the exact
// predicates: about O(B log B) for B breakpoints on a boundary's image. The hierarchy's
// shape is built once per checker over the breakpoints' fixed order along their loops;
// a check only refits its boxes to the image (O(B)) and walks it, allocating nothing
// (issue #23: in a CUDA frame the search runs on a thread of its own, beside the next
// frame's solve, interpolation.h). f at the breakpoints comes from basis rows cached
// once (mesh_evaluator.h).
//
// What is NOT checked: the curve f(∂Ω) between two breakpoints is replaced by the
// chord. A crossing of the true curves that the chords miss (two image arcs that
// brush past each other by less than the chords' sag), or a chord crossing that the
// curves do not have, is possible; "0 crossings" is a sampled verdict at the
// breakpoints, not a proof. With |G| = 10000 samples the chords are short against
// any visible overlap.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "hsi/certificate.h"
#include "hsi/harmonic_map.h"
#include "hsi/mesh_evaluator.h"

namespace hsi {

struct OverlapResult {
  bool checked = false;  // false: no check ran (the result says nothing)
  int crossings = 0;     // intersecting pairs of image segments (0: no overlap found)
  int points = 0;        // breakpoints evaluated
  // The first crossing in (loop, polyline segment) order: the shape's loops (0 the
  // outer loop, k hole k) and the polygon edges (of Shape::loop) the two crossing
  // image segments lie on, and the image point where they cross. -1 when none.
  int loop_a = -1, edge_a = -1, loop_b = -1, edge_b = -1;
  cd point{0, 0};

  bool overlaps() const { return crossings > 0; }
};

// "overlaps itself: the image of the outer loop edge 3 crosses hole 1 edge 7 at
// (0.25, 1.5) (2 crossings)"; "no self-crossing of the boundary's image (checked at
// 11234 breakpoints)"; "not checked".
std::string describe(const OverlapResult& result);

namespace detail {
struct OverlapLayout;   // the loops' slots and their box hierarchy (overlap.cpp)
struct OverlapScratch;  // one search's polylines and boxes (overlap.cpp)
}  // namespace detail

// Precomputed per shape and cage: the breakpoints and f there from basis rows cached
// once (the CPU MeshEvaluator, mesh_evaluator.h), so that a check costs one product of
// the cached rows with the map's coefficients plus the crossing search; and the box
// hierarchy over the breakpoints' loops, built once here and only refit per check
// (issue #23: the breakpoints keep their order along their loops from frame to frame).
class OverlapChecker {
 public:
  // Scratch space of check_points (the search's polylines and boxes), sized on its first
  // use and reused after, so that a check allocates nothing. check_points is const and
  // runs on several threads at once (the batch's workers, a sequence's crossing thread),
  // so the workspace is the caller's: one per thread, never shared by two at a time.
  class Workspace {
   public:
    Workspace();
    ~Workspace();
    Workspace(Workspace&&) noexcept;
    Workspace& operator=(Workspace&&) noexcept;
    detail::OverlapScratch& scratch() { return *scratch_; }

   private:
    std::unique_ptr<detail::OverlapScratch> scratch_;
  };

  OverlapChecker(const Cage& cage, const CertificateSegments& breakpoints);
  // Needs the map's full coefficients (basis_size(cage) each); throws InputError otherwise.
  OverlapResult check(const HarmonicMap& map) const;
  // f at the breakpoints, loop by loop as breakpoints().points: the image check() tests.
  VectorXcd image(const HarmonicMap& map) const;
  // The same into out.f, reusing its storage.
  void image(const HarmonicMap& map, MapValues& out) const;
  // The same test on image points already evaluated at the breakpoints (loop by loop,
  // as breakpoints().points), e.g. by a MeshEvaluator of another backend made for them.
  OverlapResult check_points(std::span<const cd> image, Workspace& workspace) const;
  OverlapResult check_points(std::span<const cd> image) const;  // with a workspace of its own (allocates)
  // The search as it was before the hierarchy was kept (issue #23): the polylines and a
  // box hierarchy over them made per call (detail::intersecting_edges, itself tested
  // against CGAL's box sweep). The same result for every input; the reference the tests
  // and bench_interpolation compare check_points against.
  OverlapResult check_points_reference(std::span<const cd> image) const;
  const CertificateSegments& breakpoints() const { return seg_; }
  // The CPU evaluator of f at the breakpoints (its rows, MeshEvaluator::rows, make another
  // backend's evaluator of the image without evaluating the basis again).
  const MeshEvaluator& evaluator() const { return *f_; }

 private:
  CertificateSegments seg_;
  // f at the breakpoints. The CPU evaluator keeps no state between calls (evaluate only
  // writes its output), so check() stays const and safe to call from several threads.
  std::shared_ptr<MeshEvaluator> f_;
  std::shared_ptr<const detail::OverlapLayout> layout_;  // read only after construction
};

// The same test for image polylines given directly (closed, one per loop; edge i
// joins vertex i to vertex i + 1): crossings counted as above, edges reported as
// polyline segment indices. For tests and for maps evaluated elsewhere.
OverlapResult polyline_overlap(const std::vector<Loop>& loops);
// The same by the reference search (OverlapChecker::check_points_reference).
OverlapResult polyline_overlap_reference(const std::vector<Loop>& loops);

}  // namespace hsi
