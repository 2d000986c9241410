// The CUDA core's entry points: the device check and the factories (the class is
// cuda_newton_core.h; its whole-solve loop is device_newton.cpp).
#include <string>

#include "cuda_newton_core.h"

namespace hsi::cuda {

bool device_available(std::string* why) {
  auto no = [&](const std::string& reason) {
    if (why) *why = reason;
    return false;
  };
  auto text = [](cudaError_t e) { return std::string(cudaGetErrorName(e)) + ", " + cudaGetErrorString(e); };
  try {
    int count = 0;
    cudaError_t e = cudaGetDeviceCount(&count);
    if (e != cudaSuccess) {
      cudaGetLastError();  // leave no error behind for the next CUDA call
      return no("no usable CUDA device (cudaGetDeviceCount: " + text(e) + ")");
    }
    if (count == 0) return no("no CUDA device");
    int device = 0;
    cudaDeviceProp prop{};
    e = cudaGetDevice(&device);
    if (e == cudaSuccess) e = cudaGetDeviceProperties(&prop, device);
    if (e != cudaSuccess) {
      cudaGetLastError();
      return no("CUDA device query failed: " + text(e));
    }
    const std::string name = std::string(prop.name) + " (sm_" + std::to_string(prop.major) + std::to_string(prop.minor) + ")";
    // The kernels exist only for the architectures this was built for.
    e = kernels::loadable();
    if (e != cudaSuccess) {
      cudaGetLastError();
      return no("this build's kernels do not run on " + name + ": " + text(e));
    }
    if (why) *why = name;
    return true;
  } catch (const std::exception& ex) {
    return no(std::string("CUDA device check failed: ") + ex.what());
  }
}

bool set_host_wait(HostWait wait, std::string* why) {
  unsigned flags = 0;
  cudaError_t e = cudaGetDeviceFlags(&flags);
  if (e == cudaSuccess) {
    const unsigned schedule = wait == HostWait::Spin    ? cudaDeviceScheduleSpin
                              : wait == HostWait::Yield ? cudaDeviceScheduleYield
                              : wait == HostWait::Block ? cudaDeviceScheduleBlockingSync
                                                        : cudaDeviceScheduleAuto;
    // cudaGetDeviceFlags reports cudaDeviceMapHost, which cudaSetDeviceFlags does not take back.
    e = cudaSetDeviceFlags((flags & ~static_cast<unsigned>(cudaDeviceScheduleMask | cudaDeviceMapHost)) | schedule);
  }
  if (e != cudaSuccess) {
    if (why) *why = std::string("cudaSetDeviceFlags: ") + cudaGetErrorName(e) + ", " + cudaGetErrorString(e);
    cudaGetLastError();
    return false;
  }
  return true;
}

namespace {
void check_inputs(const MatrixXcd& D, const std::vector<int>& H) {
  if (D.rows() < 1 || D.cols() < 1) throw InputError("hsi::cuda: the basis matrix D is empty");
  if (H.empty()) throw InputError("hsi::cuda: the Hessian sample subset H is empty");
  // cuBLAS and the kernels index with int: |G|·2, |H|·6n and (4n)² must fit.
  if (D.rows() > (1 << 29) || D.cols() > (1 << 13)) throw InputError("hsi::cuda: too many samples or basis functions");
  for (int s : H)
    if (s < 0 || s >= D.rows())
      throw InputError("hsi::cuda: Hessian sample index " + std::to_string(s) + " is outside [0, " + std::to_string(D.rows()) + ")");
}
}  // namespace

std::unique_ptr<NewtonCore> make_newton_core(const MatrixXcd& D, std::vector<int> H) {
  check_inputs(D, H);
  return std::make_unique<CudaNewtonCore>(D, H);
}

std::unique_ptr<NewtonCore> make_newton_core(const ShapeSetup& setup) {
  check_inputs(setup.D_G, setup.H);
  return std::make_unique<CudaNewtonCore>(setup.D_G, setup.H, &setup);
}

}  // namespace hsi::cuda
