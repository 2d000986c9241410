// The inverse of a map at a point: which point of the rest shape a posed map sends to
// an image point (what a click on the posed shape picks). A triangulation of the shape
// finds the triangle whose image holds the point (the map is locally injective), its
// barycentric coordinates give a first guess, and Newton on f (f_z, f_z̄) refines it to
// round-off, so f(inverse(w)) = w (the guess is kept where Newton would leave the
// triangle's neighbourhood). Within about a mesh edge of the boundary's image, a point
// that no image triangle holds is refused like a point off the shape.
#pragma once

#include <optional>

#include "hsi/harmonic_map.h"
#include "hsi/triangulate.h"

namespace hsi {

struct InverseMapOptions {
  int mesh_vertices = 3000;  // size of the triangulation that finds the triangle
  int newton_steps = 8;      // refinement steps at most (it converges quadratically)
};

class InverseMap {
 public:
  // The cage is the one the maps are over (kept by value); throws InputError for an
  // invalid shape.
  InverseMap(const Shape& shape, const Cage& cage, const InverseMapOptions& options = {});

  // The rest point z of the shape with map(z) = image, or nullopt when no triangle's
  // image holds `image` (a point off the posed shape). The map's image of the mesh is
  // kept until a map with other coefficients is asked about.
  std::optional<cd> rest_point(const HarmonicMap& map, cd image);

  const TriMesh& mesh() const { return mesh_; }

 private:
  Cage cage_;
  InverseMapOptions options_;
  TriMesh mesh_;
  BasisRows rows_;  // C at the mesh's vertices
  double size_ = 1;  // the shape's bounding-box diagonal
  std::optional<HarmonicMap> map_;  // the map f_ belongs to
  VectorXcd f_;
};

}  // namespace hsi
