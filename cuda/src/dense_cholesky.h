// The Newton system's dense Cholesky factor and solve on the GPU (issue #23), in place
// of cuSOLVER's potrf/potrs, which at our sizes (m = 4n or 4n + 1, about 50 to 1,700,
// mostly 150 to 400) cost ~150 + ~65 us per Newton iteration in launch and latency more
// than in arithmetic. FP64, lower triangle, column-major, one right-hand side. Both
// calls only enqueue kernels on `stream`: no allocation, no host synchronisation and no
// host read of device data, so they can be captured into a CUDA graph.
#pragma once

#include <cuda_runtime.h>

namespace hsi::cuda::kernels {

// Tile edge of the blocked factorisation and of the solve's substitutions.
constexpr int kCholeskyTile = 32;

// Up to this order the factorisation is ONE kernel: a cluster of 8 thread blocks that
// holds the lower triangle in their shared memory (distributed shared memory) and
// synchronises once per 32-column panel (cluster.sync()). Above it (the matrix no longer
// fits 8 × 227 KiB), or where the device cannot place such a cluster (checked once per
// device), ceil(m / 32) launches of the tiled kernel, one per column tile.
constexpr int kCholeskyClusterMaxOrder = 512;

// Above this order the caller should prefer cuSOLVER (cusolverDnDpotrf/potrs): the
// tiled factorisation (m > kCholeskyClusterMaxOrder) makes ceil(m / 32) launches, so
// its cost grows with m while cuSOLVER's blocked kernels catch up. A tuning threshold
// only: both functions are correct for every m (the solve up to kCholeskySolveMaxOrder).
// To be set from bench_dense's table on the H100.
constexpr int kCholeskyPreferredMaxOrder = 1024;

// The largest m cholesky_solve takes (its vector lives in 48 KiB of shared memory).
constexpr int kCholeskySolveMaxOrder = 5632;

// A = L Lᵀ in place (lower triangle of A, m × m, column-major, leading dimension lda;
// the strictly upper triangle is neither read nor written). *info (device memory) is
// set to 0 on success, or to the 1-based column of the first pivot that is not > 0 or
// not finite (LAPACK's and cuSOLVER's convention; the factor is then garbage from that
// column on). Enqueues one kernel (a cluster of 8 blocks) for m ≤ kCholeskyClusterMaxOrder,
// ceil(m / 32) kernels above, one memset when m = 0.
// cudaErrorInvalidValue for m < 0 or lda < max(1, m); otherwise the launch status.
cudaError_t cholesky_factor(int m, double* A, int lda, int* info, cudaStream_t stream);

// Up to this order (and where the device can place the cluster) cholesky_solve is one
// kernel of a cluster of 8 blocks holding L in their shared memory, forward and back
// substitution together; above it, one kernel of one block reading L from global memory.
constexpr int kCholeskySolveClusterMaxOrder = 512;

// Which substitutions cholesky_solve runs: both (b ← (L Lᵀ)⁻¹ b), the forward one alone
// (b ← L⁻¹ b: its squared norm is bᵀ (L Lᵀ)⁻¹ b, a Newton decrement without the
// direction), or the back one alone (b ← L⁻ᵀ b, finishing a Forward call's b). Forward
// then Back gives Both's result bit for bit (the same sums in the same order).
enum class Substitution { Both, Forward, Back };

// b ← (L Lᵀ)⁻¹ b with L lower triangular (m × m, leading dimension lda; its strictly
// upper triangle is not read): from cholesky_factor or from cuSOLVER's potrf (lower); or
// one of its two substitutions (`part`). One kernel: a cluster of 8 blocks when
// cholesky_solve_in_cluster(m), else one block. The result does not depend on timing
// (every sum in a fixed order). cudaErrorInvalidValue for m < 0, lda < max(1, m) or
// m > kCholeskySolveMaxOrder; otherwise the launch status.
cudaError_t cholesky_solve(int m, const double* L, int lda, double* b, cudaStream_t stream,
                           Substitution part = Substitution::Both);

// Whether cholesky_solve(m, …) runs as the cluster kernel on the current device (a host
// query, asked of the device once; allowed while a stream is being captured).
bool cholesky_solve_in_cluster(int m);

// cholesky_factor, then b ← (L Lᵀ)⁻¹ b, with the forward substitution fused into the
// factorisation: for m < kCholeskyClusterMaxOrder the cluster kernel factors [A | b]
// (b as row m of the lower triangle, so it leaves L⁻¹ b there) and one back
// substitution kernel follows (2 kernels in all); above, cholesky_factor then
// cholesky_solve. A and *info as cholesky_factor leaves them (L bit for bit the same);
// b is garbage when *info ≠ 0. cudaErrorInvalidValue for m < 0, lda < max(1, m) or
// m > kCholeskySolveMaxOrder; otherwise the launch status.
cudaError_t cholesky_factor_solve(int m, double* A, int lda, double* b, int* info, cudaStream_t stream);

// Many systems of one order at once (issue #23: a lockstep batch of sequences factors
// one system per sequence and step; one launch instead of one per sequence, the
// clusters of all the batch's matrices side by side on the GPU). Matrix k is
// A + k · stride_a (column-major, leading dimension lda, stride_a ≥ lda · m), its
// status info[k] as cholesky_factor's; each matrix's factor is bit for bit the one
// cholesky_factor makes of it alone. One kernel of `batch` clusters where
// cholesky_batched_in_cluster(m), else cholesky_factor on each matrix in turn.
// cudaErrorInvalidValue for m < 0, lda < max(1, m), batch outside [0, 65535] or a
// stride that makes matrices overlap; otherwise the launch status.
cudaError_t cholesky_factor_batched(int m, double* A, int lda, long long stride_a, int* info, int batch, cudaStream_t stream);

// cholesky_solve on each of `batch` systems: factor k at L + k · stride_l, right-hand
// side k at b + k · stride_b (stride_b ≥ m); bit for bit cholesky_solve's result for
// each. One kernel of `batch` clusters where cholesky_solve_in_cluster(m), else
// cholesky_solve on each in turn.
cudaError_t cholesky_solve_batched(int m, const double* L, int lda, long long stride_l, double* b, long long stride_b, int batch,
                                   cudaStream_t stream, Substitution part = Substitution::Both);

// Whether cholesky_factor_batched(m, …) is one kernel on the current device.
bool cholesky_batched_in_cluster(int m);

}  // namespace hsi::cuda::kernels
