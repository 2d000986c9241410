// The lockstep batch's stepper on the GPU (issue #23): a BatchStepper (hsi/lockstep.h)
// that serves the NewtonStepper calls of S systems of one shape setup (each its own
// targets, point, direction and kept factor; one D, one certifier) with one launch per
// stage for every system of a batch: the per-sample stages as the *_batched kernels
// (newton_kernels.h), the Hessians' products as one ZGEMM over every system's weighted
// rows, the reduced systems as strided-batched GEMMs, the factors as cuSOLVER's
// potrfBatched with our batched triangular solves (dense_cholesky.h), the certificates as
// one DeviceCertifier with a capacity of S; the small one-block kernels (the ridge, the
// step's scalars, the rotation's part of the exact system, the trial point) in their
// batched forms, one launch for neighbouring systems. Each system's loop stays newton_run's (LockstepGroup): every
// decision is the system's own, so a frame's result does not depend on its batch except
// in the last bits of the products' sums (cuBLAS may sum a batch in another order).
//
// For the setup's interpolation space (metric_space) with its certifier and no
// quadratic term: the space every Interpolator frame solves in.
#pragma once

#include <memory>
#include <vector>

#include "hsi/lockstep.h"
#include "hsi/shape_setup.h"

namespace hsi::cuda {

// Also the batch's LockstepBackend (solve_batch, BatchOptions::make_lockstep): its own
// batch, set_targets (system s's target metrics at every sample of G, NewtonCore::
// set_targets; thread safe against serve() for a system with no request in flight, its
// own thread between its solves; done when it returns), the CUDA core's preference for
// exact systems over all of G, and keyframe certificates on the device (serialised with
// serve()).
class DeviceBatchStepper : public BatchStepper, public LockstepBackend {
 public:
  BatchStepper& batch() override { return *this; }
  ExactSamples preferred_exact_samples() const override { return ExactSamples::All; }
  // Device memory the batch holds, bytes (its per-system arrays; D and the certifier's
  // rows are the setup's, shared).
  virtual size_t device_bytes() const = 0;
};

// S = `systems` systems of `setup` (which must outlive the stepper) on the current
// device. Throws InputError for systems outside 1..65,535 and hsi::cuda::Error where
// the device cannot be used.
std::unique_ptr<DeviceBatchStepper> make_batch_stepper(const ShapeSetup& setup, int systems);

}  // namespace hsi::cuda
