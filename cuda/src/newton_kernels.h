// The CUDA Newton core's kernels behind plain launch functions (no Eigen on either
// side of this line): each enqueues its work on `stream` and returns the launch
// status. Complex values are double2 (layout of std::complex<double>); vectors over G
// are G × 2 column-major pairs ([a | b], [da | db], [∂E/∂a | ∂E/∂b]); target metrics
// are (g1, g2, g3) per sample.
#pragma once

#include <cuda_runtime.h>

#include "sample_math.cuh"

namespace hsi::cuda::kernels {

constexpr int kBlock = 256;         // threads per block of the sample kernels
constexpr int kMaxPartials = 1024;  // most blocks (= partial results) of a reduction
constexpr int kMaxSteps = 4;        // most steps of one mean_energies call

// The number of partials a reduction over `count` samples writes (≤ kMaxPartials);
// scratch arrays for partials need this many entries.
unsigned reduction_blocks(int count);

// Whether this build's kernels can run on the current device (cudaSuccess if so).
cudaError_t loadable();

// D_H = the rows H of D (G × n), column-major |H| × n.
cudaError_t gather_rows(int G, int h, int n, const double2* D, const int* H, double2* DH, cudaStream_t stream);

// The reductions below are one launch each: every block writes its partial results,
// and the block that finishes last (counted on `done`, a device counter that must be 0
// before the launch and is 0 again after it) sums them in a fixed order, so the result
// is deterministic. Launches that share a counter must not overlap (one stream).
//
// *out = mean over G of the sample energies at a + s·da, b + s·db (dab unread when
// s = 0), +inf if any sample is folded or degenerate. part_sum and part_bad:
// reduction_blocks(G) entries each.
cudaError_t mean_energy(int G, const double* g, const double2* ab, const double2* dab, double s, double* part_sum,
                        int* part_bad, unsigned* done, double* out, cudaStream_t stream);

// out[k] = mean_energy at steps[k] for k < count ≤ kMaxSteps, the steps read from device
// memory (so that a CUDA graph replays it with new steps); each value bit for bit what
// mean_energy gives. part_sum and part_bad: count · reduction_blocks(G) entries.
cudaError_t mean_energies(int G, const double* g, const double2* ab, const double2* dab, const double* steps, int count,
                          double* part_sum, int* part_bad, unsigned* done, double* out, cudaStream_t stream);

// gab = per-sample (∂e/∂Re a + i ∂e/∂Im a, ∂e/∂Re b + i ∂e/∂Im b); zero where e = +inf.
cudaError_t gradient_samples(int G, const double* g, const double2* ab, double2* gab, cudaStream_t stream);

// Per H-sample projected 4×4 Hessian → six complex weights W (6 × h) → the weighted
// rows Wt (h × 6n, column-major): column block q is w_q ∘ D_H (q even) or w_q ∘ conj(D_H).
cudaError_t weighted_rows(int G, int h, int n, const int* H, const double* g, const double2* ab, sample::Projection projection,
                          bool exact, const double2* DH, double2* W, double2* Wt, cudaStream_t stream);

// out (rows × 2) = per row k the 4×4 Hessian of sample index[k] (k without an index; the
// weights weighted_rows makes) applied to (Re, Im) of din's [da | db] row k (rows × 2):
// with din = D_rows p and then D_rowsᴴ out, the Hessian times p (NewtonCore::hessian_times).
cudaError_t hessian_apply(int rows, int G, const int* index, const double* g, const double2* ab, const double2* din,
                          sample::Projection projection, bool exact, double2* out, cudaStream_t stream);

// Hv (4n × 4n, column-major, symmetric) from R = D_Hᴴ Wt (n × 6n) divided by count:
// newton.cpp's real_block layout, then (M + Mᵀ)/2.
cudaError_t real_hessian(int n, const double2* R, double count, double* Hv, cudaStream_t stream);

// *out = min over G of the first s > 0 with |a + s da| = |b + s db| (+inf if none).
// part_min: reduction_blocks(G) entries; done as above.
cudaError_t max_safe_step(int G, const double2* ab, const double2* dab, double* part_min, unsigned* done, double* out,
                          cudaStream_t stream);

// Lockstep batches (issue #23): `systems` Newton systems of one setup (the same G, H, D
// and D_H, each its own targets and point) in one launch per call, so that a batch of
// sequences stepped together pays each kernel's launch and each pass over D once, not
// once per sequence. System s's arrays sit at fixed strides from the pointers given:
// targets g 3G doubles, ab / dab / gab 2G complex (so that the 2·systems columns of one
// ZGEMM D·[c_1 … c_S] are the systems' [a | b] in order), the trial steps `count`, the
// energies out `count`, W 6|H| and Wt |H|·6n complex, R 6n² complex, Hv 16n² doubles,
// the safe steps one; each reduction's partials `count`·reduction_blocks(G) (the safe
// step's reduction_blocks(G)) and its own counter (done[s], all 0 before and after).
// System s's results are bit for bit what the one-system call gives on its arrays: the
// one-system calls above are these with systems = 1.
constexpr int kMaxBatchSystems = 65535;  // a grid's y / z extent
cudaError_t mean_energies_batched(int systems, int G, const double* g, const double2* ab, const double2* dab, const double* steps,
                                  int count, double* part_sum, int* part_bad, unsigned* done, double* out, cudaStream_t stream);
cudaError_t gradient_samples_batched(int systems, int G, const double* g, const double2* ab, double2* gab, cudaStream_t stream);
cudaError_t weighted_rows_batched(int systems, int G, int h, int n, const int* H, const double* g, const double2* ab,
                                  sample::Projection projection, bool exact, const double2* DH, double2* W, double2* Wt,
                                  cudaStream_t stream);
cudaError_t real_hessian_batched(int systems, int n, const double2* R, double count, double* Hv, cudaStream_t stream);
cudaError_t max_safe_step_batched(int systems, int G, const double2* ab, const double2* dab, double* part_min, unsigned* done,
                                  double* out, cudaStream_t stream);
// tall_times_two for each system: C_s = A · B_s (B_s k × 2 at B + 2k·s, C_s rows × 2 at
// C + 2·rows·s), A shared.
cudaError_t tall_times_two_batched(int systems, int rows, int k, const double2* A, const double2* B, double2* C, cudaStream_t stream);

// The reduced system's small helpers (one block each, deterministic):
// *out = Σ a_i b_i; *out = max_i |A_ii| (A n × n column-major; the ridge: add_relative_ridge below).
cudaError_t dot(int n, const double* a, const double* b, double* out, cudaStream_t stream);
cudaError_t diag_abs_max(int n, const double* A, double* out, cudaStream_t stream);
// Every scalar output above may be pinned host memory (mapped at the same address under
// unified addressing): the result then needs no copy.
// Products of a tall complex matrix A (rows × k, column-major) with two columns, as
// ZGEMM computes them but not launch- and split-bound at these shapes: C = A·B (B k × 2,
// C rows × 2) and C = Aᴴ·B (B rows × 2, C k × 2). Deterministic.
cudaError_t tall_times_two(int rows, int k, const double2* A, const double2* B, double2* C, cudaStream_t stream);
// With `then.g`, the same launch's last block (done: the counter of the one-launch
// reductions above) goes on to the reduced gradient g = scale · Tᵀ c (c = C read as 4k
// reals, T 4k × m column-major) and, with `then.a`, the gradient's part of
// horizontal_system (a kept system's, chord steps): g_T −= (g_dim/|u|²) a, then g_dim = 0.
struct ReducedGradient {
  const double* T = nullptr;
  int m = 0;
  double scale = 1;
  double* g = nullptr;
  const double* a = nullptr;
  int dim = 0;
  unsigned* done = nullptr;
};
cudaError_t tall_adjoint_times_two(int rows, int k, const double2* A, const double2* B, double2* C, cudaStream_t stream,
                                   const ReducedGradient& then = {});
// g (G metrics) = Σ_j w_j keys_j, or metric_exp of it with `exponential` (K sets of G
// metrics, w K weights on the device; zero weights skipped). NewtonCore::blend_targets.
cudaError_t blend_metrics(int G, int K, const double* keys, const double* w, bool exponential, double* g, cudaStream_t stream);
// Device-scalar forms for graph replays: A = A0 + (*relative)·max(*diag, 1e-300)·I, and
// *diag copied to *diag_down (NewtonStepper::solve's relative ridge, diag from
// diag_abs_max or horizontal_system); out = x + (*step)·d (n).
cudaError_t add_relative_ridge(int n, const double* A0, const double* relative, const double* diag, double* diag_down, double* A,
                               cudaStream_t stream);
cudaError_t trial_point(int n, const double* x, const double* d, const double* step, double* out, cudaStream_t stream);
// The exact system modulo the rotation in place (device_newton.cpp, linearize), A
// (dim+1)² and g (dim+1), with a = Tᵀu (dim+1; a[dim] = |u|²): A_TT −= (a kᵀ + k aᵀ)/|u|²
// − c a aᵀ/|u|⁴ (k = column dim of A, c = A_dim,dim), g_T −= (g_dim/|u|²) a, then row and
// column dim of A and g_dim cleared; then *diag = max_i |A_ii| (diag_abs_max), also put
// at A_dim,dim (so the (dim+1) system solves the dim one with d[dim] = 0).
cudaError_t horizontal_system(int dim, double* A, const double* a, double* g, double* diag, cudaStream_t stream);
// The solve's right-hand side d = −g (m entries), with info[0] = info[1] = 0.
cudaError_t negate(int m, const double* g, double* d, int* info, cudaStream_t stream);
// After the solve (one block): with `rotation`, d[dim] = −(Σ_{i<dim} a_i d_i) / a[dim] (the
// rotation's share of the system modulo the rotation); then *slope = gᵀd over m entries
// and *gnorm2 = |g|² over the first dim, each summed as dot() sums; info_out[0..1] =
// info[0..1] (the statuses, read after the solves) where info_out is given.
cudaError_t step_scalars(int dim, int m, bool rotation, const double* a, const double* g, double* d, double* slope, double* gnorm2,
                         const int* info, int* info_out, cudaStream_t stream);
// One block, after the forward substitution y = −L⁻¹ g (m entries, the solve's d): the
// squared Newton decrement as a slope, −Σ_{i<m} y_i² (gᵀd in exact arithmetic, before d
// exists), |g|² over dim entries (each summed as dot() sums), and info[0..1] copied to
// info_out.
cudaError_t decrement_scalars(int dim, int m, const double* g, const double* y, double* slope, double* gnorm2, const int* info,
                              int* info_out, cudaStream_t stream);
// y = y0 + A x for a real column-major A (rows × cols) and x = x0 + (*step)·dx (x0 alone
// without dx), deterministic (fixed slices of the columns summed in order). Options: a
// second product with the same x in the same launch (second_A, second_rows × cols, into
// second_y, no y0), and x written to x_copy (cols entries). One launch where cuBLAS's
// GEMV plus the copies and point updates around it took two to four.
struct TallOptions {
  const double* y0 = nullptr;
  const double* dx = nullptr;
  const double* step = nullptr;  // device scalar, with dx
  double* x_copy = nullptr;
  const double* second_A = nullptr;
  int second_rows = 0;
  double* second_y = nullptr;
};
cudaError_t tall_times_one(int rows, int cols, const double* A, const double* x, double* y, cudaStream_t stream,
                           const TallOptions& options = {});
// Up to kMax device-to-device copies of doubles in one launch.
struct CopyList {
  static constexpr int kMax = 4;
  struct Entry {
    const double* src = nullptr;
    double* dst = nullptr;
    size_t count = 0;
  } entry[kMax];
};
cudaError_t copy(const CopyList& list, int entries, cudaStream_t stream);
// x = MapSpace::regauge(v) for v (4n, active coefficients) into x (dim).
cudaError_t regauge(int dim, int n, int rotation_vertex, const int* primary_rows, const double* v, double* x,
                    cudaStream_t stream);

// The small kernels above for a lockstep batch (hsi/cuda/batch_stepper.h): `systems`
// systems (1 … kMaxBatchSystems, else cudaErrorInvalidValue) in one launch, system s's
// arrays at the pointers given plus s times the stride named for them (in elements; 0:
// shared by every system). Each system's result is bit for bit the one-system call's
// (the one-system calls are these with one system). step_scalars_batched copies no
// statuses (its one-system form's info, info_out).
struct TallStrides {
  long long A = 0, second_A = 0, x = 0, y = 0, second_y = 0, y0 = 0, dx = 0, step = 0, x_copy = 0;
};
cudaError_t tall_times_one_batched(int systems, int rows, int cols, const double* A, const double* x, double* y, cudaStream_t stream,
                                   const TallOptions& options, const TallStrides& strides);
cudaError_t diag_abs_max_batched(int systems, int n, const double* A, long long A_stride, double* out, long long out_stride,
                                 cudaStream_t stream);
cudaError_t add_relative_ridge_batched(int systems, int n, const double* A0, double* A, long long mat_stride, const double* relative,
                                       long long relative_stride, const double* diag, double* diag_down, long long scalar_stride,
                                       cudaStream_t stream);
cudaError_t trial_point_batched(int systems, int n, const double* x, const double* d, double* out, long long vec_stride, const double* step,
                                long long step_stride, cudaStream_t stream);
cudaError_t horizontal_system_batched(int systems, int dim, double* A, long long mat_stride, const double* a, double* g,
                                      long long vec_stride, double* diag, long long diag_stride, cudaStream_t stream);
// g (dim + 1 entries) made horizontal in the kept system's frame: g_i −= (g_dim/a_dim) a_i for
// i < dim, then g_dim = 0 (tall_adjoint_times_two's ReducedGradient::a, as a kernel of its own).
cudaError_t horizontal_gradient_batched(int systems, int dim, const double* a, double* g, long long vec_stride, cudaStream_t stream);
cudaError_t negate_batched(int systems, int m, const double* g, double* d, long long vec_stride, int* info, long long info_stride,
                           cudaStream_t stream);
cudaError_t step_scalars_batched(int systems, int dim, int m, bool rotation, const double* a, const double* g, double* d,
                                 long long vec_stride, double* slope, double* gnorm2, long long scalar_stride, cudaStream_t stream);
cudaError_t decrement_scalars_batched(int systems, int dim, int m, const double* g, const double* y, long long vec_stride, double* slope,
                                      double* gnorm2, long long scalar_stride, const int* info, int* info_out, long long info_stride,
                                      cudaStream_t stream);
cudaError_t regauge_batched(int systems, int dim, int n, int rotation_vertex, const int* primary_rows, const double* v, long long v_stride,
                            double* x, long long x_stride, cudaStream_t stream);

}  // namespace hsi::cuda::kernels
