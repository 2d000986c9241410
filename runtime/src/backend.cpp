// The backend factory (see backend.h). The only place that knows whether this build
// has CUDA: HSI_RUNTIME_CUDA is set by runtime/CMakeLists.txt when cuda/ is built.
#include "hsi/runtime/backend.h"
#include "hsi/batch.h"

#include <algorithm>

#include "built.h"
#include "hsi/domain.h"
#include "hsi/lockstep.h"
#if HSI_RUNTIME_CUDA
#include "hsi/cuda/batch_stepper.h"
#include "hsi/cuda/clocks.h"
#include "hsi/cuda/mesh_evaluator.h"
#include "hsi/cuda/newton_core.h"
#endif

namespace hsi::runtime {


const char* const kBackendHelp =
    "Newton core: auto (CUDA when this build has it and a device is present, else the CPU, saying why), cpu or cuda";

const std::vector<std::string>& backend_names() {
  static const std::vector<std::string> names = {"auto", "cpu", "cuda"};
  return names;
}

std::string_view to_string(Backend backend) {
  switch (backend) {
    case Backend::Auto: return "auto";
    case Backend::Cpu: return "cpu";
    case Backend::Cuda: return "cuda";
  }
  return "?";
}

Backend parse_backend(std::string_view name) {
  if (name == "auto") return Backend::Auto;
  if (name == "cpu") return Backend::Cpu;
  if (name == "cuda") return Backend::Cuda;
  std::string valid;
  for (const std::string& n : backend_names()) valid += (valid.empty() ? "" : ", ") + n;
  throw InputError("backend '" + std::string(name) + "' is not one of " + valid);
}

CudaStatus cuda_status() {
  CudaStatus s;
#if HSI_RUNTIME_CUDA
  try {
    s.available = hsi::cuda::device_available(&s.detail);
  } catch (const std::exception& e) {  // device_available never throws; stay safe if that changes
    s.available = false;
    s.detail = e.what();
  }
#else
  s.detail = built::kNoCuda;
#endif
  return s;
}

const char* const kCudaWaitHelp =
    "How host threads wait for the GPU: auto (CUDA's choice: spin, one core busy per waiting thread), spin, yield or block";

const std::vector<std::string>& cuda_wait_names() {
  static const std::vector<std::string> names = {"auto", "spin", "yield", "block"};  // HostWait's order
  return names;
}

std::string set_cuda_wait(std::string_view name) {
  const std::vector<std::string>& names = cuda_wait_names();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) throw InputError("CUDA wait '" + std::string(name) + "' is not one of auto, spin, yield, block");
#if HSI_RUNTIME_CUDA
  std::string why;
  return hsi::cuda::set_host_wait(static_cast<hsi::cuda::HostWait>(it - names.begin()), &why) ? "" : why;
#else
  return built::kNoCuda;
#endif
}

BackendChoice choose_backend(Backend requested, const CudaStatus& cuda) {
  BackendChoice c;
  c.requested = requested;
  switch (requested) {
    case Backend::Cpu:
      c.used = Backend::Cpu;
      break;
    case Backend::Cuda:
      if (!cuda.available) throw BackendUnavailable("--backend cuda: " + cuda.detail);
      c.used = Backend::Cuda;
      c.device = cuda.detail;
      break;
    case Backend::Auto:
      c.used = cuda.available ? Backend::Cuda : Backend::Cpu;
      (cuda.available ? c.device : c.fallback) = cuda.detail;
      break;
  }
  return c;
}

NewtonCoreChoice make_newton_core(const ShapeSetup& setup, Backend requested) {
  // cpu never asks the CUDA runtime anything.
  return make_newton_core(setup, requested, requested == Backend::Cpu ? CudaStatus{} : cuda_status());
}

namespace {

// The one fallback policy of the factories below: the choice for `requested`, then the
// CUDA object (make_cuda) where CUDA was chosen, else the CPU one (make_cpu). A CUDA
// object that cannot be made (out of device memory, say): auto falls back to the CPU
// with the reason, cuda throws BackendUnavailable. `what` names the object in messages.
template <class T, class MakeCuda, class MakeCpu>
std::unique_ptr<T> make_on_backend(Backend requested, const CudaStatus& cuda, const char* what, BackendChoice& choice,
                                   MakeCuda&& make_cuda, MakeCpu&& make_cpu) {
  choice = choose_backend(requested, cuda);
#if HSI_RUNTIME_CUDA
  if (choice.used == Backend::Cuda) {
    try {
      return make_cuda();
    } catch (const hsi::cuda::Error& e) {
      if (requested == Backend::Cuda) throw BackendUnavailable(std::string("--backend cuda: the CUDA ") + what + " could not be made: " + e.what());
      choice.used = Backend::Cpu;
      choice.fallback = std::string("the CUDA ") + what + " could not be made on " + choice.device + ": " + e.what();
      choice.device.clear();
    }
  }
#else
  (void)make_cuda;
  (void)what;
  if (choice.used == Backend::Cuda) throw BackendUnavailable(std::string("--backend cuda: ") + built::kNoCuda);
#endif
  return make_cpu();
}

// What the factories make on CUDA; in a build without it make_on_backend never calls these.
std::unique_ptr<NewtonCore> cuda_core(const ShapeSetup& setup) {
#if HSI_RUNTIME_CUDA
  return hsi::cuda::make_newton_core(setup);
#else
  (void)setup;
  throw BackendUnavailable(std::string("--backend cuda: ") + built::kNoCuda);
#endif
}
std::unique_ptr<MeshEvaluator> cuda_mesh_evaluator(const Cage& cage, std::span<const cd> points, const MeshEvaluatorOptions& o) {
#if HSI_RUNTIME_CUDA
  return std::make_unique<hsi::cuda::MeshEvaluator>(cage, points, o);
#else
  (void)cage, (void)points, (void)o;
  throw BackendUnavailable(std::string("--backend cuda: ") + built::kNoCuda);
#endif
}

// The CUDA image of the boundary for the overlap check: the setup's CPU evaluator's rows at
// the breakpoints uploaded, not evaluated again.
std::unique_ptr<MeshEvaluator> cuda_boundary_evaluator(const ShapeSetup& setup) {
#if HSI_RUNTIME_CUDA
  return std::make_unique<hsi::cuda::MeshEvaluator>(setup.overlap.evaluator());
#else
  (void)setup;
  throw BackendUnavailable(std::string("--backend cuda: ") + built::kNoCuda);
#endif
}

}  // namespace

NewtonCoreChoice make_newton_core(const ShapeSetup& setup, Backend requested, const CudaStatus& cuda, bool with_boundary) {
  NewtonCoreChoice r;
  r.core = make_on_backend<NewtonCore>(
      requested, cuda, "core", r.choice,
      [&] {
        std::unique_ptr<NewtonCore> core = cuda_core(setup);
        if (with_boundary) r.boundary = cuda_boundary_evaluator(setup);
        return core;
      },
      [&] {
        r.boundary.reset();  // a CUDA evaluator made before the fallback is not kept
        return make_cpu_newton_core(setup.D_G, setup.H);
      });
  return r;
}

void set_batch_backend(BatchOptions& o, Backend used, const CudaStatus& cuda) {
  o.make_core = [used, cuda](const ShapeSetup& setup) { return make_newton_core(setup, used, cuda, false).core; };
  o.make_boundary = nullptr;
  if (used == Backend::Cuda)
    o.make_boundary = [](const ShapeSetup& setup) { return cuda_boundary_evaluator(setup); };
}

void set_batch_lockstep(BatchOptions& o, Backend used, int systems) {
  o.lockstep_systems = systems;
#if HSI_RUNTIME_CUDA
  if (used == Backend::Cuda) {
    o.make_lockstep = [](const ShapeSetup& setup, int n) -> std::unique_ptr<LockstepBackend> {
      return hsi::cuda::make_batch_stepper(setup, n);
    };
    return;
  }
#endif
  if (used == Backend::Cuda) throw InputError("this build has no CUDA backend for a lockstep batch");
  o.make_lockstep = [](const ShapeSetup& setup, int n) {
    return make_serial_lockstep_backend(setup, n, [&setup] { return make_cpu_newton_core(setup.D_G, setup.H); });
  };
}

MeshEvaluatorChoice make_mesh_evaluator(const Cage& cage, std::span<const cd> points, Backend requested,
                                        const MeshEvaluatorOptions& options) {
  return make_mesh_evaluator(cage, points, requested, requested == Backend::Cpu ? CudaStatus{} : cuda_status(), options);
}

MeshEvaluatorChoice make_mesh_evaluator(const Cage& cage, std::span<const cd> points, Backend requested, const CudaStatus& cuda,
                                        const MeshEvaluatorOptions& options) {
  MeshEvaluatorChoice r;
  r.evaluator = make_on_backend<MeshEvaluator>(requested, cuda, "mesh evaluator", r.choice,
                                               [&] { return cuda_mesh_evaluator(cage, points, options); },
                                               [&] { return make_cpu_mesh_evaluator(cage, points, options); });
  return r;
}

std::string gpu_clocks() {
#if HSI_RUNTIME_CUDA
  if (!cuda_status().available) return "";
  return hsi::cuda::clocks().describe();
#else
  return "";
#endif
}

std::string describe(const BackendChoice& c) {
  std::string s(to_string(c.used));
  if (!c.device.empty()) s += " (" + c.device + ")";
  if (!c.fallback.empty()) s += " (--backend auto: CUDA not used: " + c.fallback + ")";
  return s;
}

}  // namespace hsi::runtime
