// Per-shape precomputation shared by keyframe authoring and interpolation.
#include "hsi/shape_setup.h"

namespace hsi {

ShapeSetup::ShapeSetup(Shape s, Cage c, int samples, double hessian_ratio)
    : shape(std::move(s)),
      cage(std::move(c)),
      G(sample_boundary(shape, samples)),
      H(hessian_subset(G, hessian_ratio, [&] {
        // Each sample gives 4 real equations for 4 real unknowns per cage vertex of a
        // loop (φ, ψ); keep a safety factor of 3 so small holes stay well posed.
        std::vector<int> min_per_loop;
        for (const Loop& l : cage.loops) min_per_loop.push_back(3 * static_cast<int>(l.size()));
        return min_per_loop;
      }())),
      map_space(cage, Gauge::Map),
      metric_space(cage, Gauge::ModuloRigid),
      D_G(map_space.restrict_columns(evaluate_basis(cage, G.points, kBasisD).D)),
      certifier(shape, cage, G),
      overlap(cage, certifier.segments()),
      size(bounding_box(shape).diagonal()) {}

std::unique_ptr<ShapeSetup> make_shape_setup(const Scene& scene, int samples, double hessian_ratio) {
  return std::make_unique<ShapeSetup>(scene.shape, scene_cage(scene), samples > 0 ? samples : scene.samples,
                                      hessian_ratio > 0 ? hessian_ratio : scene.hessian_ratio);
}

}  // namespace hsi
