// The CUDA mesh evaluator's kernel (see mesh_kernels.h): a fused GEMV of the cached
// basis rows against [φ | ψ], memory-bound, one launch per map.
#include "mesh_kernels.h"

#include <algorithm>

namespace hsi::cuda::kernels {
namespace {

// 128 threads a block: 10k points already spread over ~80 SMs (the kernel is bound by
// reading the rows, so it wants many SMs issuing loads, not large blocks).
constexpr int kThreads = 128;

__device__ __forceinline__ void mul_add(double2& acc, double2 a, double2 b) {
  acc.x = fma(a.x, b.x, fma(-a.y, b.y, acc.x));
  acc.y = fma(a.x, b.y, fma(a.y, b.x, acc.y));
}

__global__ void __launch_bounds__(kThreads) mesh_values_kernel(long long P, int M, const double2* __restrict__ C,
                                                               const double2* __restrict__ D,
                                                               const double2* __restrict__ coef, double2* __restrict__ out) {
  const long long p = static_cast<long long>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (p >= P) return;
  double2 a = make_double2(0, 0), b = make_double2(0, 0);
#pragma unroll 4
  for (int j = 0; j < M; ++j) {  // unrolled: several rows' loads in flight per thread
    const double2 c = C[static_cast<long long>(j) * P + p];
    mul_add(a, c, coef[j]);
    mul_add(b, c, coef[M + j]);
  }
  out[p] = make_double2(a.x + b.x, a.y - b.y);  // Cφ + conj(Cψ)
  if (D) {
    double2 fz = make_double2(0, 0), fzb = make_double2(0, 0);
#pragma unroll 4
    for (int j = 0; j < M; ++j) {
      const double2 d = D[static_cast<long long>(j) * P + p];
      mul_add(fz, d, coef[j]);
      mul_add(fzb, d, coef[M + j]);
    }
    out[P + p] = fz;
    out[2 * P + p] = fzb;
  }
}

}  // namespace

cudaError_t mesh_values(long long P, int M, const double2* C, const double2* D, const double2* coef, double2* out,
                        cudaStream_t stream) {
  if (P <= 0) return cudaSuccess;
  const long long blocks = (P + kThreads - 1) / kThreads;
  mesh_values_kernel<<<static_cast<unsigned>(std::min<long long>(blocks, 0x7fffffffLL)), kThreads, 0, stream>>>(P, M, C, D, coef,
                                                                                                               out);
  return cudaGetLastError();
}

}  // namespace hsi::cuda::kernels
