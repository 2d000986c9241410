// The CUDA Newton core's kernels (see newton_kernels.h): per-sample energy, gradient,
// projected Hessian weights and safe step from sample_math.cuh, block reductions with
// fixed per-block partials summed in a fixed order (deterministic; one atomic counter
// only picks the block that finishes them, one_launch.cuh), and the Hessian's layout maps.
#include "newton_kernels.h"
#include "one_launch.cuh"

#include <algorithm>

namespace hsi::cuda::kernels {
namespace {

static_assert(kBlock % 32 == 0 && kBlock <= 1024 && kMaxPartials % 32 == 0);

using sample::Projection;

__device__ __forceinline__ void load_metric(const double* __restrict__ g, int i, double out[3]) {
  out[0] = g[3 * static_cast<size_t>(i)];
  out[1] = g[3 * static_cast<size_t>(i) + 1];
  out[2] = g[3 * static_cast<size_t>(i) + 2];
}

// Block-wide sum of `sum` and OR of `bad`, valid in thread 0. Every thread of the block
// must call it (blockDim.x a multiple of 32, at most 1024).
__device__ void block_sum_bad(double& sum, int& bad) {
  __shared__ double s_sum[32];
  __shared__ int s_bad[32];
  for (int o = 16; o > 0; o >>= 1) {
    sum += __shfl_down_sync(0xffffffffu, sum, o);
    bad |= __shfl_down_sync(0xffffffffu, bad, o);
  }
  const int lane = static_cast<int>(threadIdx.x) & 31, warp = static_cast<int>(threadIdx.x) >> 5;
  if (lane == 0) {
    s_sum[warp] = sum;
    s_bad[warp] = bad;
  }
  __syncthreads();
  if (warp == 0) {
    const int warps = static_cast<int>(blockDim.x) >> 5;
    sum = lane < warps ? s_sum[lane] : 0.0;
    bad = lane < warps ? s_bad[lane] : 0;
    for (int o = 16; o > 0; o >>= 1) {
      sum += __shfl_down_sync(0xffffffffu, sum, o);
      bad |= __shfl_down_sync(0xffffffffu, bad, o);
    }
  }
}

// Block-wide minimum, valid in thread 0 (same contract as block_sum_bad).
__device__ void block_min(double& v) {
  __shared__ double s_min[32];
  for (int o = 16; o > 0; o >>= 1) v = fmin(v, __shfl_down_sync(0xffffffffu, v, o));
  const int lane = static_cast<int>(threadIdx.x) & 31, warp = static_cast<int>(threadIdx.x) >> 5;
  if (lane == 0) s_min[warp] = v;
  __syncthreads();
  if (warp == 0) {
    const int warps = static_cast<int>(blockDim.x) >> 5;
    v = lane < warps ? s_min[lane] : sample::infinity();
    for (int o = 16; o > 0; o >>= 1) v = fmin(v, __shfl_down_sync(0xffffffffu, v, o));
  }
}

// The finishing pass of a mean: `parts` partials from `base` on, summed in thread
// order then by block_sum_bad's tree (every thread of the block calls it): the mean,
// or +inf if any sample was, into *out by thread 0.
__device__ void finish_mean_block(int parts, const double* __restrict__ part_sum, const int* __restrict__ part_bad, size_t base,
                                  double count, double* __restrict__ out) {
  double sum = 0;
  int bad = 0;
  for (int i = static_cast<int>(threadIdx.x); i < parts; i += static_cast<int>(blockDim.x)) {
    sum += __ldcg(part_sum + base + static_cast<size_t>(i));
    bad |= __ldcg(part_bad + base + static_cast<size_t>(i));
  }
  block_sum_bad(sum, bad);
  if (threadIdx.x == 0) *out = bad ? sample::infinity() : sum / count;
}

// Pass 1 of E(s) = mean_G e(g, a + s da, b + s db): this block's sum of the finite
// sample energies and whether any sample was infinite (folded or degenerate), written
// to part_sum / part_bad at `slot`.
__device__ void energy_partial(int G, const double* __restrict__ g, const double2* __restrict__ ab,
                               const double2* __restrict__ dab, double s, double* __restrict__ part_sum,
                               int* __restrict__ part_bad, unsigned slot) {
  double sum = 0;
  int bad = 0;
  for (int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x); i < G; i += static_cast<int>(gridDim.x * blockDim.x)) {
    double2 a = ab[i], b = ab[G + i];
    if (s != 0) {
      const double2 da = dab[i], db = dab[G + i];
      a = make_double2(a.x + s * da.x, a.y + s * da.y);
      b = make_double2(b.x + s * db.x, b.y + s * db.y);
    }
    double gi[3];
    load_metric(g, i, gi);
    const double e = sample::isometric_energy(gi, a.x, a.y, b.x, b.y);
    if (!sample::is_finite(e)) bad = 1;
    else sum += e;
  }
  block_sum_bad(sum, bad);
  if (threadIdx.x == 0) {
    part_sum[slot] = sum;
    part_bad[slot] = bad;
  }
}

// E(s) in one launch: each block's partial, then the last block sums them
// (last_block_done) exactly as a separate finishing block would.
__global__ void __launch_bounds__(kBlock) energy_mean_kernel(int G, const double* __restrict__ g, const double2* __restrict__ ab,
                                                             const double2* __restrict__ dab, double s, double* __restrict__ part_sum,
                                                             int* __restrict__ part_bad, unsigned* __restrict__ done,
                                                             double* __restrict__ out) {
  energy_partial(G, g, ab, dab, s, part_sum, part_bad, blockIdx.x);
  if (!last_block_done(done)) return;
  finish_mean_block(static_cast<int>(gridDim.x), part_sum, part_bad, 0, static_cast<double>(G), out);
}

// For `count` steps read from device memory: step k's partials at k·gridDim.x + block,
// each summed exactly as energy_mean_kernel sums it (same grid, same order), then the
// last block finishes every step's mean into out[k].
__global__ void __launch_bounds__(kBlock) energies_mean_kernel(int G, const double* __restrict__ g, const double2* __restrict__ ab,
                                                               const double2* __restrict__ dab, const double* __restrict__ steps,
                                                               int count, double* __restrict__ part_sum, int* __restrict__ part_bad,
                                                               unsigned* __restrict__ done, double* __restrict__ out) {
  // System blockIdx.y of a lockstep batch (mean_energies_batched; one system: 0): its
  // arrays at fixed strides, its own partials and counter.
  const size_t sys = blockIdx.y, parts_per_system = static_cast<size_t>(count) * gridDim.x;
  g += sys * 3 * static_cast<size_t>(G);
  ab += sys * 2 * static_cast<size_t>(G);
  dab += sys * 2 * static_cast<size_t>(G);
  steps += sys * static_cast<size_t>(count);
  part_sum += sys * parts_per_system;
  part_bad += sys * parts_per_system;
  done += sys;
  out += sys * static_cast<size_t>(count);
  for (int k = 0; k < count; ++k) {
    energy_partial(G, g, ab, dab, steps[k], part_sum, part_bad, static_cast<unsigned>(k) * gridDim.x + blockIdx.x);
    __syncthreads();  // block_sum_bad's shared slots are reused by the next step
  }
  if (!last_block_done(done)) return;
  const int parts = static_cast<int>(gridDim.x);
  for (int k = 0; k < count; ++k) {
    finish_mean_block(parts, part_sum, part_bad, static_cast<size_t>(k) * static_cast<size_t>(parts), static_cast<double>(G),
                      out + k);
    __syncthreads();
  }
}

// ∂e/∂(Re a, Im a, Re b, Im b) per sample of G, packed as complex ∂E/∂a, ∂E/∂b (zero
// where the sample is infinite, as on the CPU).
__global__ void __launch_bounds__(kBlock) gradient_kernel(int G, const double* __restrict__ g, const double2* __restrict__ ab,
                                                           double2* __restrict__ gab) {
  const size_t sys = blockIdx.y;  // system of a lockstep batch (gradient_samples_batched)
  g += sys * 3 * static_cast<size_t>(G);
  ab += sys * 2 * static_cast<size_t>(G);
  gab += sys * 2 * static_cast<size_t>(G);
  for (int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x); i < G; i += static_cast<int>(gridDim.x * blockDim.x)) {
    const double2 a = ab[i], b = ab[G + i];
    double gi[3];
    load_metric(g, i, gi);
    const sample::Derivatives d =
        sample::isometric_derivatives(gi, a.x, a.y, b.x, b.y, Projection::Delete, false, /*with_hessian=*/false);
    gab[i] = make_double2(d.grad[0], d.grad[1]);
    gab[G + i] = make_double2(d.grad[2], d.grad[3]);
  }
}

// The six complex weights of each H-sample's projected 4×4 Hessian, stored 6 × |H|
// (weight-major, so the next kernel's loads are coalesced).
__global__ void __launch_bounds__(kBlock) h_sample_weights(int h, int G, const int* __restrict__ H, const double* __restrict__ g,
                                                          const double2* __restrict__ ab, Projection projection, bool exact,
                                                          double2* __restrict__ W) {
  const size_t sys = blockIdx.y;  // system of a lockstep batch (weighted_rows_batched)
  g += sys * 3 * static_cast<size_t>(G);
  ab += sys * 2 * static_cast<size_t>(G);
  W += sys * 6 * static_cast<size_t>(h);
  for (int k = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x); k < h; k += static_cast<int>(gridDim.x * blockDim.x)) {
    const int s = H[k];
    const double2 a = ab[s], b = ab[G + s];
    double gi[3];
    load_metric(g, s, gi);
    const sample::Derivatives d = sample::isometric_derivatives(gi, a.x, a.y, b.x, b.y, projection, exact, true);
    double w[6][2];
    sample::hessian_weights(d.hess, w);
#pragma unroll
    for (int q = 0; q < 6; ++q) W[static_cast<size_t>(q) * h + k] = make_double2(w[q][0], w[q][1]);
  }
}

// out (rows × 2, [w_a | w_b]): per row k, sample s = index[k] (or k without an index),
// the sample's 4×4 Hessian (as h_sample_weights makes it) applied to the row's
// (Re da, Im da, Re db, Im db) from din (rows × 2): NewtonCore::hessian_times' samples.
__global__ void __launch_bounds__(kBlock) hessian_apply_kernel(int rows, int G, const int* __restrict__ index, const double* __restrict__ g,
                                                              const double2* __restrict__ ab, const double2* __restrict__ din,
                                                              Projection projection, bool exact, double2* __restrict__ out) {
  for (int k = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x); k < rows; k += static_cast<int>(gridDim.x * blockDim.x)) {
    const int s = index ? index[k] : k;
    const double2 a = ab[s], b = ab[G + s];
    double gi[3];
    load_metric(g, s, gi);
    const sample::Derivatives d = sample::isometric_derivatives(gi, a.x, a.y, b.x, b.y, projection, exact, true);
    const double2 da = din[k], db = din[rows + k];
    const double v[4] = {da.x, da.y, db.x, db.y};
    double y[4];
#pragma unroll
    for (int i = 0; i < 4; ++i) y[i] = d.hess.m[i][0] * v[0] + d.hess.m[i][1] * v[1] + d.hess.m[i][2] * v[2] + d.hess.m[i][3] * v[3];
    out[k] = make_double2(y[0], y[1]);
    out[rows + k] = make_double2(y[2], y[3]);
  }
}

// Wt (|H| × 6n, column-major): column block q is w_q ∘ D_H for even q, w_q ∘ conj(D_H)
// for odd q. Threads run along the rows (k) so that every access is coalesced.
__global__ void weighted_rows_kernel(int h, int n, const double2* __restrict__ DH, const double2* __restrict__ W, double2* __restrict__ Wt) {
  const int k = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  if (k >= h) return;
  const size_t sys = blockIdx.z;  // system of a lockstep batch: its weights and rows (D_H shared)
  W += sys * 6 * static_cast<size_t>(h);
  Wt += sys * static_cast<size_t>(h) * 6 * static_cast<size_t>(n);
  double2 w[6];
#pragma unroll
  for (int q = 0; q < 6; ++q) w[q] = W[static_cast<size_t>(q) * h + k];
  for (int j = static_cast<int>(blockIdx.y * blockDim.y + threadIdx.y); j < n; j += static_cast<int>(gridDim.y * blockDim.y)) {
    const double2 d = DH[static_cast<size_t>(j) * h + k];
#pragma unroll
    for (int q = 0; q < 6; ++q) {
      const double dr = d.x, di = q % 2 == 0 ? d.y : -d.y;  // D or conj(D)
      Wt[(static_cast<size_t>(q) * n + j) * h + k] = make_double2(w[q].x * dr - w[q].y * di, w[q].x * di + w[q].y * dr);
    }
  }
}

// Entry (r, c) of the real 4n × 4n Hessian before symmetrisation, from R = Dᴴ Wt (n × 6n,
// not yet divided by |H|): newton.cpp's real_block for the blocks (0,0), (0,1), (1,1)
// from the column pairs (0,1), (2,3), (4,5) of R, and block (1,0) = block (0,1)ᵀ.
__device__ __forceinline__ double raw_hessian(int n, const double2* __restrict__ R, double count, int r, int c) {
  const int m = 2 * n;
  if (r >= m && c < m) {
    const int t = r;
    r = c;
    c = t;
  }
  const int p = r < m ? (c < m ? 0 : 1) : 2;
  const int rr = r < m ? r : r - m, cc = c < m ? c : c - m;
  const bool hi_r = rr >= n, hi_c = cc >= n;
  const int i = hi_r ? rr - n : rr, j = hi_c ? cc - n : cc;
  const double2 P = R[static_cast<size_t>(2 * p * n + j) * n + i], Q = R[static_cast<size_t>((2 * p + 1) * n + j) * n + i];
  const double Pr = P.x / count, Pi = P.y / count, Qr = Q.x / count, Qi = Q.y / count;
  if (!hi_r) return hi_c ? -Pi + Qi : Pr + Qr;
  return hi_c ? Pr - Qr : Pi + Qi;
}

// Hv = (M + Mᵀ)/2, column-major 4n × 4n, with M the raw Hessian above.
__global__ void real_hessian_kernel(int n, const double2* __restrict__ R, double count, double* __restrict__ Hv) {
  const int N = 4 * n;
  const size_t sys = blockIdx.z;  // system of a lockstep batch (real_hessian_batched)
  R += sys * 6 * static_cast<size_t>(n) * static_cast<size_t>(n);
  Hv += sys * static_cast<size_t>(N) * static_cast<size_t>(N);
  for (int c = static_cast<int>(blockIdx.y * blockDim.y + threadIdx.y); c < N; c += static_cast<int>(gridDim.y * blockDim.y))
    for (int r = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x); r < N; r += static_cast<int>(gridDim.x * blockDim.x))
      Hv[static_cast<size_t>(c) * N + r] = (raw_hessian(n, R, count, r, c) + raw_hessian(n, R, count, c, r)) / 2;
}

// The safe step in one launch: per-block minima over samples of the first s > 0 with
// |a + s da| = |b + s db|, then the last block's minimum of them.
__global__ void __launch_bounds__(kBlock) safe_step_kernel(int G, const double2* __restrict__ ab, const double2* __restrict__ dab,
                                                           double* __restrict__ part_min, unsigned* __restrict__ done,
                                                           double* __restrict__ out) {
  const size_t sys = blockIdx.y;  // system of a lockstep batch (max_safe_step_batched): its own partials and counter
  ab += sys * 2 * static_cast<size_t>(G);
  dab += sys * 2 * static_cast<size_t>(G);
  part_min += sys * gridDim.x;
  done += sys;
  out += sys;
  double t = sample::infinity();
  for (int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x); i < G; i += static_cast<int>(gridDim.x * blockDim.x)) {
    const double2 a = ab[i], b = ab[G + i], da = dab[i], db = dab[G + i];
    t = fmin(t, sample::first_fold_step(a.x, a.y, b.x, b.y, da.x, da.y, db.x, db.y));
  }
  block_min(t);
  if (threadIdx.x == 0) part_min[blockIdx.x] = t;
  if (!last_block_done(done)) return;
  t = sample::infinity();
  for (int i = static_cast<int>(threadIdx.x); i < static_cast<int>(gridDim.x); i += static_cast<int>(blockDim.x))
    t = fmin(t, __ldcg(part_min + i));
  block_min(t);
  if (threadIdx.x == 0) *out = t;
}

// D_H = the rows H of D_G, column-major |H| × n.
__global__ void gather_rows_kernel(int G, int h, int n, const double2* __restrict__ D, const int* __restrict__ H, double2* __restrict__ DH) {
  const int k = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  if (k >= h) return;
  const int s = H[k];
  for (int j = static_cast<int>(blockIdx.y * blockDim.y + threadIdx.y); j < n; j += static_cast<int>(gridDim.y * blockDim.y))
    DH[static_cast<size_t>(j) * h + k] = D[static_cast<size_t>(j) * G + s];
}

// One block: Σ_{i<n} a_i b_i, each thread summing its entries in order, then
// block_sum_bad's tree; valid in thread 0. Every thread of the block calls it; a second
// call in the same kernel needs a __syncthreads() between (the tree's shared slots).
__device__ double block_dot(int n, const double* __restrict__ a, const double* __restrict__ b) {
  double sum = 0;
  int bad = 0;
  for (int i = static_cast<int>(threadIdx.x); i < n; i += static_cast<int>(blockDim.x)) sum += a[i] * b[i];
  block_sum_bad(sum, bad);
  return sum;
}

// One block: max_i |A_ii| over an n × n column-major matrix, valid in thread 0 (the
// same contract as block_dot).
__device__ double block_diag_abs_max(int n, const double* __restrict__ A) {
  double v = 0;
  for (int i = static_cast<int>(threadIdx.x); i < n; i += static_cast<int>(blockDim.x))
    v = fmax(v, fabs(A[static_cast<size_t>(i) * static_cast<size_t>(n) + static_cast<size_t>(i)]));
  v = -v;  // block_min of −|A_ii|
  block_min(v);
  return -v;
}

// One block: the gradient made horizontal, g_i −= (g_dim / a_dim) a_i for i < dim and
// g_dim = 0 (dim + 1 entries). Every thread of the block calls it; g is fully written
// once the caller's next __syncthreads() has passed.
__device__ void block_horizontal_gradient(int dim, const double* __restrict__ a, double* __restrict__ g) {
  const double f = g[dim] / a[dim];
  __syncthreads();  // every thread has read g[dim] before it is cleared
  for (int i = static_cast<int>(threadIdx.x); i <= dim; i += static_cast<int>(blockDim.x)) {
    if (i < dim) g[i] -= f * a[i];
    else g[i] = 0;
  }
}

unsigned blocks_for(long long count, long long per_block, long long cap) {
  return static_cast<unsigned>(std::clamp((count + per_block - 1) / per_block, 1LL, cap));
}


// One block: Σ a_i b_i over n entries (fixed order per thread, then block_sum_bad's tree).
__global__ void __launch_bounds__(kBlock) dot_kernel(int n, const double* __restrict__ a, const double* __restrict__ b,
                                                     double* __restrict__ out) {
  const double sum = block_dot(n, a, b);
  if (threadIdx.x == 0) *out = sum;
}

__global__ void __launch_bounds__(kBlock) diag_max_kernel(int n, const double* __restrict__ A, double* __restrict__ out,
                                                          long long A_stride, long long out_stride) {
  const long long sys = blockIdx.x;  // one block per system
  A += sys * A_stride;
  out += sys * out_stride;
  const double v = block_diag_abs_max(n, A);
  if (threadIdx.x == 0) *out = v;
}

__global__ void add_relative_ridge_kernel(int n, const double* __restrict__ A0, const double* __restrict__ relative,
                                          const double* __restrict__ diag, double* __restrict__ diag_down, double* __restrict__ A,
                                          long long mat_stride, long long relative_stride, long long scalar_stride) {
  const long long sys = blockIdx.y;
  A0 += sys * mat_stride;
  A += sys * mat_stride;
  relative += sys * relative_stride;
  diag += sys * scalar_stride;
  diag_down += sys * scalar_stride;
  const double r = *relative * fmax(*diag, 1e-300);
  if (blockIdx.x == 0 && threadIdx.x == 0) *diag_down = *diag;
  const size_t total = static_cast<size_t>(n) * static_cast<size_t>(n);
  for (size_t t = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x; t < total;
       t += static_cast<size_t>(gridDim.x) * blockDim.x)
    A[t] = A0[t] + (t % (static_cast<size_t>(n) + 1) == 0 ? r : 0.0);
}

__global__ void trial_point_kernel(int n, const double* __restrict__ x, const double* __restrict__ d, const double* __restrict__ step,
                                   double* __restrict__ out, long long vec_stride, long long step_stride) {
  const long long sys = blockIdx.y;
  x += sys * vec_stride;
  d += sys * vec_stride;
  out += sys * vec_stride;
  step += sys * step_stride;
  const int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i < n) out[i] = x[i] + *step * d[i];
}

// The leading dim × dim block of the exact system modulo the rotation (device_newton.cpp,
// linearize): A_ij += −(a_i k_j + k_i a_j)/uu + c a_i a_j/uu², with k = column dim of A, c =
// A_dim,dim and uu = a[dim]. Reads column dim, writes only the leading block.
__global__ void horizontal_block_kernel(int dim, int m, double* __restrict__ A, const double* __restrict__ a, long long mat_stride,
                                        long long vec_stride) {
  A += static_cast<long long>(blockIdx.z) * mat_stride;
  a += static_cast<long long>(blockIdx.z) * vec_stride;
  const int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x), j = static_cast<int>(blockIdx.y * blockDim.y + threadIdx.y);
  if (i >= dim || j >= dim) return;
  const size_t M = static_cast<size_t>(m), D = static_cast<size_t>(dim);
  const double uu = a[dim], c = A[D * M + D];
  const double* k = A + D * M;
  const double ai = a[i], aj = a[j];
  A[static_cast<size_t>(j) * M + static_cast<size_t>(i)] += -(ai * k[j] + k[i] * aj) / uu + c * ai * aj / (uu * uu);
}


// C = A · B for a tall A (rows × k) and B (k × 2), all complex column-major: a block is
// 32 rows × 8 slices of k; each thread sums its slice in order, then the block adds the
// 8 slices in order (deterministic). Faster than ZGEMM at these shapes (two columns).
constexpr int kTallRows = 32, kTallSlices = 8;
__global__ void __launch_bounds__(kTallRows* kTallSlices)
    tall_times_two_kernel(int rows, int k, const double2* __restrict__ A, const double2* __restrict__ B, double2* __restrict__ C) {
  __shared__ double2 part[2][kTallSlices][kTallRows];
  const size_t sys = blockIdx.y;  // system of a lockstep batch (tall_times_two_batched): its B and C, A shared
  B += sys * 2 * static_cast<size_t>(k);
  C += sys * 2 * static_cast<size_t>(rows);
  const int tx = static_cast<int>(threadIdx.x), ty = static_cast<int>(threadIdx.y);
  const int i = static_cast<int>(blockIdx.x) * kTallRows + tx;
  double2 c0 = make_double2(0, 0), c1 = make_double2(0, 0);
  if (i < rows)
    for (int j = ty; j < k; j += kTallSlices) {
      const double2 a = A[static_cast<size_t>(j) * static_cast<size_t>(rows) + static_cast<size_t>(i)];
      const double2 b0 = B[j], b1 = B[k + j];
      c0.x += a.x * b0.x - a.y * b0.y;
      c0.y += a.x * b0.y + a.y * b0.x;
      c1.x += a.x * b1.x - a.y * b1.y;
      c1.y += a.x * b1.y + a.y * b1.x;
    }
  part[0][ty][tx] = c0;
  part[1][ty][tx] = c1;
  __syncthreads();
  if (ty < 2 && i < rows) {
    double2 c = make_double2(0, 0);
    for (int q = 0; q < kTallSlices; ++q) {
      c.x += part[ty][q][tx].x;
      c.y += part[ty][q][tx].y;
    }
    C[static_cast<size_t>(ty) * static_cast<size_t>(rows) + static_cast<size_t>(i)] = c;
  }
}

// C = Aᴴ · B for a tall A (rows × k) and B (rows × 2): one block of kAdjointThreads per
// column of A, each thread a fixed stride of rows, kAdjointUnroll rows' loads issued
// before they are summed (in row order), then a fixed tree: deterministic. With 256
// threads and one load in flight per thread the loop waited on memory every row: 22 µs
// for bar_holes' |G| = 10,000 × 76 on an H200 by Nsight Compute (bench/results/
// ncu_hsi_interpolate_bar_holes_h200.txt), against ~3 µs to read A once.
constexpr int kAdjointThreads = 1024, kAdjointUnroll = 4;
__global__ void __launch_bounds__(kAdjointThreads)
    tall_adjoint_times_two_kernel(int rows, int k, const double2* __restrict__ A, const double2* __restrict__ B, double2* __restrict__ C,
                                  ReducedGradient epi) {
  __shared__ double s[4][kAdjointThreads / 32];
  const int j = static_cast<int>(blockIdx.x);
  const double2* a_col = A + static_cast<size_t>(j) * static_cast<size_t>(rows);
  double v[4] = {0, 0, 0, 0};  // Re, Im of conj(a)·b0, conj(a)·b1
  const int stride = static_cast<int>(blockDim.x);
  int i = static_cast<int>(threadIdx.x);
  for (; i + (kAdjointUnroll - 1) * stride < rows; i += kAdjointUnroll * stride) {
    double2 a[kAdjointUnroll], b0[kAdjointUnroll], b1[kAdjointUnroll];
#pragma unroll
    for (int u = 0; u < kAdjointUnroll; ++u) {
      a[u] = a_col[i + u * stride];
      b0[u] = B[i + u * stride];
      b1[u] = B[rows + i + u * stride];
    }
#pragma unroll
    for (int u = 0; u < kAdjointUnroll; ++u) {
      v[0] += a[u].x * b0[u].x + a[u].y * b0[u].y;
      v[1] += a[u].x * b0[u].y - a[u].y * b0[u].x;
      v[2] += a[u].x * b1[u].x + a[u].y * b1[u].y;
      v[3] += a[u].x * b1[u].y - a[u].y * b1[u].x;
    }
  }
  for (; i < rows; i += stride) {
    const double2 a = a_col[i], b0 = B[i], b1 = B[rows + i];
    v[0] += a.x * b0.x + a.y * b0.y;
    v[1] += a.x * b0.y - a.y * b0.x;
    v[2] += a.x * b1.x + a.y * b1.y;
    v[3] += a.x * b1.y - a.y * b1.x;
  }
  const int lane = static_cast<int>(threadIdx.x) & 31, warp = static_cast<int>(threadIdx.x) >> 5;
  for (int q = 0; q < 4; ++q) {
    for (int o = 16; o > 0; o >>= 1) v[q] += __shfl_down_sync(0xffffffffu, v[q], o);
    if (lane == 0) s[q][warp] = v[q];
  }
  __syncthreads();
  if (threadIdx.x < 32) {  // the warps' sums, by one warp in a fixed tree
    const int warps = static_cast<int>(blockDim.x) / 32;
    for (int q = 0; q < 4; ++q) {
      double t = lane < warps ? s[q][lane] : 0.0;
      for (int o = 16; o > 0; o >>= 1) t += __shfl_down_sync(0xffffffffu, t, o);
      if (lane == 0) v[q] = t;
    }
    if (lane == 0) {
      C[j] = make_double2(v[0], v[1]);
      C[k + j] = make_double2(v[2], v[3]);
    }
  }
  if (!epi.g || !last_block_done(epi.done)) return;
  // The reduced gradient g = scale · Tᵀ c, c = C read as 4k reals: one warp per entry of
  // g, its lanes over T's column (contiguous), then a fixed shuffle tree.
  const double* c = reinterpret_cast<const double*>(C);
  const int rows4 = 4 * k, warps = static_cast<int>(blockDim.x) / 32;
  for (int col = warp; col < epi.m; col += warps) {
    const double* t = epi.T + static_cast<size_t>(col) * static_cast<size_t>(rows4);
    double sum = 0;
    for (int r = lane; r < rows4; r += 32) sum += t[r] * __ldcg(c + r);
    for (int o = 16; o > 0; o >>= 1) sum += __shfl_down_sync(0xffffffffu, sum, o);
    if (lane == 0) epi.g[col] = sum * epi.scale;
  }
  if (!epi.a) return;
  __syncthreads();  // every entry of g written
  block_horizontal_gradient(epi.dim, epi.a, epi.g);  // then the horizontal part
}

// Per sample: m = Σ_j w_j keys_j (j with w_j ≠ 0, in order), with `exponential`
// metric_exp(m) (timing.cpp's closed form). keys: K sets of G metrics (g1, g2, g3).
__global__ void blend_metrics_kernel(int G, int K, const double* __restrict__ keys, const double* __restrict__ w, bool exponential,
                                     double* __restrict__ g) {
  const int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= G) return;
  double m[3] = {0, 0, 0};
  for (int j = 0; j < K; ++j) {
    const double wj = w[j];
    if (wj == 0) continue;
    const double* k = keys + (static_cast<size_t>(j) * static_cast<size_t>(G) + static_cast<size_t>(i)) * 3;
    m[0] += wj * k[0];
    m[1] += wj * k[1];
    m[2] += wj * k[2];
  }
  if (exponential) {
    const double nu = 0.5 * (m[0] + m[2]), h = 0.5 * (m[0] - m[2]);
    const double delta = hypot(h, m[1]);
    const double sinhc = delta < 1e-4 ? 1 + delta * delta / 6 : sinh(delta) / delta;
    const double e = exp(nu), c = cosh(delta);
    m[0] = e * (c + sinhc * h);
    m[1] = e * sinhc * m[1];
    m[2] = e * (c - sinhc * h);
  }
  double* out = g + 3 * static_cast<size_t>(i);
  out[0] = m[0];
  out[1] = m[1];
  out[2] = m[2];
}

// The solve's right-hand side: d = −g (m entries), and both status words (the factor's,
// the triangular solves') cleared, in one launch.
__global__ void negate_kernel(int m, const double* __restrict__ g, double* __restrict__ d, int* __restrict__ info, long long vec_stride,
                              long long info_stride) {
  const long long sys = blockIdx.y;
  g += sys * vec_stride;
  d += sys * vec_stride;
  info += sys * info_stride;
  const int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i < m) d[i] = -g[i];
  if (i == 0) {
    info[0] = 0;
    info[1] = 0;
  }
}

// One block: with the rotation freed d[dim] = −(Σ_{i<dim} a_i d_i)/a[dim] (the rotation's share),
// then slope = Σ_{i<m} g_i d_i and gnorm2 = Σ_{i<dim} g_i², each summed as dot_kernel sums.
__global__ void __launch_bounds__(kBlock) step_scalars_kernel(int dim, int m, bool rotation, const double* __restrict__ a,
                                                              const double* __restrict__ g, double* __restrict__ d,
                                                              double* __restrict__ slope, double* __restrict__ gnorm2,
                                                              const int* __restrict__ info, int* __restrict__ info_out,
                                                              long long vec_stride, long long scalar_stride) {
  const long long sys = blockIdx.x;  // one block per system (info, info_out: one system only)
  a += sys * vec_stride;
  g += sys * vec_stride;
  d += sys * vec_stride;
  slope += sys * scalar_stride;
  gnorm2 += sys * scalar_stride;
  if (info_out && threadIdx.x < 2) info_out[threadIdx.x] = info[threadIdx.x];
  if (rotation) {
    const double ad = block_dot(dim, a, d);
    if (threadIdx.x == 0) d[dim] = -ad / a[dim];
    __syncthreads();  // d[dim] written, block_dot's slots free
  }
  const double gd = block_dot(m, g, d);
  if (threadIdx.x == 0) *slope = gd;
  __syncthreads();
  const double gg = block_dot(dim, g, g);
  if (threadIdx.x == 0) *gnorm2 = gg;
}

__global__ void __launch_bounds__(kBlock) decrement_scalars_kernel(int dim, int m, const double* __restrict__ g,
                                                                   const double* __restrict__ y, double* __restrict__ slope,
                                                                   double* __restrict__ gnorm2, const int* __restrict__ info,
                                                                   int* __restrict__ info_out, long long vec_stride,
                                                                   long long scalar_stride, long long info_stride) {
  const long long sys = blockIdx.x;  // one block per system
  g += sys * vec_stride;
  y += sys * vec_stride;
  slope += sys * scalar_stride;
  gnorm2 += sys * scalar_stride;
  info += sys * info_stride;
  info_out += sys * info_stride;
  if (threadIdx.x < 2) info_out[threadIdx.x] = info[threadIdx.x];
  const double yy = block_dot(m, y, y);
  if (threadIdx.x == 0) *slope = -yy;
  __syncthreads();
  const double gg = block_dot(dim, g, g);
  if (threadIdx.x == 0) *gnorm2 = gg;
}

// One block per system: the gradient made horizontal (block_horizontal_gradient).
__global__ void __launch_bounds__(kBlock) horizontal_gradient_kernel(int dim, const double* __restrict__ a, double* __restrict__ g,
                                                                     long long vec_stride) {
  a += static_cast<long long>(blockIdx.x) * vec_stride;
  g += static_cast<long long>(blockIdx.x) * vec_stride;
  block_horizontal_gradient(dim, a, g);
}

// One block, after horizontal_block_kernel: g_i −= (g_dim/uu) a_i, row and column dim of
// A and g_dim cleared, then max_i |A_ii| over the m × m system (diag_max_kernel's order)
// into *diag and into A_dim,dim.
__global__ void __launch_bounds__(kBlock) horizontal_clear_diag_kernel(int dim, int m, double* __restrict__ A,
                                                                       const double* __restrict__ a, double* __restrict__ g,
                                                                       double* __restrict__ diag, long long mat_stride,
                                                                       long long vec_stride, long long diag_stride) {
  const long long sys = blockIdx.x;  // one block per system
  A += sys * mat_stride;
  a += sys * vec_stride;
  g += sys * vec_stride;
  diag += sys * diag_stride;
  block_horizontal_gradient(dim, a, g);  // (m = dim + 1 entries)
  const size_t M = static_cast<size_t>(m), D = static_cast<size_t>(dim);
  for (int i = static_cast<int>(threadIdx.x); i < m; i += static_cast<int>(blockDim.x)) {
    A[D * M + static_cast<size_t>(i)] = 0;  // column dim
    A[static_cast<size_t>(i) * M + D] = 0;  // row dim
  }
  __syncthreads();  // the cleared entries are read below
  const double v = block_diag_abs_max(m, A);
  if (threadIdx.x == 0) {
    *diag = v;
    A[D * M + D] = v;
  }
}

// y = y0 + A x for real column-major A (rows × cols, leading dimension rows), with
// x = x0 + (*step)·dx where dx is given (else x0); blockIdx.z picks one of two products
// sharing x. A block is kTallRows rows × kOneSlices slices of the columns, each thread
// summing its slice in order, then the block the slices in order (deterministic). Block
// (0, 0) also writes x into x_copy where given. The products are short (a few hundred
// rows: a few blocks), so each block splits the columns finely (32 slices of ~10) to keep
// its chain of dependent loads short.
struct RealProduct {
  const double* A;
  const double* y0;  // null: 0
  double* y;
  int rows;
};
constexpr int kOneSlices = 32;
__global__ void __launch_bounds__(kTallRows* kOneSlices)
    tall_times_one_kernel(RealProduct p0, RealProduct p1, int cols, const double* __restrict__ x0, const double* __restrict__ dx,
                          const double* __restrict__ step, double* __restrict__ x_copy, TallStrides bs) {
  __shared__ double part[kOneSlices][kTallRows];
  const long long sys = blockIdx.y;  // the system of a batch (TallStrides)
  RealProduct p = blockIdx.z == 0 ? p0 : p1;
  p.A += sys * (blockIdx.z == 0 ? bs.A : bs.second_A);
  p.y += sys * (blockIdx.z == 0 ? bs.y : bs.second_y);
  if (p.y0) p.y0 += sys * bs.y0;
  x0 += sys * bs.x;
  if (dx) {
    dx += sys * bs.dx;
    step += sys * bs.step;
  }
  if (x_copy) x_copy += sys * bs.x_copy;
  const int tx = static_cast<int>(threadIdx.x), ty = static_cast<int>(threadIdx.y);
  const int i = static_cast<int>(blockIdx.x) * kTallRows + tx;
  const double s = dx ? *step : 0.0;
  auto x_at = [&](int j) { return dx ? x0[j] + s * dx[j] : x0[j]; };
  if (x_copy && blockIdx.x == 0 && blockIdx.z == 0)
    for (int j = ty * kTallRows + tx; j < cols; j += kTallRows * kOneSlices) x_copy[j] = x_at(j);
  if (static_cast<int>(blockIdx.x) * kTallRows >= p.rows) return;  // the shorter product's spare blocks (whole block)
  double c = 0;
  if (i < p.rows)
    for (int j = ty; j < cols; j += kOneSlices) c += p.A[static_cast<size_t>(j) * static_cast<size_t>(p.rows) + static_cast<size_t>(i)] * x_at(j);
  part[ty][tx] = c;
  __syncthreads();
  if (ty == 0 && i < p.rows) {
    double y = 0;
    for (int q = 0; q < kOneSlices; ++q) y += part[q][tx];
    p.y[i] = p.y0 ? p.y0[i] + y : y;
  }
}

// Up to four device-to-device copies in one launch (blockIdx.y picks one).
__global__ void copy_kernel(CopyList list) {
  const CopyList::Entry& e = list.entry[blockIdx.y];
  for (size_t t = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x; t < e.count; t += static_cast<size_t>(gridDim.x) * blockDim.x)
    e.dst[t] = e.src[t];
}

// MapSpace::regauge on the device: rotate the image so that φ_r lies on the positive
// imaginary axis, then read x off the primary rows (same arithmetic as the host).
__global__ void regauge_kernel(int dim, int n, int r, const int* __restrict__ primary, const double* __restrict__ v,
                               double* __restrict__ x, long long v_stride, long long x_stride) {
  v += static_cast<long long>(blockIdx.y) * v_stride;
  x += static_cast<long long>(blockIdx.y) * x_stride;
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  if (c >= dim) return;
  const double px = v[r], py = v[n + r];
  const double len = hypot(px, py);
  const double rx = len > 0 ? py / len : 1.0, ry = len > 0 ? px / len : 0.0;  // r = i conj(p) / |p|
  const int row = primary[c], a = row % n, part = row / n;
  double zx, zy;
  if (part < 2) {
    const double ux = v[a], uy = v[n + a];
    zx = rx * ux - ry * uy;
    zy = rx * uy + ry * ux;
  } else {  // conj(r) ψ
    const double ux = v[2 * n + a], uy = v[3 * n + a];
    zx = rx * ux + ry * uy;
    zy = rx * uy - ry * ux;
  }
  x[c] = part % 2 == 0 ? zx : zy;
}

}  // namespace

cudaError_t regauge(int dim, int n, int rotation_vertex, const int* primary_rows, const double* v, double* x,
                    cudaStream_t stream) {
  return regauge_batched(1, dim, n, rotation_vertex, primary_rows, v, 0, x, 0, stream);
}

cudaError_t regauge_batched(int systems, int dim, int n, int rotation_vertex, const int* primary_rows, const double* v, long long v_stride,
                            double* x, long long x_stride, cudaStream_t stream) {
  if (systems < 1 || systems > kMaxBatchSystems) return cudaErrorInvalidValue;
  regauge_kernel<<<dim3(static_cast<unsigned>((dim + kBlock - 1) / kBlock), static_cast<unsigned>(systems)), kBlock, 0, stream>>>(
      dim, n, rotation_vertex, primary_rows, v, x, v_stride, x_stride);
  return cudaGetLastError();
}

unsigned reduction_blocks(int count) { return blocks_for(count, kBlock, kMaxPartials); }

cudaError_t loadable() {
  cudaFuncAttributes attr{};
  return cudaFuncGetAttributes(&attr, energy_mean_kernel);
}

cudaError_t gather_rows(int G, int h, int n, const double2* D, const int* H, double2* DH, cudaStream_t stream) {
  const dim3 block(32, 8), grid(blocks_for(h, 32, 1LL << 30), blocks_for(n, 8, 65535));
  gather_rows_kernel<<<grid, block, 0, stream>>>(G, h, n, D, H, DH);
  return cudaGetLastError();
}

cudaError_t mean_energy(int G, const double* g, const double2* ab, const double2* dab, double s, double* part_sum,
                        int* part_bad, unsigned* done, double* out, cudaStream_t stream) {
  energy_mean_kernel<<<reduction_blocks(G), kBlock, 0, stream>>>(G, g, ab, dab, s, part_sum, part_bad, done, out);
  return cudaGetLastError();
}

cudaError_t mean_energies(int G, const double* g, const double2* ab, const double2* dab, const double* steps, int count,
                          double* part_sum, int* part_bad, unsigned* done, double* out, cudaStream_t stream) {
  return mean_energies_batched(1, G, g, ab, dab, steps, count, part_sum, part_bad, done, out, stream);
}

cudaError_t gradient_samples(int G, const double* g, const double2* ab, double2* gab, cudaStream_t stream) {
  return gradient_samples_batched(1, G, g, ab, gab, stream);
}

cudaError_t mean_energies_batched(int systems, int G, const double* g, const double2* ab, const double2* dab, const double* steps,
                                  int count, double* part_sum, int* part_bad, unsigned* done, double* out, cudaStream_t stream) {
  if (count < 1 || count > kMaxSteps || systems < 1 || systems > kMaxBatchSystems) return cudaErrorInvalidValue;
  const dim3 grid(reduction_blocks(G), static_cast<unsigned>(systems));
  energies_mean_kernel<<<grid, kBlock, 0, stream>>>(G, g, ab, dab, steps, count, part_sum, part_bad, done, out);
  return cudaGetLastError();
}

cudaError_t gradient_samples_batched(int systems, int G, const double* g, const double2* ab, double2* gab, cudaStream_t stream) {
  if (systems < 1 || systems > kMaxBatchSystems) return cudaErrorInvalidValue;
  const dim3 grid(blocks_for(G, kBlock, 1LL << 30), static_cast<unsigned>(systems));
  gradient_kernel<<<grid, kBlock, 0, stream>>>(G, g, ab, gab);
  return cudaGetLastError();
}

cudaError_t weighted_rows_batched(int systems, int G, int h, int n, const int* H, const double* g, const double2* ab,
                                  sample::Projection projection, bool exact, const double2* DH, double2* W, double2* Wt,
                                  cudaStream_t stream) {
  if (systems < 1 || systems > kMaxBatchSystems) return cudaErrorInvalidValue;
  h_sample_weights<<<dim3(blocks_for(h, kBlock, 1LL << 30), static_cast<unsigned>(systems)), kBlock, 0, stream>>>(h, G, H, g, ab,
                                                                                                                 projection, exact, W);
  if (const cudaError_t e = cudaGetLastError(); e != cudaSuccess) return e;
  const dim3 block(32, 8), grid(blocks_for(h, 32, 1LL << 30), blocks_for(n, 8, 65535), static_cast<unsigned>(systems));
  weighted_rows_kernel<<<grid, block, 0, stream>>>(h, n, DH, W, Wt);
  return cudaGetLastError();
}

cudaError_t real_hessian_batched(int systems, int n, const double2* R, double count, double* Hv, cudaStream_t stream) {
  if (systems < 1 || systems > kMaxBatchSystems) return cudaErrorInvalidValue;
  const long long N = 4LL * n;
  const dim3 block(32, 8), grid(blocks_for(N, 32, 65535), blocks_for(N, 8, 65535), static_cast<unsigned>(systems));
  real_hessian_kernel<<<grid, block, 0, stream>>>(n, R, count, Hv);
  return cudaGetLastError();
}

cudaError_t max_safe_step_batched(int systems, int G, const double2* ab, const double2* dab, double* part_min, unsigned* done,
                                  double* out, cudaStream_t stream) {
  if (systems < 1 || systems > kMaxBatchSystems) return cudaErrorInvalidValue;
  safe_step_kernel<<<dim3(reduction_blocks(G), static_cast<unsigned>(systems)), kBlock, 0, stream>>>(G, ab, dab, part_min, done, out);
  return cudaGetLastError();
}

cudaError_t hessian_apply(int rows, int G, const int* index, const double* g, const double2* ab, const double2* din,
                          sample::Projection projection, bool exact, double2* out, cudaStream_t stream) {
  hessian_apply_kernel<<<blocks_for(rows, kBlock, 1LL << 30), kBlock, 0, stream>>>(rows, G, index, g, ab, din, projection, exact, out);
  return cudaGetLastError();
}

cudaError_t weighted_rows(int G, int h, int n, const int* H, const double* g, const double2* ab, sample::Projection projection,
                          bool exact, const double2* DH, double2* W, double2* Wt, cudaStream_t stream) {
  return weighted_rows_batched(1, G, h, n, H, g, ab, projection, exact, DH, W, Wt, stream);
}

cudaError_t real_hessian(int n, const double2* R, double count, double* Hv, cudaStream_t stream) {
  return real_hessian_batched(1, n, R, count, Hv, stream);
}

cudaError_t max_safe_step(int G, const double2* ab, const double2* dab, double* part_min, unsigned* done, double* out,
                          cudaStream_t stream) {
  return max_safe_step_batched(1, G, ab, dab, part_min, done, out, stream);
}

cudaError_t dot(int n, const double* a, const double* b, double* out, cudaStream_t stream) {
  dot_kernel<<<1, kBlock, 0, stream>>>(n, a, b, out);
  return cudaGetLastError();
}

cudaError_t diag_abs_max(int n, const double* A, double* out, cudaStream_t stream) {
  return diag_abs_max_batched(1, n, A, 0, out, 0, stream);
}

cudaError_t add_relative_ridge(int n, const double* A0, const double* relative, const double* diag, double* diag_down, double* A,
                               cudaStream_t stream) {
  return add_relative_ridge_batched(1, n, A0, A, 0, relative, 0, diag, diag_down, 0, stream);
}

cudaError_t trial_point(int n, const double* x, const double* d, const double* step, double* out, cudaStream_t stream) {
  return trial_point_batched(1, n, x, d, out, 0, step, 0, stream);
}

cudaError_t horizontal_system(int dim, double* A, const double* a, double* g, double* diag, cudaStream_t stream) {
  return horizontal_system_batched(1, dim, A, 0, a, g, 0, diag, 0, stream);
}

cudaError_t negate(int m, const double* g, double* d, int* info, cudaStream_t stream) { return negate_batched(1, m, g, d, 0, info, 0, stream); }

cudaError_t step_scalars(int dim, int m, bool rotation, const double* a, const double* g, double* d, double* slope, double* gnorm2,
                         const int* info, int* info_out, cudaStream_t stream) {
  step_scalars_kernel<<<1, kBlock, 0, stream>>>(dim, m, rotation, a, g, d, slope, gnorm2, info, info_out, 0, 0);
  return cudaGetLastError();
}

cudaError_t decrement_scalars(int dim, int m, const double* g, const double* y, double* slope, double* gnorm2, const int* info,
                              int* info_out, cudaStream_t stream) {
  return decrement_scalars_batched(1, dim, m, g, y, 0, slope, gnorm2, 0, info, info_out, 0, stream);
}

cudaError_t tall_times_one(int rows, int cols, const double* A, const double* x, double* y, cudaStream_t stream,
                           const TallOptions& o) {
  return tall_times_one_batched(1, rows, cols, A, x, y, stream, o, TallStrides{});
}

namespace {
bool bad_batch(int systems) { return systems < 1 || systems > kMaxBatchSystems; }
}  // namespace

cudaError_t diag_abs_max_batched(int systems, int n, const double* A, long long A_stride, double* out, long long out_stride,
                                 cudaStream_t stream) {
  if (bad_batch(systems)) return cudaErrorInvalidValue;
  diag_max_kernel<<<static_cast<unsigned>(systems), kBlock, 0, stream>>>(n, A, out, A_stride, out_stride);
  return cudaGetLastError();
}

cudaError_t add_relative_ridge_batched(int systems, int n, const double* A0, double* A, long long mat_stride, const double* relative,
                                       long long relative_stride, const double* diag, double* diag_down, long long scalar_stride,
                                       cudaStream_t stream) {
  if (bad_batch(systems)) return cudaErrorInvalidValue;
  const long long total = static_cast<long long>(n) * n;
  const unsigned x = static_cast<unsigned>(std::min<long long>((total + 255) / 256, systems > 1 ? 512 : 4096));
  add_relative_ridge_kernel<<<dim3(x, static_cast<unsigned>(systems)), 256, 0, stream>>>(n, A0, relative, diag, diag_down, A, mat_stride,
                                                                                         relative_stride, scalar_stride);
  return cudaGetLastError();
}

cudaError_t trial_point_batched(int systems, int n, const double* x, const double* d, double* out, long long vec_stride, const double* step,
                                long long step_stride, cudaStream_t stream) {
  if (bad_batch(systems)) return cudaErrorInvalidValue;
  trial_point_kernel<<<dim3(static_cast<unsigned>((n + kBlock - 1) / kBlock), static_cast<unsigned>(systems)), kBlock, 0, stream>>>(
      n, x, d, step, out, vec_stride, step_stride);
  return cudaGetLastError();
}

cudaError_t horizontal_system_batched(int systems, int dim, double* A, long long mat_stride, const double* a, double* g,
                                      long long vec_stride, double* diag, long long diag_stride, cudaStream_t stream) {
  if (bad_batch(systems)) return cudaErrorInvalidValue;
  const int m = dim + 1;
  const dim3 block(32, 8), grid(blocks_for(dim, 32, 65535), blocks_for(dim, 8, 65535), static_cast<unsigned>(systems));
  horizontal_block_kernel<<<grid, block, 0, stream>>>(dim, m, A, a, mat_stride, vec_stride);
  if (const cudaError_t e = cudaGetLastError(); e != cudaSuccess) return e;
  horizontal_clear_diag_kernel<<<static_cast<unsigned>(systems), kBlock, 0, stream>>>(dim, m, A, a, g, diag, mat_stride, vec_stride,
                                                                                       diag_stride);
  return cudaGetLastError();
}

cudaError_t horizontal_gradient_batched(int systems, int dim, const double* a, double* g, long long vec_stride, cudaStream_t stream) {
  if (bad_batch(systems)) return cudaErrorInvalidValue;
  horizontal_gradient_kernel<<<static_cast<unsigned>(systems), kBlock, 0, stream>>>(dim, a, g, vec_stride);
  return cudaGetLastError();
}

cudaError_t negate_batched(int systems, int m, const double* g, double* d, long long vec_stride, int* info, long long info_stride,
                           cudaStream_t stream) {
  if (bad_batch(systems)) return cudaErrorInvalidValue;
  negate_kernel<<<dim3(blocks_for(m, kBlock, 65535), static_cast<unsigned>(systems)), kBlock, 0, stream>>>(m, g, d, info, vec_stride,
                                                                                                          info_stride);
  return cudaGetLastError();
}

cudaError_t step_scalars_batched(int systems, int dim, int m, bool rotation, const double* a, const double* g, double* d,
                                 long long vec_stride, double* slope, double* gnorm2, long long scalar_stride, cudaStream_t stream) {
  if (bad_batch(systems)) return cudaErrorInvalidValue;
  step_scalars_kernel<<<static_cast<unsigned>(systems), kBlock, 0, stream>>>(dim, m, rotation, a, g, d, slope, gnorm2, nullptr, nullptr,
                                                                            vec_stride, scalar_stride);
  return cudaGetLastError();
}

cudaError_t decrement_scalars_batched(int systems, int dim, int m, const double* g, const double* y, long long vec_stride, double* slope,
                                      double* gnorm2, long long scalar_stride, const int* info, int* info_out, long long info_stride,
                                      cudaStream_t stream) {
  if (bad_batch(systems)) return cudaErrorInvalidValue;
  decrement_scalars_kernel<<<static_cast<unsigned>(systems), kBlock, 0, stream>>>(dim, m, g, y, slope, gnorm2, info, info_out, vec_stride,
                                                                                 scalar_stride, info_stride);
  return cudaGetLastError();
}

cudaError_t tall_times_one_batched(int systems, int rows, int cols, const double* A, const double* x, double* y, cudaStream_t stream,
                                   const TallOptions& o, const TallStrides& strides) {
  if (bad_batch(systems)) return cudaErrorInvalidValue;
  const int rows1 = o.second_A ? o.second_rows : 0;
  const RealProduct p0{A, o.y0, y, rows}, p1{o.second_A ? o.second_A : A, nullptr, o.second_A ? o.second_y : y, rows1};
  const dim3 block(kTallRows, kOneSlices);
  const dim3 grid(blocks_for(std::max(rows, rows1), kTallRows, 1LL << 30), static_cast<unsigned>(systems), o.second_A ? 2 : 1);
  tall_times_one_kernel<<<grid, block, 0, stream>>>(p0, p1, cols, x, o.dx, o.step, o.x_copy, strides);
  return cudaGetLastError();
}

cudaError_t copy(const CopyList& list, int entries, cudaStream_t stream) {
  if (entries < 1 || entries > CopyList::kMax) return cudaErrorInvalidValue;
  size_t most = 0;
  for (int e = 0; e < entries; ++e) most = std::max(most, list.entry[e].count);
  const dim3 grid(blocks_for(static_cast<long long>(std::max<size_t>(most, 1)), kBlock, 1024), static_cast<unsigned>(entries));
  copy_kernel<<<grid, kBlock, 0, stream>>>(list);
  return cudaGetLastError();
}

cudaError_t tall_times_two(int rows, int k, const double2* A, const double2* B, double2* C, cudaStream_t stream) {
  return tall_times_two_batched(1, rows, k, A, B, C, stream);
}

cudaError_t tall_times_two_batched(int systems, int rows, int k, const double2* A, const double2* B, double2* C, cudaStream_t stream) {
  if (systems < 1 || systems > kMaxBatchSystems) return cudaErrorInvalidValue;
  const dim3 block(kTallRows, kTallSlices), grid(blocks_for(rows, kTallRows, 1LL << 30), static_cast<unsigned>(systems));
  tall_times_two_kernel<<<grid, block, 0, stream>>>(rows, k, A, B, C);
  return cudaGetLastError();
}

cudaError_t tall_adjoint_times_two(int rows, int k, const double2* A, const double2* B, double2* C, cudaStream_t stream,
                                   const ReducedGradient& then) {
  if (k <= 0) return cudaSuccess;
  if (then.g && (!then.T || !then.done || then.m < 1)) return cudaErrorInvalidValue;
  tall_adjoint_times_two_kernel<<<static_cast<unsigned>(k), kAdjointThreads, 0, stream>>>(rows, k, A, B, C, then);
  return cudaGetLastError();
}

cudaError_t blend_metrics(int G, int K, const double* keys, const double* w, bool exponential, double* g, cudaStream_t stream) {
  blend_metrics_kernel<<<static_cast<unsigned>((G + kBlock - 1) / kBlock), kBlock, 0, stream>>>(G, K, keys, w, exponential, g);
  return cudaGetLastError();
}

}  // namespace hsi::cuda::kernels
