// Everything the solvers precompute once per shape: cage, samples G and H, the
// reduced spaces, the active basis rows at G, the certifier and the overlap check.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "hsi/basis.h"
#include "hsi/certificate.h"
#include "hsi/map_space.h"
#include "hsi/overlap.h"
#include "hsi/scene_io.h"

namespace hsi {

// The basis at G as interpolation needs it beyond D_G (Interpolator: the keyframes'
// metrics, the pose's Procrustes sums), evaluated once per shape on first use. An
// Interpolator built per sequence evaluated these itself, |G| × (m + N) complex rows
// twice: 60 % of its set-up, 150-230 ms on one thread on the bundled scenes, paid again
// by every worker of a batch that met the sequence (issue #23, batched baking).
struct InterpolationRows {
  BasisRows D;  // D rows at G, every column (D only; C and E empty)
  // With w̄ the mean of G and u_i = w_i − w̄: Σ_i C_ij / |G|, Σ_i conj(u_i) C_ij, Σ_i u_i C_ij.
  Eigen::RowVectorXcd c_mean, c_rot, c_rot_bar;
};

struct ShapeSetup {
  Shape shape;
  Cage cage;
  BoundarySamples G;
  std::vector<int> H;
  MapSpace map_space;     // Gauge::Map: keyframes (f itself matters)
  MapSpace metric_space;  // Gauge::ModuloRigid: interpolation (only the metric matters)
  MatrixXcd D_G;          // active D rows at G (the same active columns in both gauges)
  Certifier certifier;
  OverlapChecker overlap;  // self-crossings of f(∂Ω) at the certifier's breakpoints (overlap.h)
  double size = 1;        // bounding-box diagonal of the shape

  ShapeSetup(Shape shape, Cage cage, int samples, double hessian_ratio);

  // InterpolationRows, evaluated by the first call (others wait for it; safe from many
  // threads at once), then kept for the setup's life: |G| × (m + N) complex, as much
  // memory as D_G (an Interpolator held the same rows only while it was made; a setup
  // that never interpolates, e.g. the viewer's authoring, never evaluates them).
  const InterpolationRows& interpolation_rows() const;

  // Data a backend derives from this setup once and shares between the objects it makes
  // for it (the CUDA backend's device copies of D_G and of the certifier's rows, one per
  // GPU, instead of one per Newton core): the data held under `key` while anyone still
  // holds it, else what make() returns (kept under `key`). The setup keeps only a weak
  // reference, so the data goes with its last holder, never after the setup. Safe from
  // many threads at once; make() runs with the key's entry locked (callers of other keys
  // of this setup wait too) and may throw (nothing is kept).
  std::shared_ptr<void> shared_backend_data(const std::string& key, const std::function<std::shared_ptr<void>()>& make) const;

 private:
  struct Lazy {
    std::once_flag once;
    InterpolationRows rows;
  };
  struct Shared {
    std::mutex mutex;
    std::map<std::string, std::weak_ptr<void>> data;
  };
  std::unique_ptr<Lazy> lazy_ = std::make_unique<Lazy>();
  std::unique_ptr<Shared> shared_ = std::make_unique<Shared>();
};

// From a scene: its cage (user-given or automatic) and its sample settings;
// samples/ratio override the scene's when positive.
std::unique_ptr<ShapeSetup> make_shape_setup(const Scene& scene, int samples = 0, double hessian_ratio = 0);

}  // namespace hsi
