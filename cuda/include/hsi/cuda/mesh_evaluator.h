// f at a fixed set of points (a mesh's vertices) on the GPU from cached basis rows: the
// CUDA twin of the CPU reference (hsi/mesh_evaluator.h). The rows C (and D) are
// evaluated on the host once and uploaded; per map the coefficients [φ | ψ] (2(m + N)
// complex) go up and one kernel evaluates every point (a fused GEMV). runtime/'s
// factory (hsi/runtime/backend.h) makes it by backend name.
#pragma once

#include <memory>
#include <span>

#include "hsi/mesh_evaluator.h"

namespace hsi::cuda {

class MeshEvaluator final : public hsi::MeshEvaluator {
 public:
  // Throws hsi::cuda::Error if the device cannot be used or cannot hold the rows
  // (mesh_evaluator_bytes), InputError as make_cpu_mesh_evaluator.
  MeshEvaluator(const Cage& cage, std::span<const cd> points, const MeshEvaluatorOptions& options = {});
  // The same evaluator from the rows `source` keeps on the host (hsi::MeshEvaluator::rows:
  // the CPU evaluator's), uploaded instead of evaluated again (issue #23: a batch worker's
  // image of the boundary evaluated its ~10k breakpoints' rows on its one thread, 0.3 s a
  // worker). With options.derivatives the source must have them. InputError where the
  // source keeps no rows on the host.
  MeshEvaluator(const hsi::MeshEvaluator& source, const MeshEvaluatorOptions& options = {});
  ~MeshEvaluator() override;
  MeshEvaluator(const MeshEvaluator&) = delete;
  MeshEvaluator& operator=(const MeshEvaluator&) = delete;

  const char* name() const override { return "cuda"; }
  std::size_t size() const override;
  bool derivatives() const override;
  // enqueue(), then the values copied to the host; returns when they are in `out`.
  void evaluate(const HarmonicMap& map, MapValues& out) override;

  // For a consumer on the device (and the benchmark's device-only time): starts the
  // evaluation of `map` on the evaluator's stream and returns; synchronize() waits for it.
  void enqueue(const HarmonicMap& map);
  void synchronize();
  // Device memory: f at every point, then (with derivatives) f_z, then conj f_zbar;
  // size() values each. Valid after synchronize() until the next enqueue().
  const cd* device_values() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hsi::cuda
