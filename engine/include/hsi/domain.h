// The domain Ω: one outer boundary loop and any number of hole loops (math.md §1).
// Shapes are validated before use; every refusal names the loop and the vertex or
// edge at fault, so a user can find the problem in their file.
#pragma once

#include <complex>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace hsi {

using cd = std::complex<double>;

// A closed polygon; the last vertex connects back to the first (not repeated).
using Loop = std::vector<cd>;

struct Shape {
  Loop outer;               // counter-clockwise after normalize()
  std::vector<Loop> holes;  // clockwise after normalize()

  int loop_count() const { return 1 + static_cast<int>(holes.size()); }
  // Loop 0 is the outer loop, loop k ≥ 1 is hole k−1.
  const Loop& loop(int k) const { return k == 0 ? outer : holes[static_cast<size_t>(k - 1)]; }
  Loop& loop(int k) { return k == 0 ? outer : holes[static_cast<size_t>(k - 1)]; }
};

// Thrown for any input the engine refuses; what() says what and where.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Writes bytes to path through a temporary file and a rename, so a failed write
// never leaves a partial file that looks complete. Throws InputError naming path.
void write_file_atomic(const std::filesystem::path& path, const std::string& bytes);

// "outer loop" or "hole 2" (1-based for people), used in every message.
std::string loop_name(int loop);

double signed_area(const Loop& loop);     // > 0 for counter-clockwise
double perimeter(const Loop& loop);
double area(const Shape& shape);          // outer area minus hole areas
bool point_in_loop(const Loop& loop, cd p);  // even-odd rule; boundary points undefined
bool point_in_shape(const Shape& shape, cd p);
// Distance from p to the segment [a, b], and to a whole loop's boundary.
double segment_distance(cd p, cd a, cd b);
double loop_distance(const Loop& loop, cd p);
double boundary_distance(const Shape& shape, cd p);
// Smallest distance between two segments (0 if they intersect).
double segment_segment_distance(cd a0, cd a1, cd b0, cd b1);

struct BoundingBox {
  cd lo, hi;
  double diagonal() const { return std::abs(hi - lo); }
};
BoundingBox bounding_box(const Loop& loop);
BoundingBox bounding_box(const Shape& shape);

// Splits every edge longer than max_edge into equal parts (points stay on the
// edges), so that a deformed outline bends along long straight runs too.
Loop subdivide_edges(const Loop& loop, double max_edge);

// Orients the outer loop counter-clockwise and the holes clockwise.
Shape normalize(Shape shape);

// Throws InputError naming the first problem found: fewer than 3 vertices, a
// non-finite coordinate, duplicate consecutive vertices (zero-length edge), a loop
// with (near) zero area, self-intersection, loops crossing each other, a hole
// outside the outer loop, a hole inside another hole. Orientation is not checked
// (call normalize() first if it matters).
void validate(const Shape& shape);

// Centre and radius of (approximately, to rel_tol of the loop's size) the largest
// circle inside a simple loop: the "pole of inaccessibility" by quadtree search.
struct Circle {
  cd center;
  double radius;
};
Circle largest_inscribed_circle(const Loop& loop, double rel_tol = 1e-3);

}  // namespace hsi
