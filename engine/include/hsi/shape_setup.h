// Everything the solvers precompute once per shape: cage, samples G and H, the
// reduced spaces, the active basis rows at G, the certifier and the overlap check.
#pragma once

#include <memory>

#include "hsi/certificate.h"
#include "hsi/map_space.h"
#include "hsi/overlap.h"
#include "hsi/scene_io.h"

namespace hsi {

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
};

// From a scene: its cage (user-given or automatic) and its sample settings;
// samples/ratio override the scene's when positive.
std::unique_ptr<ShapeSetup> make_shape_setup(const Scene& scene, int samples = 0, double hessian_ratio = 0);

}  // namespace hsi
