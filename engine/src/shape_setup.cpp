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

const InterpolationRows& ShapeSetup::interpolation_rows() const {
  std::call_once(lazy_->once, [this] {
    InterpolationRows& r = lazy_->rows;
    BasisRows rows = evaluate_basis(cage, G.points, kBasisC | kBasisD);
    const MatrixXcd& C = rows.C;
    const double count = static_cast<double>(G.size());
    cd cw = 0;
    for (const cd& w : G.points) cw += w;
    cw /= count;
    VectorXcd u(static_cast<Eigen::Index>(G.size()));
    for (Eigen::Index i = 0; i < u.size(); ++i) u(i) = G.points[static_cast<size_t>(i)] - cw;
    r.c_mean = C.colwise().sum() / count;
    r.c_rot = u.conjugate().transpose() * C;  // Σ conj(u_i) C_ij
    r.c_rot_bar = u.transpose() * C;          // Σ u_i C_ij
    r.D.D = std::move(rows.D);
  });
  return lazy_->rows;
}

std::shared_ptr<void> ShapeSetup::shared_backend_data(const std::string& key,
                                                     const std::function<std::shared_ptr<void>()>& make) const {
  std::lock_guard<std::mutex> lock(shared_->mutex);
  std::weak_ptr<void>& slot = shared_->data[key];
  if (std::shared_ptr<void> held = slot.lock()) return held;
  std::shared_ptr<void> made = make();
  slot = made;
  return made;
}

std::unique_ptr<ShapeSetup> make_shape_setup(const Scene& scene, int samples, double hessian_ratio) {
  return std::make_unique<ShapeSetup>(scene.shape, scene_cage(scene), samples > 0 ? samples : scene.samples,
                                      hessian_ratio > 0 ? hessian_ratio : scene.hessian_ratio);
}

}  // namespace hsi
