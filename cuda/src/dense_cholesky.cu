// Dense Cholesky factor and solve for the Newton system (see dense_cholesky.h).
//
// Factor, m ≤ kCholeskyClusterMaxOrder: one kernel, a cluster of 8 blocks holding the
// matrix in shared memory (factor_cluster below). Factor, larger m: right-looking over
// 32-column tiles with a look-ahead of one, one launch per column tile c. Launch c (a) factors column tile c: every block of tile row i ≥ c
// applies panel c − 1's update to A_cc and A_ic itself, factors A_cc in registers of
// one warp (redundantly in each block, 32 × 32 is cheap) and solves its A_ic against it;
// (b) applies panel c − 1 to the trailing tiles (i, j), j ≥ c + 1; (c) stores L_c−1,c−1,
// which launch c − 1 could not (its blocks were reading A_c−1,c−1). No block reads what
// another block of the same launch writes, so launches are the only synchronisation.
// Solve, m ≤ kCholeskySolveClusterMaxOrder: one kernel, a cluster of 8 blocks holding L in
// shared memory (solve_cluster below). Solve, larger m (and the back substitution after
// the fused factor): one block; warp w owns the tile rows ≡ w (mod 8) and substitutes them in
// order, waiting on a per-tile ready flag in shared memory for the tiles it needs
// (forward L y = b from the top, then back Lᵀ x = y from the bottom); the diagonal
// tiles are applied as explicit inverses, made by each owner before it waits.
#include "dense_cholesky.h"

#include <cooperative_groups.h>

#include <atomic>
#include <cfloat>
#include <cstddef>

namespace hsi::cuda::kernels {
namespace {

constexpr int kT = kCholeskyTile;
constexpr int kFactorThreads = 256;  // 8 warps: 4 outputs each of a 32 × 32 tile product
constexpr int kSolveThreads = 256;   // 8 warps, each up to 255 registers (two 32-entry rows)
constexpr int kSolveWarps = kSolveThreads / 32;
constexpr unsigned kFull = 0xffffffffu;
static_assert(kT == 32, "the tile kernels map one lane to one tile row");
static_assert(kFactorThreads == 8 * kT, "subtract_product maps 8 warps x 4 rows");

using Tile = double[kT][kT + 1];  // padded: column walks hit 32 different banks

__device__ __forceinline__ double at(const double* A, int lda, int r, int c) {
  return A[static_cast<size_t>(r) + static_cast<size_t>(c) * static_cast<size_t>(lda)];
}

// S = tile (ti, tj) of A, zero outside the m × m matrix. lower_only: a diagonal tile,
// whose strictly upper part must not be read (it need not hold A) and is set to zero,
// and whose rows past m get a unit diagonal (so the padding factors to I, fails nothing).
__device__ void load_tile(Tile& S, const double* A, int lda, int m, int ti, int tj, bool lower_only) {
  for (int e = static_cast<int>(threadIdx.x); e < kT * kT; e += kFactorThreads) {
    const int r = e & (kT - 1), c = e / kT;  // consecutive threads: consecutive rows (coalesced)
    const int gr = ti * kT + r, gc = tj * kT + c;
    double v = 0.0;
    if (gr < m && gc < m && (!lower_only || r >= c)) v = at(A, lda, gr, gc);
    else if (lower_only && r == c) v = 1.0;
    S[r][c] = v;
  }
}

// Tile (ti, tj) of A = S where inside the matrix (and, lower_only, on or below the diagonal).
__device__ void store_tile(const Tile& S, double* A, int lda, int m, int ti, int tj, bool lower_only) {
  for (int e = static_cast<int>(threadIdx.x); e < kT * kT; e += kFactorThreads) {
    const int r = e & (kT - 1), c = e / kT;
    const int gr = ti * kT + r, gc = tj * kT + c;
    if (gr < m && gc < m && (!lower_only || r >= c))
      A[static_cast<size_t>(gr) + static_cast<size_t>(gc) * static_cast<size_t>(lda)] = S[r][c];
  }
}

// C −= X Yᵀ (32 × 32 × 32). Thread t: column t mod 32, rows t / 32 + 8p. X reads are
// warp-wide broadcasts, Y reads walk a column of the padded tile (no bank conflicts).
__device__ void subtract_product(Tile& C, const Tile& X, const Tile& Y) {
  const int col = static_cast<int>(threadIdx.x) & (kT - 1), r0 = static_cast<int>(threadIdx.x) / kT;
  double acc[4] = {0.0, 0.0, 0.0, 0.0};
#pragma unroll 8
  for (int q = 0; q < kT; ++q) {
    const double y = Y[col][q];
#pragma unroll
    for (int p = 0; p < 4; ++p) acc[p] += X[r0 + 8 * p][q] * y;
  }
#pragma unroll
  for (int p = 0; p < 4; ++p) C[r0 + 8 * p][col] -= acc[p];
}

// D = its Cholesky factor (lower, upper part zeroed), by one warp: lane r holds row r in
// registers, column q's pivot and multipliers travel by shuffle. inv_diag[q] = 1 / L_qq.
// Returns the 1-based column of the first pivot that is not > 0 or not finite, or 0.
// Every lane of warp 0 calls it.
__device__ int factor_diagonal_tile(Tile& D, double* inv_diag) {
  const int lane = static_cast<int>(threadIdx.x) & 31;
  double v[kT];
#pragma unroll
  for (int j = 0; j < kT; ++j) v[j] = j <= lane ? D[lane][j] : 0.0;
  int fail = 0;
#pragma unroll
  for (int q = 0; q < kT; ++q) {
    const double pivot = __shfl_sync(kFull, v[q], q);  // A_qq − Σ_{p<q} L_qp²
    if (fail == 0 && !(pivot > 0.0 && pivot <= DBL_MAX)) fail = q + 1;  // NaN fails both tests
    const double inv = rsqrt(pivot);
    // Lane q: L_qq = √pivot; lanes r > q: L_rq; lanes r < q: unused (their row's upper part).
    const double l = lane == q ? pivot * inv : v[q] * inv;
    v[q] = l;
    if (lane == q) inv_diag[q] = inv;
#pragma unroll
    for (int j = q + 1; j < kT; ++j) v[j] -= l * __shfl_sync(kFull, l, j);  // A_rj −= L_rq L_jq
  }
#pragma unroll
  for (int j = 0; j < kT; ++j) D[lane][j] = j <= lane ? v[j] : 0.0;
  return fail;
}

// B = B L⁻ᵀ (each row x of the result solves x Lᵀ = b) with L = D from
// factor_diagonal_tile; lane r solves row r. Every lane of warp 0 calls it.
__device__ void solve_panel_tile(Tile& B, const Tile& D, const double* inv_diag) {
  const int lane = static_cast<int>(threadIdx.x) & 31;
  double x[kT];
#pragma unroll
  for (int j = 0; j < kT; ++j) x[j] = B[lane][j];
#pragma unroll
  for (int q = 0; q < kT; ++q) {
    x[q] *= inv_diag[q];
#pragma unroll
    for (int p = q + 1; p < kT; ++p) x[p] -= x[q] * D[p][q];  // broadcast reads of column q
  }
#pragma unroll
  for (int j = 0; j < kT; ++j) B[lane][j] = x[j];
}

// D = the diagonal tile (c, c) with panel c − 1's update applied, factored: what every
// block that needs L_cc computes for itself (the same instructions on the same data, so
// the same bits). Y = L_c,c−1 afterwards (c > 0). Returns factor_diagonal_tile's failing
// column. Every thread of the block calls it; the caller's own loads (load_more) join
// the first barrier and its own updates with Y (update_more) the second.
template <class LoadMore, class UpdateMore>
__device__ int factor_diagonal(Tile& D, Tile& Y, double* inv_diag, int* fail, const double* A, int lda, int m, int c,
                               LoadMore load_more, UpdateMore update_more) {
  load_tile(D, A, lda, m, c, c, true);
  if (c > 0) load_tile(Y, A, lda, m, c, c - 1, false);
  load_more();
  __syncthreads();
  if (c > 0) {
    subtract_product(D, Y, Y);  // D −= L_c,c−1 L_c,c−1ᵀ
    update_more();
    __syncthreads();
  }
  if (threadIdx.x < 32) {
    const int f = factor_diagonal_tile(D, inv_diag);
    if (threadIdx.x == 0) *fail = f;
  }
  __syncthreads();
  return *fail;
}

// Launch c of the factorisation (T column tiles). Blocks, in order:
//  - T − c panel blocks, tile rows i = c..T−1 of column tile c: each factors L_cc for
//    itself; i > c then stores L_ic = (A_ic − L_i,c−1 L_c,c−1ᵀ) L_cc⁻ᵀ; i = c only sets
//    *info, and stores L_cc itself when c is the last tile;
//  - for c > 0, one block that stores L_c−1,c−1 (factored again as launch c − 1 did):
//    in launch c − 1 the other panel blocks still read A_c−1,c−1, so nobody wrote it;
//  - the trailing tiles (i, j), c + 1 ≤ j ≤ i < T, column by column: A_ij −= L_i,c−1 L_j,c−1ᵀ.
// No block reads a tile another block of the same launch writes.
__global__ void __launch_bounds__(kFactorThreads) factor_step(int m, double* A, int lda, int* info, int c, int T) {
  __shared__ Tile D, B, X, Y;
  __shared__ double inv_diag[kT];
  __shared__ int fail;
  const int k = c - 1;  // the panel whose update this launch applies (none when c = 0)
  const int panel_blocks = T - c, delayed_blocks = c > 0 ? 1 : 0;
  const int b = static_cast<int>(blockIdx.x);

  if (b >= panel_blocks + delayed_blocks) {  // trailing update: A_ij −= L_ik L_jkᵀ
    int r = b - panel_blocks - delayed_blocks, j = c + 1;
    while (r >= T - j) {
      r -= T - j;
      ++j;
    }
    const int i = j + r;
    load_tile(B, A, lda, m, i, j, i == j);
    load_tile(X, A, lda, m, i, k, false);
    if (i != j) load_tile(Y, A, lda, m, j, k, false);
    __syncthreads();
    subtract_product(B, X, i == j ? X : Y);
    __syncthreads();
    store_tile(B, A, lda, m, i, j, i == j);
    return;
  }

  if (b == panel_blocks) {  // the delayed store of L_kk
    factor_diagonal(D, Y, inv_diag, &fail, A, lda, m, k, [] {}, [] {});
    store_tile(D, A, lda, m, k, k, true);
    return;
  }

  const int i = c + b;  // this block's tile row in column tile c
  const int f = factor_diagonal(
      D, Y, inv_diag, &fail, A, lda, m, c,
      [&] {
        if (i > c) {
          load_tile(B, A, lda, m, i, c, false);
          if (k >= 0) load_tile(X, A, lda, m, i, k, false);
        }
      },
      [&] {
        if (i > c) subtract_product(B, X, Y);  // B = A_ic − L_ik L_ckᵀ, beside D's update
      });
  if (i == c) {
    if (c == T - 1) store_tile(D, A, lda, m, c, c, true);  // no later launch to store it
    // Only this block of each launch touches *info, and launches run in order: launch 0
    // resets it, later ones keep the first failure.
    if (threadIdx.x == 0) {
      if (c == 0) *info = f;
      else if (f != 0 && *info == 0) *info = c * kT + f;
    }
    return;
  }
  if (threadIdx.x < 32) solve_panel_tile(B, D, inv_diag);
  __syncthreads();
  store_tile(B, A, lda, m, i, c, false);
}

// ---- One-kernel factorisation for m ≤ kCholeskyClusterMaxOrder: a cluster of 8 blocks.
// Block r of the cluster owns column tiles j ≡ r (mod 8), and keeps each one's lower part
// (tile rows j..T−1: 32(T − j) rows × 32 columns, column-major, leading dimension
// 32(T − j)) in its shared memory for the whole factorisation. Rows past m hold zero
// (a unit diagonal), so the padding factors to I and fails nothing. Step k (k = 0..T−2),
// with panel k (column tile k, factored) final in its owner's shared memory:
//  1. every block copies L_jk (32 × 32) for each of its own columns j > k from the
//     owner's shared memory (distributed shared memory) into its own;
//  2. every block applies A_ij −= L_ik L_jkᵀ to its own tiles j > k, i ≥ j (L_ik read
//     from the owner's shared memory straight into registers);
//  3. the owner of column tile k + 1 factors it (its diagonal tile by one warp, then its
//     rows below, one per thread);
//  4. cluster.sync(): panel k + 1 is final and visible to the cluster.
// With b (cholesky_factor_solve), b is row m of the lower triangle (the bordered matrix
// [A b; bᵀ 1]): the factor leaves L⁻¹ b in that row, i.e. forward substitution rides
// along, and b gets it back; the bordered pivot m + 1 is not reported.
// Panel k is never written after it is final and a block writes only its own columns, so
// the one cluster barrier per panel is the only synchronisation between blocks.
namespace cg = cooperative_groups;

constexpr int kClusterBlocks = 8;  // the portable maximum of a thread-block cluster
constexpr int kClusterThreads = 256;
constexpr int kClusterWarps = kClusterThreads / 32;
constexpr int kClusterMaxTiles = kCholeskyClusterMaxOrder / kT;
static_assert(kCholeskyClusterMaxOrder % kT == 0);

// Column tiles block `rank` owns (j = rank, rank + 8, ... < T).
__host__ __device__ constexpr int owned_columns(int T, int rank) {
  return rank < T ? (T - 1 - rank) / kClusterBlocks + 1 : 0;
}
// Offset (doubles) of block `rank`'s q-th column tile in its shared memory.
__host__ __device__ constexpr int column_offset(int T, int rank, int q) {
  int offset = 0;
  for (int p = 0; p < q; ++p) offset += kT * kT * (T - rank - kClusterBlocks * p);
  return offset;
}
// Dynamic shared memory of every block: rank 0 owns the most (and the tallest) columns;
// then one 32 × 32 buffer per own column (its L_jk) and 32 reciprocal pivots.
__host__ __device__ constexpr size_t cluster_shared_bytes(int T) {
  const int own = owned_columns(T, 0);
  return sizeof(double) * static_cast<size_t>(column_offset(T, 0, own) + own * kT * kT + kT);
}
static_assert(cluster_shared_bytes(kClusterMaxTiles) <= 227 * 1024, "sm_90's shared memory per block (opt-in)");

// Factor column tile j, held by this block at `col` (leading dimension ld = 32(T − j)):
// its diagonal tile by warp 0 (lane r holds row r, column q's pivot and multipliers by
// shuffle), then its rows below by all threads, one row each (x Lᵀ = a, forward). Sets
// *fail to the 1-based global column of the first bad pivot if *fail is still 0 and that
// column is inside the m × m matrix (the fused solve's pivot m + 1 is not A's). Every
// thread of the block calls it; it ends with a barrier.
__device__ void factor_column(double* col, int ld, int j, double* inv_diag, int* fail, int m) {
  const int tid = static_cast<int>(threadIdx.x);
  if (tid < 32) {
    const int lane = tid;
    double v[kT];
#pragma unroll
    for (int c = 0; c < kT; ++c) v[c] = c <= lane ? col[lane + c * ld] : 0.0;
    int f = 0;
#pragma unroll
    for (int q = 0; q < kT; ++q) {
      const double pivot = __shfl_sync(kFull, v[q], q);  // A_qq − Σ_{p<q} L_qp²
      if (f == 0 && !(pivot > 0.0 && pivot <= DBL_MAX)) f = q + 1;  // NaN fails both tests
      const double inv = rsqrt(pivot);
      const double l = lane == q ? pivot * inv : v[q] * inv;
      v[q] = l;
      if (lane == q) inv_diag[q] = inv;
#pragma unroll
      for (int c = q + 1; c < kT; ++c) v[c] -= l * __shfl_sync(kFull, l, c);  // A_rc −= L_rq L_cq
    }
#pragma unroll
    for (int c = 0; c < kT; ++c) col[lane + c * ld] = c <= lane ? v[c] : 0.0;
    if (lane == 0 && f != 0 && *fail == 0 && j * kT + f <= m) *fail = j * kT + f;  // not the row of b (column m + 1)
  }
  __syncthreads();
  for (int r = kT + tid; r < ld; r += kClusterThreads) {
    double x[kT];
#pragma unroll
    for (int c = 0; c < kT; ++c) x[c] = col[r + c * ld];  // consecutive threads, consecutive rows
#pragma unroll
    for (int q = 0; q < kT; ++q) {
      x[q] *= inv_diag[q];
#pragma unroll
      for (int p = q + 1; p < kT; ++p) x[p] -= x[q] * col[p + q * ld];  // broadcast reads of L_pq
    }
#pragma unroll
    for (int c = 0; c < kT; ++c) col[r + c * ld] = x[c];
  }
  __syncthreads();
}

__global__ void __cluster_dims__(kClusterBlocks, 1, 1) __launch_bounds__(kClusterThreads)
    factor_cluster(int m, double* A, int lda, double* b, int* info, int T, long long stride_a, long long stride_b) {
  // Matrix blockIdx.y of a strided batch (cholesky_factor_batched; one matrix: y = 0).
  A += static_cast<long long>(blockIdx.y) * stride_a;
  if (b != nullptr) b += static_cast<long long>(blockIdx.y) * stride_b;
  info += blockIdx.y;
  extern __shared__ double smem[];
  __shared__ int fail;
  const cg::cluster_group cluster = cg::this_cluster();
  const int rank = static_cast<int>(cluster.block_rank());
  const int tid = static_cast<int>(threadIdx.x), lane = tid & 31, warp = tid / 32;
  const int own = owned_columns(T, rank);
  double* const ybuf = smem + column_offset(T, rank, own);  // own × (32 × 32), column-major
  double* const inv_diag = ybuf + own * kT * kT;
  auto global_column = [&](int q) { return rank + kClusterBlocks * q; };
  auto height = [&](int j) { return kT * (T - j); };

  // Load the own columns' lower parts; zero above the diagonal and past m, 1 on the
  // diagonal past m.
  for (int q = 0; q < own; ++q) {
    const int j = global_column(q), ld = height(j);
    double* const col = smem + column_offset(T, rank, q);
    for (int e = tid; e < ld * kT; e += kClusterThreads) {
      const int gr = j * kT + e % ld, gc = j * kT + e / ld;
      double v = gr == gc ? 1.0 : 0.0;
      if (gr < m && gc < m && gr >= gc) v = A[static_cast<size_t>(gr) + static_cast<size_t>(gc) * lda];
      else if (b != nullptr && gr == m && gc < m) v = b[gc];  // [A | b] factored: row m of L becomes (L⁻¹ b)ᵀ
      col[e] = v;
    }
  }
  if (tid == 0) fail = 0;
  __syncthreads();
  if (rank == 0) factor_column(smem, height(0), 0, inv_diag, &fail, m);
  cluster.sync();

  for (int k = 0; k + 1 < T; ++k) {
    const int owner = k % kClusterBlocks, ldp = height(k);
    const double* const panel = cluster.map_shared_rank(smem, owner) + column_offset(T, owner, k / kClusterBlocks);
    // Own columns right of k: q0..own−1.
    const int q0 = rank > k ? 0 : (k - rank) / kClusterBlocks + 1;
    // 1. Y_q = L_jk (row c of tile j, column p at ybuf[q][c + 32p]).
    for (int e = tid; e < (own - q0) * kT * kT; e += kClusterThreads) {
      const int q = q0 + e / (kT * kT), c = e % kT, p = (e / kT) % kT;
      ybuf[q * kT * kT + c + p * kT] = panel[(global_column(q) - k) * kT + c + p * ldp];
    }
    __syncthreads();
    // 2. A_ij −= L_ik L_jkᵀ: items (q, i), i = j..T−1, over the warps; lane r: row 32i + r.
    int items = 0;
    for (int q = q0; q < own; ++q) items += T - global_column(q);
    for (int item = warp; item < items; item += kClusterWarps) {
      int q = q0, i = item;
      while (i >= T - global_column(q)) {
        i -= T - global_column(q);
        ++q;
      }
      const int j = global_column(q);
      i += j;
      double x[kT];
#pragma unroll
      for (int p = 0; p < kT; ++p) x[p] = panel[(i - k) * kT + lane + p * ldp];  // L_ik, row `lane`
      double* const c_tile = smem + column_offset(T, rank, q) + (i - j) * kT + lane;
      const double* const y = ybuf + q * kT * kT;
      const int ld = height(j);
#pragma unroll 4
      for (int c = 0; c < kT; ++c) {
        double s0 = 0.0, s1 = 0.0;
#pragma unroll
        for (int p = 0; p < kT; p += 2) {
          s0 += x[p] * y[c + p * kT];  // broadcast reads
          s1 += x[p + 1] * y[c + (p + 1) * kT];
        }
        c_tile[c * ld] -= s0 + s1;
      }
    }
    __syncthreads();
    // 3. The owner of column tile k + 1 factors it.
    if ((k + 1) % kClusterBlocks == rank) {
      const int q = (k + 1) / kClusterBlocks;
      factor_column(smem + column_offset(T, rank, q), height(k + 1), k + 1, inv_diag, &fail, m);
    }
    // 4. Panel k + 1 final; every block is also done reading panel k.
    cluster.sync();
  }

  // Store the own columns' lower parts inside the matrix.
  for (int q = 0; q < own; ++q) {
    const int j = global_column(q), ld = height(j);
    const double* const col = smem + column_offset(T, rank, q);
    for (int e = tid; e < ld * kT; e += kClusterThreads) {
      const int gr = j * kT + e % ld, gc = j * kT + e / ld;
      if (gr < m && gc < m && gr >= gc) A[static_cast<size_t>(gr) + static_cast<size_t>(gc) * lda] = col[e];
      else if (b != nullptr && gr == m && gc < m) b[gc] = col[e];
    }
  }
  // *info: the first failing column over the cluster (a failure leaves only later
  // columns garbage, so the smallest is the first). Block 0 reads the others' `fail`,
  // which must stay alive until it has: a barrier on each side.
  cluster.sync();
  if (rank == 0 && tid == 0) {
    int first = 0;
    for (int r = 0; r < kClusterBlocks; ++r) {
      const int f = *cluster.map_shared_rank(&fail, static_cast<unsigned>(r));
      if (f != 0 && (first == 0 || f < first)) first = f;
    }
    *info = first;
  }
  cluster.sync();
}

// Flags between warps, of one block (the one-block solve) or of a cluster (the cluster
// solve). The hand-off is PTX's release/acquire pattern: every lane of the publishing warp
// writes its values, the warp barrier orders those writes before the flag lane's release
// store (release is cumulative over what the barrier ordered before it), and a waiting
// lane's acquire load that sees the flag orders every read after it. A fence in each
// writing lane before the barrier would order that lane's own writes only before its own
// later stores, not before another lane's flag.
enum class Scope { Cta, Cluster };
template <Scope S>
__device__ __forceinline__ int load_acquire(const int* flag) {
  int v;
  if constexpr (S == Scope::Cta)
    asm volatile("ld.acquire.cta.u32 %0, [%1];" : "=r"(v) : "l"(flag) : "memory");
  else
    asm volatile("ld.acquire.cluster.u32 %0, [%1];" : "=r"(v) : "l"(flag) : "memory");
  return v;
}
template <Scope S>
__device__ __forceinline__ void store_release(int* flag, int v) {
  if constexpr (S == Scope::Cta)
    asm volatile("st.release.cta.u32 [%0], %1;" ::"l"(flag), "r"(v) : "memory");
  else
    asm volatile("st.release.cluster.u32 [%0], %1;" ::"l"(flag), "r"(v) : "memory");
}
// Waits for a flag another warp raises. A flag that never comes is a bug of this file;
// the kernel then traps (a launch error at the next synchronisation) after 2^27 polls
// (about a second) instead of hanging the device.
template <Scope S>
__device__ __forceinline__ void wait_flag(const int* flag) {
  for (long long polls = 0; load_acquire<S>(flag) == 0; ++polls)
    if (polls > (1LL << 27)) __trap();
}
__device__ __forceinline__ void publish_ready(int* flag) {
  __syncwarp();  // every lane's values written
  if ((threadIdx.x & 31) == 0) store_release<Scope::Cta>(flag, 1);
}

// x = row `lane` of the inverse of a 32 × 32 triangular tile T whose row `lane` this lane
// holds in t (zero off the triangle and on the diagonal) with inv_d = 1 / T_rr. Lower:
// row p of T⁻¹ is final once rows q < p are (so p ascends); upper: p descends. Each row,
// once final, is broadcast and eliminated from the rows beyond it.
template <bool kLower>
__device__ __forceinline__ void invert_triangular_tile(const double (&t)[kT], double inv_d, double (&x)[kT]) {
  const int lane = static_cast<int>(threadIdx.x) & 31;
#pragma unroll
  for (int j = 0; j < kT; ++j) x[j] = j == lane ? 1.0 : 0.0;
#pragma unroll
  for (int step = 0; step < kT; ++step) {
    const int p = kLower ? step : kT - 1 - step;
    if (lane == p) {
#pragma unroll
      for (int j = 0; j < kT; ++j) x[j] *= inv_d;
    }
    // Row p of T⁻¹ is zero outside j ≤ p (lower) or j ≥ p (upper); t[p] is zero on p's
    // own side of the diagonal and at p, so only the rows beyond p change.
#pragma unroll
    for (int j = kLower ? 0 : p; j <= (kLower ? p : kT - 1); ++j) x[j] -= t[p] * __shfl_sync(kFull, x[j], p);
  }
}

// Σ_c x[c] · (lane c's v): row `lane` of a 32 × 32 matrix times the warp's vector.
__device__ __forceinline__ double row_times_warp_vector(const double (&x)[kT], double v) {
  double s0 = 0.0, s1 = 0.0;
#pragma unroll
  for (int c = 0; c < kT; c += 2) {
    s0 += x[c] * __shfl_sync(kFull, v, c);
    s1 += x[c + 1] * __shfl_sync(kFull, v, c + 1);
  }
  return s0 + s1;
}

// Which substitutions run (Substitution): Back alone when b already holds L⁻¹ b
// (cholesky_factor_solve, or a Forward call before).
__global__ void __launch_bounds__(kSolveThreads)
    solve_kernel(int m, const double* __restrict__ L, int lda, double* b, int T, Substitution part) {
  const bool forward = part != Substitution::Back, back = part != Substitution::Forward;
  extern __shared__ double y[];  // 32T entries (zero past m), then the forward and back flags
  int* const ready_fwd = reinterpret_cast<int*>(y + kT * T);
  int* const ready_bwd = ready_fwd + T;
  for (int e = static_cast<int>(threadIdx.x); e < kT * T; e += kSolveThreads) y[e] = e < m ? b[e] : 0.0;
  for (int e = static_cast<int>(threadIdx.x); e < 2 * T; e += kSolveThreads) ready_fwd[e] = 0;
  __syncthreads();
  const int lane = static_cast<int>(threadIdx.x) & 31, warp = static_cast<int>(threadIdx.x) / 32;
  double l[kT], x[kT];  // a row of L's tile; a row of the diagonal tile's inverse

  // Forward: y_i = L_ii⁻¹ (b_i − Σ_{s<i} L_is y_s); lane r holds row 32i + r. L_ii⁻¹ is
  // made before the first wait, off the critical path, so that a tile's last step is
  // one update and one 32 × 32 product instead of 32 dependent substitution steps.
  for (int i = warp; forward && i < T; i += kSolveWarps) {
    const int row = i * kT + lane;
    const bool valid = row < m;
#pragma unroll
    for (int c = 0; c < kT; ++c) l[c] = valid && c < lane ? __ldg(L + row + static_cast<size_t>(i * kT + c) * lda) : 0.0;
    invert_triangular_tile<true>(l, valid ? 1.0 / __ldg(L + row + static_cast<size_t>(row) * lda) : 1.0, x);
    double acc = valid ? y[row] : 0.0;
    for (int s = 0; s < i; ++s) {
#pragma unroll
      for (int c = 0; c < kT; ++c) l[c] = valid ? __ldg(L + row + static_cast<size_t>(s * kT + c) * lda) : 0.0;  // coalesced
      wait_flag<Scope::Cta>(ready_fwd + s);
#pragma unroll
      for (int c = 0; c < kT; ++c) acc -= l[c] * y[s * kT + c];  // broadcast reads
    }
    acc = row_times_warp_vector(x, acc);
    if (valid) y[row] = acc;
    publish_ready(ready_fwd + i);
  }
  __syncthreads();

  // Back: x_i = L_ii⁻ᵀ (y_i − Σ_{s>i} L_siᵀ x_s), from the last tile row up; lane r holds
  // row r of L_iiᵀ (column 32i + r of L: strided across lanes, each 32-byte sector
  // serving 4 rows from L1).
  if (back && warp < T) {
    for (int i = warp + ((T - 1 - warp) / kSolveWarps) * kSolveWarps; i >= 0; i -= kSolveWarps) {
      const int row = i * kT + lane;
      const bool valid = row < m;
#pragma unroll
      for (int c = 0; c < kT; ++c)
        l[c] = valid && c > lane && i * kT + c < m ? __ldg(L + (i * kT + c) + static_cast<size_t>(row) * lda) : 0.0;
      invert_triangular_tile<false>(l, valid ? 1.0 / __ldg(L + row + static_cast<size_t>(row) * lda) : 1.0, x);
      double acc = valid ? y[row] : 0.0;
      for (int s = T - 1; s > i; --s) {
#pragma unroll
        for (int c = 0; c < kT; ++c)
          l[c] = valid && s * kT + c < m ? __ldg(L + (s * kT + c) + static_cast<size_t>(row) * lda) : 0.0;
        wait_flag<Scope::Cta>(ready_bwd + s);
#pragma unroll
        for (int c = 0; c < kT; ++c) acc -= l[c] * y[s * kT + c];
      }
      acc = row_times_warp_vector(x, acc);
      if (valid) y[row] = acc;
      publish_ready(ready_bwd + i);
    }
  }
  __syncthreads();
  for (int e = static_cast<int>(threadIdx.x); e < m; e += kSolveThreads) b[e] = y[e];
}


// ---- The solve for m ≤ kCholeskySolveClusterMaxOrder: one cluster of 8 blocks that
// holds L in shared memory. The one-block solve above reads L from global memory with
// one block's few loads in flight (~58 µs at m = 292 on an H100, no faster than
// cuSOLVER's potrs); here 8 blocks load it at once. Block r owns the tile rows i ≡ r
// (mod 8): L_i0 … L_ii, each tile 32 × 32 column-major with column stride 33, the
// diagonal tile replaced by its inverse once loaded. Warp q of a block substitutes its
// q-th own tile row, so every tile row has a warp of its own and the substitution is a
// dataflow between warps:
//  - forward, y_i = L_ii⁻¹ (b_i − Σ_{s<i} L_is y_s): the warp subtracts each y_s as soon
//    as it is published (in order of s), then pushes y_i into every block's copy of y
//    and raises that block's flag for i;
//  - back, x_i = L_ii⁻ᵀ (y_i − Σ_{j>i} L_jiᵀ x_j): row j's warp, once it has x_j, makes
//    each L_jiᵀ x_j (i = j − 1 first: the next row waits for it) and pushes it into a
//    slot of row i's block; row i sums its slots in order of j once each has arrived.
// Every sum runs in a fixed order, so the result does not depend on timing. A flag is
// raised by a release store after the warp's barrier that follows the data it guards,
// and read by an acquire load before the data (wait_flag); flags are cleared and the
// cluster synchronised before any push, and again before any block exits (no block's
// shared memory may go while others write it).
constexpr int kSolveClusterThreads = 256;  // all load L; warps 0..(own rows − 1) substitute
constexpr int kSolveClusterMaxTiles = kCholeskySolveClusterMaxOrder / kT;
constexpr int kTileStride = kT + 1;        // column stride of a tile in shared memory
constexpr int kTileDoubles = kT * kTileStride;
static_assert(kCholeskySolveClusterMaxOrder % kT == 0);
static_assert(kSolveClusterMaxTiles <= kClusterBlocks * (kSolveClusterThreads / 32), "a warp per own tile row");

// Tile rows block `rank` owns (i = rank, rank + 8, ... < T) and where its q-th one starts
// (in tiles: row i has i + 1 of them).
__host__ __device__ constexpr int solve_owned_rows(int T, int rank) {
  return rank < T ? (T - 1 - rank) / kClusterBlocks + 1 : 0;
}
__host__ __device__ constexpr int solve_row_offset(int rank, int q) {
  int offset = 0;
  for (int p = 0; p < q; ++p) offset += rank + kClusterBlocks * p + 1;
  return offset;
}
// Dynamic shared memory, the same layout in every block (a block writes into another's
// at the same offsets, cluster.map_shared_rank): first what the others write, a copy of
// y (32T doubles) and a slot of 32 per own row and source row (the back substitution's
// L_jiᵀ x_j; rank 0 owns the most rows), then the flags (T for y, then one per slot;
// an even count keeps the tiles 8-byte aligned), then the block's own tile rows.
__host__ __device__ constexpr int solve_slot_rows(int T) { return solve_owned_rows(T, 0); }
__host__ __device__ constexpr int solve_flag_count(int T) { return (T + solve_slot_rows(T) * T + 1) / 2 * 2; }
__host__ __device__ constexpr size_t solve_header_doubles(int T) {
  return static_cast<size_t>(kT) * T + static_cast<size_t>(solve_slot_rows(T)) * T * kT + static_cast<size_t>(solve_flag_count(T)) / 2;
}
__host__ __device__ constexpr size_t solve_cluster_bytes(int T, int rank) {
  return sizeof(double) *
         (solve_header_doubles(T) + static_cast<size_t>(solve_row_offset(rank, solve_owned_rows(T, rank))) * kTileDoubles);
}
// The most any block of the cluster asks for (every block gets the same amount).
__host__ __device__ constexpr size_t solve_cluster_shared_bytes(int T) {
  size_t most = 0;
  for (int r = 0; r < kClusterBlocks; ++r) most = solve_cluster_bytes(T, r) > most ? solve_cluster_bytes(T, r) : most;
  return most;
}
static_assert(solve_cluster_shared_bytes(kSolveClusterMaxTiles) <= 227 * 1024, "sm_90's shared memory per block (opt-in)");

// The flags between the cluster's warps: load_acquire / store_release / wait_flag above
// at cluster scope. A publishing warp's lanes write their values (into this or another
// block's shared memory), __syncwarp, and then the lane that raises a flag does so with a
// release store, which covers every lane's writes the barrier ordered before it.

__global__ void __cluster_dims__(kClusterBlocks, 1, 1) __launch_bounds__(kSolveClusterThreads)
    solve_cluster(int m, const double* __restrict__ L, int lda, double* b, int T, Substitution part, long long stride_l,
                  long long stride_b) {
  // Matrix blockIdx.y of a strided batch (cholesky_solve_batched; one matrix: y = 0).
  L += static_cast<long long>(blockIdx.y) * stride_l;
  b += static_cast<long long>(blockIdx.y) * stride_b;
  const bool forward = part != Substitution::Back, back = part != Substitution::Forward;
  extern __shared__ double smem[];
  const cg::cluster_group cluster = cg::this_cluster();
  const int rank = static_cast<int>(cluster.block_rank());
  const int tid = static_cast<int>(threadIdx.x), lane = tid & 31, warp = tid / 32;
  const int own = solve_owned_rows(T, rank);
  double* const ycopy = smem;
  double* const slots = ycopy + kT * T;
  int* const yflag = reinterpret_cast<int*>(slots + solve_slot_rows(T) * T * kT);
  int* const sflag = yflag + T;
  double* const tiles = smem + solve_header_doubles(T);

  // Own tile rows of L: the lower triangle inside the matrix, 1 on the diagonal past m,
  // 0 elsewhere (the strictly upper triangle is never read). Consecutive threads read
  // consecutive rows of a column (coalesced).
  for (int q = 0; q < own; ++q) {
    const int i = rank + kClusterBlocks * q, width = kT * (i + 1);
    double* const row = tiles + static_cast<size_t>(solve_row_offset(rank, q)) * kTileDoubles;
#pragma unroll 4
    for (int e = tid; e < kT * width; e += kSolveClusterThreads) {
      const int r = e & (kT - 1), c = e / kT, gr = i * kT + r;
      double v = gr == c ? 1.0 : 0.0;
      if (gr < m && c < m && c <= gr) v = L[static_cast<size_t>(gr) + static_cast<size_t>(c) * static_cast<size_t>(lda)];
      row[(c / kT) * kTileDoubles + r + (c & (kT - 1)) * kTileStride] = v;
    }
  }
  for (int e = tid; e < solve_flag_count(T); e += kSolveClusterThreads) yflag[e] = 0;  // yflag, then sflag
  __syncthreads();
  // Each warp inverts its own row's diagonal tile in place (lane r: row r).
  if (warp < own) {
    double* const D = tiles + static_cast<size_t>(solve_row_offset(rank, warp) + rank + kClusterBlocks * warp) * kTileDoubles;
    double t[kT], x[kT];
#pragma unroll
    for (int c = 0; c < kT; ++c) t[c] = c < lane ? D[lane + c * kTileStride] : 0.0;
    const double inv_d = 1.0 / D[lane + lane * kTileStride];
    invert_triangular_tile<true>(t, inv_d, x);
#pragma unroll
    for (int c = 0; c < kT; ++c) D[lane + c * kTileStride] = x[c];
  }
  cluster.sync();  // every flag cleared before anyone pushes

  if (warp < own) {
    const int q = warp, i = rank + kClusterBlocks * q, gr = i * kT + lane;
    const double* const row = tiles + static_cast<size_t>(solve_row_offset(rank, q)) * kTileDoubles;
    const double* const inv = row + static_cast<size_t>(i) * kTileDoubles;
    double v[kT];

    // Forward (else b holds y already).
    double acc = gr < m ? b[gr] : 0.0;
    for (int s = 0; forward && s < i; ++s) {
      const double* const t = row + static_cast<size_t>(s) * kTileDoubles;
#pragma unroll
      for (int c = 0; c < kT; ++c) v[c] = t[lane + c * kTileStride];  // row `lane` of L_is
      wait_flag<Scope::Cluster>(yflag + s);
      const double* const ys = ycopy + s * kT;
      double a0 = 0.0, a1 = 0.0, a2 = 0.0, a3 = 0.0;
#pragma unroll
      for (int c = 0; c < kT; c += 4) {  // broadcast reads of y_s
        a0 += v[c] * ys[c];
        a1 += v[c + 1] * ys[c + 1];
        a2 += v[c + 2] * ys[c + 2];
        a3 += v[c + 3] * ys[c + 3];
      }
      acc -= (a0 + a1) + (a2 + a3);
    }
    double y = acc;
    if (forward) {
#pragma unroll
      for (int c = 0; c < kT; ++c) v[c] = inv[lane + c * kTileStride];  // row `lane` of L_ii⁻¹
      y = row_times_warp_vector(v, acc);
      for (int r = 0; r < kClusterBlocks; ++r) cluster.map_shared_rank(ycopy, r)[i * kT + lane] = y;
      __syncwarp();  // every lane's y_i pushed before any flag
      if (lane < kClusterBlocks) store_release<Scope::Cluster>(cluster.map_shared_rank(yflag, lane) + i, 1);
    }
    if (!back) {  // y alone (each warp wrote its own rows only; b's other rows were read by their own warps)
      if (gr < m) b[gr] = y;
    }

    // Back.
    acc = y;
    for (int j = T - 1; back && j > i; --j) {
      wait_flag<Scope::Cluster>(sflag + q * T + j);
      acc -= slots[(q * T + j) * kT + lane];
    }
#pragma unroll
    for (int c = 0; c < kT; ++c) v[c] = inv[c + lane * kTileStride];  // row `lane` of L_ii⁻ᵀ
    const double x = back ? row_times_warp_vector(v, acc) : 0.0;
    if (back && gr < m) b[gr] = x;
    for (int s = i - 1; back && s >= 0; --s) {  // L_isᵀ x_i to row s, the next row first
      const double* const t = row + static_cast<size_t>(s) * kTileDoubles;
#pragma unroll
      for (int c = 0; c < kT; ++c) v[c] = t[c + lane * kTileStride];  // row `lane` of L_isᵀ
      const double contribution = row_times_warp_vector(v, x);
      const int owner = s % kClusterBlocks, qs = s / kClusterBlocks;
      cluster.map_shared_rank(slots, owner)[(qs * T + i) * kT + lane] = contribution;
      __syncwarp();  // every lane's entry pushed before the flag
      if (lane == 0) store_release<Scope::Cluster>(cluster.map_shared_rank(sflag, owner) + qs * T + i, 1);
    }
  }
  cluster.sync();  // no block leaves while another may still write its shared memory
}

int tiles(int m) { return (m + kT - 1) / kT; }

// Whether the current device can run one cluster of `Kernel` (kClusterBlocks blocks of
// `threads`) at `bytes` of dynamic shared memory, the most the kernel asks for, whose
// attribute it sets (sm_90 and up; a GPU partition or MPS share may not place 8 such
// blocks in one GPC). Asked once per device and kernel; a host query only, so it is
// allowed while a stream is being captured.
template <auto Kernel>
bool cluster_available(int threads, size_t bytes) {
  static std::atomic<int> known[64] = {};  // 0 unknown, 1 yes, 2 no (per device ordinal); racing askers agree
  int device = 0;
  if (cudaGetDevice(&device) != cudaSuccess || device < 0 || device >= 64) return false;
  if (known[device] == 0) {
    int clusters = 0;
    cudaLaunchConfig_t config = {};
    config.gridDim = dim3(kClusterBlocks);
    config.blockDim = dim3(static_cast<unsigned>(threads));
    config.dynamicSmemBytes = bytes;
    const bool ok = cudaFuncSetAttribute(Kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, static_cast<int>(bytes)) == cudaSuccess &&
                    cudaOccupancyMaxActiveClusters(&clusters, Kernel, &config) == cudaSuccess && clusters >= 1;
    (void)cudaGetLastError();  // a refused query leaves no error behind
    known[device] = ok ? 1 : 2;
  }
  return known[device] == 1;
}

// factor_cluster at its largest T; otherwise the tiled kernels factor every m.
bool cluster_factor_available() { return cluster_available<factor_cluster>(kClusterThreads, cluster_shared_bytes(kClusterMaxTiles)); }
// solve_cluster at its largest T; otherwise the one-block kernel solves every m.
bool cluster_solve_available() {
  return cluster_available<solve_cluster>(kSolveClusterThreads, solve_cluster_shared_bytes(kSolveClusterMaxTiles));
}

size_t solve_shared_bytes(int T) { return static_cast<size_t>(T) * (kT * sizeof(double) + 2 * sizeof(int)); }

}  // namespace

cudaError_t cholesky_factor(int m, double* A, int lda, int* info, cudaStream_t stream) {
  if (m < 0 || lda < (m > 1 ? m : 1)) return cudaErrorInvalidValue;
  if (m == 0) return cudaMemsetAsync(info, 0, sizeof(int), stream);
  const int T = tiles(m);
  if (m <= kCholeskyClusterMaxOrder && cluster_factor_available()) {
    // cluster_factor_available() set the attribute for the largest T.
    const size_t bytes = cluster_shared_bytes(T);
    factor_cluster<<<kClusterBlocks, kClusterThreads, bytes, stream>>>(m, A, lda, nullptr, info, T, 0, 0);
    return cudaGetLastError();
  }
  for (int c = 0; c < T; ++c) {
    const int rest = T - 1 - c;  // column tiles right of c
    const int blocks = (T - c) + (c > 0 ? 1 + rest * (rest + 1) / 2 : 0);  // panel, delayed L_c−1,c−1, trailing
    factor_step<<<blocks, kFactorThreads, 0, stream>>>(m, A, lda, info, c, T);
    if (const cudaError_t e = cudaGetLastError(); e != cudaSuccess) return e;
  }
  return cudaSuccess;
}

cudaError_t cholesky_solve(int m, const double* L, int lda, double* b, cudaStream_t stream, Substitution part) {
  if (m < 0 || lda < (m > 1 ? m : 1) || m > kCholeskySolveMaxOrder) return cudaErrorInvalidValue;
  if (m == 0) return cudaSuccess;
  const int T = tiles(m);
  static_assert(kCholeskySolveMaxOrder % kT == 0);
  static_assert((kCholeskySolveMaxOrder / kT) * (kT * sizeof(double) + 2 * sizeof(int)) <= 48 * 1024,
                "the solve's shared memory must fit the default 48 KiB");
  if (cholesky_solve_in_cluster(m)) {
    solve_cluster<<<kClusterBlocks, kSolveClusterThreads, solve_cluster_shared_bytes(T), stream>>>(m, L, lda, b, T, part, 0, 0);
    return cudaGetLastError();
  }
  solve_kernel<<<1, kSolveThreads, solve_shared_bytes(T), stream>>>(m, L, lda, b, T, part);
  return cudaGetLastError();
}

bool cholesky_solve_in_cluster(int m) { return m > 0 && m <= kCholeskySolveClusterMaxOrder && cluster_solve_available(); }

cudaError_t cholesky_factor_solve(int m, double* A, int lda, double* b, int* info, cudaStream_t stream) {
  if (m < 0 || lda < (m > 1 ? m : 1) || m > kCholeskySolveMaxOrder) return cudaErrorInvalidValue;
  if (m == 0) return cudaMemsetAsync(info, 0, sizeof(int), stream);
  if (m + 1 > kCholeskyClusterMaxOrder || !cluster_factor_available()) {  // [A | b] does not fit: factor, then solve
    if (const cudaError_t e = cholesky_factor(m, A, lda, info, stream); e != cudaSuccess) return e;
    return cholesky_solve(m, A, lda, b, stream);
  }
  const int T = tiles(m + 1);  // b is row m
  const size_t bytes = cluster_shared_bytes(T);
  factor_cluster<<<kClusterBlocks, kClusterThreads, bytes, stream>>>(m, A, lda, b, info, T, 0, 0);
  if (const cudaError_t e = cudaGetLastError(); e != cudaSuccess) return e;
  solve_kernel<<<1, kSolveThreads, solve_shared_bytes(tiles(m)), stream>>>(m, A, lda, b, tiles(m), Substitution::Back);
  return cudaGetLastError();
}

cudaError_t cholesky_factor_batched(int m, double* A, int lda, long long stride_a, int* info, int batch, cudaStream_t stream) {
  if (m < 0 || lda < (m > 1 ? m : 1) || batch < 0 || batch > 65535 || (batch > 1 && stride_a < static_cast<long long>(lda) * m))
    return cudaErrorInvalidValue;
  if (batch == 0) return cudaSuccess;
  if (m == 0) return cudaMemsetAsync(info, 0, sizeof(int) * static_cast<size_t>(batch), stream);
  if (!cholesky_batched_in_cluster(m)) {  // one matrix after the other
    for (int k = 0; k < batch; ++k)
      if (const cudaError_t e = cholesky_factor(m, A + k * stride_a, lda, info + k, stream); e != cudaSuccess) return e;
    return cudaSuccess;
  }
  const int T = tiles(m);
  factor_cluster<<<dim3(kClusterBlocks, static_cast<unsigned>(batch)), kClusterThreads, cluster_shared_bytes(T), stream>>>(
      m, A, lda, nullptr, info, T, stride_a, 0);
  return cudaGetLastError();
}

cudaError_t cholesky_solve_batched(int m, const double* L, int lda, long long stride_l, double* b, long long stride_b, int batch,
                                   cudaStream_t stream, Substitution part) {
  if (m < 0 || lda < (m > 1 ? m : 1) || m > kCholeskySolveMaxOrder || batch < 0 || batch > 65535 ||
      (batch > 1 && (stride_l < static_cast<long long>(lda) * m || stride_b < m)))
    return cudaErrorInvalidValue;
  if (batch == 0 || m == 0) return cudaSuccess;
  if (!cholesky_solve_in_cluster(m)) {
    for (int k = 0; k < batch; ++k)
      if (const cudaError_t e = cholesky_solve(m, L + k * stride_l, lda, b + k * stride_b, stream, part); e != cudaSuccess) return e;
    return cudaSuccess;
  }
  const int T = tiles(m);
  solve_cluster<<<dim3(kClusterBlocks, static_cast<unsigned>(batch)), kSolveClusterThreads, solve_cluster_shared_bytes(T), stream>>>(
      m, L, lda, b, T, part, stride_l, stride_b);
  return cudaGetLastError();
}

bool cholesky_batched_in_cluster(int m) { return m > 0 && m <= kCholeskyClusterMaxOrder && cluster_factor_available(); }

}  // namespace hsi::cuda::kernels
