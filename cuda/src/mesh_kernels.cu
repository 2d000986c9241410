// The CUDA mesh evaluator's kernel (see mesh_kernels.h): a fused GEMV of the cached
// basis rows against [φ | ψ], memory-bound, one launch per map.
#include "mesh_kernels.h"

#include <algorithm>

namespace hsi::cuda::kernels {
namespace {

// A block is 32 points × kSlices row slices: thread (x, y) sums rows y, y + kSlices, …
// of point x, then the slices are added in order (deterministic). One thread per point
// summing all M rows left ~80 blocks of 128 threads with one load chain each: 31.5 µs for
// bar_holes' 10,487 breakpoints × 84 rows on an H200 by Nsight Compute (bench/results/
// ncu_hsi_interpolate_bar_holes_h200.txt), against ~3.5 µs to read the rows once.
constexpr int kPoints = 32, kSlices = 8;

__device__ __forceinline__ void mul_add(double2& acc, double2 a, double2 b) {
  acc.x = fma(a.x, b.x, fma(-a.y, b.y, acc.x));
  acc.y = fma(a.x, b.y, fma(a.y, b.x, acc.y));
}

__global__ void __launch_bounds__(kPoints* kSlices) mesh_values_kernel(long long P, int M, const double2* __restrict__ C,
                                                                       const double2* __restrict__ D,
                                                                       const double2* __restrict__ coef, double2* __restrict__ out) {
  __shared__ double2 part[4][kSlices][kPoints];
  const int tx = static_cast<int>(threadIdx.x), ty = static_cast<int>(threadIdx.y);
  const long long p = static_cast<long long>(blockIdx.x) * kPoints + tx;
  const bool inside = p < P;
  double2 a = make_double2(0, 0), b = make_double2(0, 0), fz = make_double2(0, 0), fzb = make_double2(0, 0);
  if (inside) {
#pragma unroll 2
    for (int j = ty; j < M; j += kSlices) {
      const double2 c = C[static_cast<long long>(j) * P + p];
      mul_add(a, c, coef[j]);
      mul_add(b, c, coef[M + j]);
      if (D) {
        const double2 d = D[static_cast<long long>(j) * P + p];
        mul_add(fz, d, coef[j]);
        mul_add(fzb, d, coef[M + j]);
      }
    }
  }
  part[0][ty][tx] = a;
  part[1][ty][tx] = b;
  part[2][ty][tx] = fz;
  part[3][ty][tx] = fzb;
  __syncthreads();
  // Thread (x, 0) adds both halves of the value, Cφ and Cψ; threads (x, 2), (x, 3) add f_z and
  // f_z̄. The others have nothing left to do.
  if (ty == 1 || ty >= 4 || !inside || (ty >= 2 && !D)) return;
  double2 t = make_double2(0, 0);
  for (int y = 0; y < kSlices; ++y) {
    t.x += part[ty][y][tx].x;
    t.y += part[ty][y][tx].y;
  }
  if (ty == 0) {
    double2 cb = make_double2(0, 0);
    for (int y = 0; y < kSlices; ++y) {
      cb.x += part[1][y][tx].x;
      cb.y += part[1][y][tx].y;
    }
    out[p] = make_double2(t.x + cb.x, t.y - cb.y);  // Cφ + conj(Cψ)
  } else if (ty == 2) {
    out[P + p] = t;
  } else if (ty == 3) {
    out[2 * P + p] = t;
  }
}

}  // namespace

cudaError_t mesh_values(long long P, int M, const double2* C, const double2* D, const double2* coef, double2* out,
                        cudaStream_t stream) {
  if (P <= 0) return cudaSuccess;
  const long long blocks = (P + kPoints - 1) / kPoints;
  if (blocks > 0x7fffffffLL) return cudaErrorInvalidValue;
  mesh_values_kernel<<<static_cast<unsigned>(blocks), dim3(kPoints, kSlices), 0, stream>>>(P, M, C, D, coef, out);
  return cudaGetLastError();
}

}  // namespace hsi::cuda::kernels
