// The CUDA twin of the CPU Newton core (hsi/newton.h): the same NewtonCore interface,
// in double precision, with every per-sample array resident on the GPU. Only scalars,
// the gradient (4n) and the Hessian (4n × 4n) come back to the host.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "hsi/newton.h"
#include "hsi/shape_setup.h"

namespace hsi::cuda {

// A failed CUDA, cuBLAS or cuSOLVER call; the message names the call and where.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Whether a CUDA device can run this library's kernels. Never throws: on a machine
// without a GPU or driver it returns false and, if `why` is given, says why.
bool device_available(std::string* why = nullptr);

// How host threads wait for this device's work (the CUDA context's scheduling flag;
// cudaSetDeviceFlags): Auto is CUDA's heuristic, which spins while the process has fewer
// contexts than the machine has cores (always, for us): each waiting thread keeps a core
// busy; Yield and Block free it at some latency per wait. (Measured for a batch with as
// many workers as cores, bench_batch --cuda-wait on one H200: no difference.)
enum class HostWait { Auto, Spin, Yield, Block };
// Sets it for the current device, whether or not its context exists yet; false (and
// `why`) where CUDA refuses. Applies to every thread's later waits.
bool set_host_wait(HostWait wait, std::string* why = nullptr);

// D: the active basis rows D(w) at the samples G (|G| × n); H: indices into G (the
// Hessian subset). Uploads D once; throws Error if the device cannot be used and
// InputError on inconsistent input. The core lives on the CUDA device current when it
// is made and, like the CPU core, is not thread-safe.
std::unique_ptr<NewtonCore> make_newton_core(const MatrixXcd& D, std::vector<int> H);

// The same core for a shape's setup (which must outlive it), able to run newton_solve's
// whole certified iteration on the device (NewtonCore::solve) for the setup's two
// spaces and its certifier: Cholesky by cuSOLVER, the safe step, Armijo backtracking
// and the certificate on the GPU, a few scalars back to the host per iteration.
std::unique_ptr<NewtonCore> make_newton_core(const ShapeSetup& setup);

}  // namespace hsi::cuda
