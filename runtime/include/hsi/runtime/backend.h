// The one backend factory (issue #21): which Newton core (hsi/newton.h) runs a solve,
// picked by name (auto | cpu | cuda) here and nowhere else. auto takes the CUDA core
// where this build has one and a device can run it, else the CPU reference, and says
// why it fell back (as tiny-cuda-nn's create_network does); cuda that cannot be had is
// an error with that reason. Front-ends (the CLI, the viewer, the C API, benchmarks)
// parse the name, call make_newton_core and print the fallback.
#pragma once

#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "hsi/mesh_evaluator.h"
#include "hsi/newton.h"
#include "hsi/shape_setup.h"

namespace hsi {
struct BatchOptions;  // hsi/batch.h
}

namespace hsi::runtime {

enum class Backend { Auto, Cpu, Cuda };

// "auto", "cpu", "cuda": every name parse_backend accepts, in this order (for an
// option's check, e.g. CLI::IsMember(backend_names())).
const std::vector<std::string>& backend_names();
std::string_view to_string(Backend backend);
// Throws InputError naming `name` and the valid names for anything else.
Backend parse_backend(std::string_view name);
// The help text of every --backend option (the CLI's commands, the viewer).
extern const char* const kBackendHelp;

// The CUDA backend can be neither built nor run here, or it can.
struct CudaStatus {
  bool available = false;
  std::string detail;  // available: the device ("NVIDIA H100 (sm_90)"); else why not
};
// Never throws: "this hsi was built without CUDA", "no CUDA device (cudaGetDeviceCount: ...)", ...
CudaStatus cuda_status();

// How host threads wait for the GPU (hsi::cuda::HostWait): auto (CUDA's heuristic: spin,
// a core busy per waiting thread), spin, yield or block; cuda_wait_names() in that order
// (for an option's check). bench_batch --cuda-wait compares them: on one H200 with 16
// workers on 16 cores they made no difference (2,131-2,188 frames/s, README). "" when
// set, else why not (no CUDA in this build, or CUDA refused). Throws InputError for a
// name not among these four.
const std::vector<std::string>& cuda_wait_names();
std::string set_cuda_wait(std::string_view name);
extern const char* const kCudaWaitHelp;

// What a request gave.
struct BackendChoice {
  Backend requested = Backend::Auto;
  Backend used = Backend::Cpu;  // Cpu or Cuda, never Auto
  std::string fallback;         // why auto did not use CUDA; empty when it did, or for cpu / cuda
  std::string device;           // with Cuda: the device
};

// cuda asked for but not to be had: the reason, worded for a front-end's message.
class BackendUnavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The decision alone, for a CUDA status (tests give any): cpu gives cpu; cuda gives
// cuda or throws BackendUnavailable ("--backend cuda: <why>"); auto gives cuda where
// available, else cpu with `fallback` set to why.
BackendChoice choose_backend(Backend requested, const CudaStatus& cuda);

// The core for a request, as used by `hsi interpolate`, `hsi compare`, hsi-viewer, the
// C API and bench_stress. The CUDA core is made for `setup` (which must outlive it) and
// runs whole solves on the device; if making it fails (out of device memory, say), auto
// falls back to the CPU with that reason and cuda throws BackendUnavailable.
struct NewtonCoreChoice {
  std::unique_ptr<NewtonCore> core;
  // f at setup.overlap's breakpoints on the same backend (the image each frame's overlap
  // check tests): the Interpolator's `boundary`. Null on the CPU (the setup's own is used).
  std::unique_ptr<MeshEvaluator> boundary;
  BackendChoice choice;
};
NewtonCoreChoice make_newton_core(const ShapeSetup& setup, Backend requested);
// The same, the CUDA status already known (a front-end that makes many cores asks once).
// with_boundary = false: no `boundary` evaluator (for callers that take the core alone: a
// batch's core factory, authoring). The CUDA boundary evaluator is made from the rows the
// setup's overlap checker keeps on the host (OverlapChecker::evaluator), uploaded.
NewtonCoreChoice make_newton_core(const ShapeSetup& setup, Backend requested, const CudaStatus& cuda, bool with_boundary = true);

// A batch's factories on the backend `used` (BatchOptions::make_core, make_boundary), as
// hsi bake, the C API's batch and bench_batch set them: each worker's Newton core alone,
// and on CUDA f at the setup's overlap breakpoints on the GPU, one evaluator per worker
// and shape, its rows uploaded from the setup's CPU evaluator (on the CPU none: every
// Interpolator uses the setup's own evaluator).
void set_batch_backend(BatchOptions& options, Backend used, const CudaStatus& cuda);
// The batch in lockstep (BatchOptions::make_lockstep, issue #23) with groups of up to
// `systems` sequences per setup: on CUDA each group's calls served by the device's batched
// stepper (hsi/cuda/batch_stepper.h); on the CPU by each system's own CPU core, one after
// another (the reference: the same frames as the workers'). The boundary factory stays
// set_batch_backend's.
void set_batch_lockstep(BatchOptions& options, Backend used, int systems);

// f at a fixed set of points (a mesh's vertices) from cached basis rows
// (hsi/mesh_evaluator.h), on the backend a request gives, decided as for the Newton
// core: the CUDA evaluator keeps the rows on the GPU; if making it fails (the rows do
// not fit in device memory, say), auto falls back to the CPU with that reason and cuda
// throws BackendUnavailable.
struct MeshEvaluatorChoice {
  std::unique_ptr<MeshEvaluator> evaluator;
  BackendChoice choice;
};
MeshEvaluatorChoice make_mesh_evaluator(const Cage& cage, std::span<const cd> points, Backend requested,
                                        const MeshEvaluatorOptions& options = {});
MeshEvaluatorChoice make_mesh_evaluator(const Cage& cage, std::span<const cd> points, Backend requested, const CudaStatus& cuda,
                                        const MeshEvaluatorOptions& options = {});

// The GPU's clocks now, in one line for a report ("SM 1980 MHz (max 1980 MHz), memory
// 2619 MHz, read by NVML" or, where NVML cannot be loaded, the device's peak clock from
// cudaDevAttrClockRate, named as such); empty where this build or machine has no CUDA device.
std::string gpu_clocks();

// One line for a log: "cpu", "cuda (NVIDIA H100 (sm_90))" or "cpu (CUDA not used: <why>)".
std::string describe(const BackendChoice& choice);

}  // namespace hsi::runtime
