// The Cauchy cage P and the hole points ρ_i (math.md §1): a polygon per boundary
// loop, offset outward for the outer loop and into the hole for each hole, with far
// fewer vertices than the shape boundary.
#pragma once

#include <vector>

#include "hsi/domain.h"
#include "hsi/samples.h"

namespace hsi {

struct Cage {
  std::vector<Loop> loops;     // loop 0 encloses Ω (counter-clockwise); loop k ≥ 1 lies inside hole k (clockwise)
  std::vector<cd> hole_points; // ρ_i, one per hole, strictly inside hole i

  int hole_count() const { return static_cast<int>(hole_points.size()); }
  int vertex_count() const;  // m: all cage vertices over all loops
  // Index of the first vertex of loop k in the concatenated vertex list.
  int loop_offset(int k) const;
};

struct CageOptions {
  double clearance = 0.06;        // target offset, relative to the shape's bounding-box diagonal
  int max_vertices_per_loop = 32; // decimation stops at this many vertices per loop
  double min_clearance = 0.4;     // decimated edges stay at least this fraction of the offset away
  double hole_clearance = 0.45;   // a hole's offset is at most this fraction of its inscribed radius
};

// Builds the cage from the shape (which must be valid and normalized): Clipper
// offsets each loop, then constrained Visvalingam decimation removes vertices while
// the cage stays simple, keeps its distance from the shape and encloses it.
// ρ_i is the centre of the largest inscribed circle of hole i.
Cage build_cage(const Shape& shape, const CageOptions& options = {});

// Throws InputError if the cage does not fit the shape: wrong loop or hole-point
// count, a loop with < 3 vertices or non-finite coordinates, a cage loop that is
// not simple or crosses another, the outer cage not enclosing the shape, a hole cage
// not inside its hole, a hole point outside its hole or on the cage, or the shape
// boundary closer to the cage than min_distance (relative to the bounding-box diagonal).
void check_cage(const Shape& shape, const Cage& cage, double min_distance = 2e-3);

// Smallest distance from the shape's boundary to the cage, and to the hole points.
double cage_clearance(const Shape& shape, const Cage& cage);

// The inscribed radius from which build_cage always keeps a hole's cage loop at
// check_cage's distance (min_distance of the shape's size `size`): the hole's cage is
// offset hole_clearance·r into it and decimation keeps min_clearance of that offset, so
// r ≥ min_distance·size / (hole_clearance·min_clearance) suffices. A narrower hole may
// still get a cage; below it build_cage can fail with "comes within".
double sufficient_hole_radius(double size, const CageOptions& options = {}, double min_distance = 2e-3);

}  // namespace hsi
