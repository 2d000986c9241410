// Dense evaluation of a harmonic map on the GPU (shaders/dense_eval.comp): f, f_z,
// conj(f_zbar) and the per-point distortion fields at a list of points or on a
// regular grid, evaluated straight from the cage (math.md §2) so memory stays
// O(points + cage). hsi::evaluate_map is the CPU reference it is tested against.
//
// Precision: double when the device has shaderFloat64 (lavapipe and most desktop
// GPUs do), agreeing with the CPU to ~1e-12 relative to the field's magnitude (the
// tests demand 1e-9). The float fallback agrees to ~1e-5 relative (tests: 1e-4;
// near the cage, where the basis is large, float loses more).
//
// Output layout. On the GPU, one storage buffer per field, indexed by point (grid
// points row-major: index = j * width + i, row j at y = origin.y + j dy), with
// Real = double or float:
//   binding 3  Real2 f[]            image point, ready to draw as a vertex position
//   binding 4  Real2 f_z[]
//   binding 5  Real2 fzbar_conj[]   conj(f_zbar)
//   binding 6  Real4 fields[]       (σ1, σ2, σ1/σ2, symmetric Dirichlet)
//   binding 7  uint  flags[]        kFlag* bits below
// On the host, DenseField holds the same as structure-of-arrays vectors.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "hsi/cage.h"
#include "hsi/compute/compute_pipeline.h"
#include "hsi/compute/vulkan_context.h"
#include "hsi/harmonic_map.h"

namespace hsi::compute {

enum class Precision {
  kAuto,    // double if the device has shaderFloat64, else float
  kDouble,  // double or throw VulkanError
  kFloat,   // float (e.g. to test the fallback, or for speed on GPUs with slow fp64)
};

struct DenseEvalOptions {
  Precision precision = Precision::kAuto;
  // Larger point sets are evaluated in passes of at most this many points (and at
  // most what the device's maxStorageBufferRange allows), so GPU memory is bounded.
  uint32_t max_points_per_pass = 1u << 20;
  // With a mask shape: points outside it are not evaluated; their fields are NaN,
  // det_sign 0 (for drawing only the shape, at a fraction of the cost).
  bool skip_outside = false;
  // Copy results through separate host-cached readback buffers even where the
  // device-local output is host-readable (as on discrete GPUs; lets lavapipe test it).
  bool force_staging = false;
};

// GPU flag bits (binding 7); the host exposes them as DenseField::inside / det_sign.
inline constexpr uint32_t kFlagInside = 1u, kFlagDetPositive = 2u, kFlagDetNegative = 4u, kFlagEvaluated = 8u;

// A regular grid: point (i, j) = (origin.x + i dx, origin.y + j dy), 0 <= i < width,
// 0 <= j < height, where (dx, dy) = (spacing.real(), spacing.imag()) > 0.
struct Grid {
  cd origin;
  cd spacing;
  int width = 0, height = 0;

  size_t size() const { return static_cast<size_t>(width) * static_cast<size_t>(height); }
  // The exact arithmetic the shader uses, so CPU references see the same points.
  cd point(int i, int j) const {
    return {origin.real() + static_cast<double>(i) * spacing.real(),
            origin.imag() + static_cast<double>(j) * spacing.imag()};
  }
  std::vector<cd> points() const;  // all points, row-major

  // width × height cell centres tiling the box (a pixel grid over it).
  static Grid covering(const BoundingBox& box, int width, int height);
  // Square cells, the longer side of the box split into `max_side` cells.
  static Grid covering(const BoundingBox& box, int max_side);
};

// Per-point results, structure of arrays; each vector has size() entries.
struct DenseField {
  int width = 0, height = 0;  // grid dimensions; 0 × 0 for a point list
  bool double_precision = true;
  std::vector<cd> f, f_z, fzbar_conj;  // f_z = Σ D φ, fzbar_conj = conj(f_zbar) = Σ D ψ
  std::vector<double> sigma1;          // |f_z| + |f_zbar|
  std::vector<double> sigma2;          // |f_z| − |f_zbar| (negative where the map folds)
  std::vector<double> distortion;      // conformal distortion σ1/σ2 (negative or ±inf where det J <= 0)
  std::vector<double> dirichlet;       // symmetric Dirichlet ½(σ1² + σ1⁻² + σ2² + σ2⁻²)
  std::vector<int8_t> det_sign;        // sign of det J = |f_z|² − |f_zbar|²: +1, −1, 0 (zero or not evaluated)
  std::vector<uint8_t> inside;         // 1 if inside the mask shape; empty when no shape was given

  size_t size() const { return f.size(); }
};

// Host wall-clock times of the last evaluate_* call, in milliseconds.
struct DenseEvalStats {
  double upload_ms = 0;    // writing inputs to GPU-visible memory
  double gpu_ms = 0;       // submit to fence (dispatch + copies), summed over passes
  double device_ms = 0;    // GPU execution time of the same (timestamps), summed; < 0: not available
  double readback_ms = 0;  // copying results out and converting to DenseField
  int passes = 0;
};

class DenseEvaluator {
 public:
  // Builds the pipeline for the chosen precision. The context must outlive this.
  explicit DenseEvaluator(const Context& context, const DenseEvalOptions& options = {});

  bool double_precision() const { return double_; }
  const DenseEvalStats& last_stats() const { return stats_; }

  // The map must have m + N coefficients in both φ and ψ (else hsi::InputError);
  // points must avoid the cage and the hole points (the basis is singular there).
  DenseField evaluate_points(const Cage& cage, const HarmonicMap& map, std::span<const cd> points);
  // With a shape, DenseField::inside is its even-odd mask, computed on the GPU with
  // the arithmetic of hsi::point_in_shape (identical results in double precision).
  DenseField evaluate_grid(const Cage& cage, const HarmonicMap& map, const Grid& grid,
                           const Shape* mask_shape = nullptr);

  // For passes that consume the fields on the GPU (the renderer draws f directly):
  // uploads the inputs and records the point-list evaluation of all `points` into
  // `cmd` as one dispatch, without reading anything back. The results land in
  // device_output(k), k = 0..4 for bindings 3..7 above (f, f_z, fzbar_conj, fields,
  // flags). The caller submits `cmd`, puts a barrier (compute shader write -> its
  // reads) after this, and calls no other evaluate_* / record_* before the
  // submission has finished. Throws InputError if the points need more than one pass.
  void record_points(VkCommandBuffer cmd, const Cage& cage, const HarmonicMap& map, std::span<const cd> points);
  // The same for a grid (e.g. a frame's dense distortion field that a later pass
  // consumes on the GPU): one dispatch into `cmd`, results left in device_output(k).
  // Throws InputError if the grid needs more than one pass (raise
  // DenseEvalOptions::max_points_per_pass for grids over 2^20 points).
  void record_grid(VkCommandBuffer cmd, const Cage& cage, const HarmonicMap& map, const Grid& grid,
                   const Shape* mask_shape = nullptr);
  const Buffer& device_output(int k) const { return out_[k]; }

 private:
  struct Job;
  DenseField run(const Job& job);
  void ensure_capacity(uint32_t points);

  const Context* context_;
  DenseEvalOptions options_;
  bool double_ = true;
  ComputePipeline pipeline_;
  DescriptorSet set_;
  uint32_t capacity_ = 0;  // points per pass the buffers below hold
  Buffer loops_, geom_, points_;
  Buffer row_count_, row_cross_;  // a grid mask's crossings per row (dense_eval.comp)
  Buffer out_[5];       // f, f_z, fzbar_conj, fields, flags (device-local)
  Buffer readback_[5];  // host copies, where out_ is not host-readable
  DenseEvalStats stats_;
};

}  // namespace hsi::compute
