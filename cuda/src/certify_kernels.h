// The certificate's kernels (the CUDA twin of engine/src/certificate.cpp, math.md §6):
// one thread per boundary segment runs the Lipschitz test with adaptive subdivision
// (an explicit stack instead of recursion, pieces in the CPU's depth-first order),
// then one block reduces the outcomes to a verdict and the certified bounds without
// the per-segment data leaving the device. Plain launch functions, no Eigen.
#pragma once

#include <cuda_runtime.h>

namespace hsi::cuda::kernels {

// Deepest subdivision the segment kernel supports (its stack lives in registers /
// local memory); CertificateOptions::max_depth beyond this is refused by the host.
constexpr int kMaxCertifyDepth = 24;

// The cage, flattened: loop l has vertices z[loop_begin[l] .. loop_begin[l+1]); the
// full coefficient index of cage vertex j is j, of hole point h is m + h.
struct CageView {
  const double2* z;
  const int* loop_begin;  // loops + 1 entries
  int loops, m;
  const double2* holes;   // hole points ρ
  int N;
};

// The segments: segment i joins points[i] to points[next[i]].
struct SegmentsView {
  const double2* points;
  const int* next;
  int S;
};

// Per segment, what the test found (SegmentCertificate of certificate.h).
struct SegmentOutcome {
  double arg, margin, sigma1, sigma2, k;
  double2 fail_point;
  long long pieces;
  int ok;
};

// The reduction over all segments. first_fail = the lowest failing segment (S if none).
struct CertifySummary {
  double arg_total, min_margin, sigma1_max, sigma2_min, k_max;
  double observed_sigma1_max, observed_sigma2_min, observed_k_max, observed_isometric_max;
  double2 fail_point;
  long long segments, subdivisions;
  int first_fail;
};

// jumps (M × 2, column-major: [|S_j(φ)| ; |S_j(ψ)|] scaled, then the log terms):
// rows 0..m−1: upper bounds of |S_j(c)| / 2π (hsi::certificate_jumps with its rounding)
// for c = φ (column 0) and ψ (column 1); rows m..m+N−1: 2 |c_log,h| rounded up, so that
// [W | Wh] · jumps = (La, Lb) per segment before the sum's rounding (certificate.cpp).
// abs_coef (M × 2): |φ| and |ψ|, for the values' error bounds.
// coef: [φ | ψ] full, M × 2 complex, column-major. stop (may be null): certify_segments'
// flag, set to 0 here (one launch fewer than a memset before the segments).
cudaError_t lipschitz_jumps(CageView cage, const double2* coef, double* jumps, double* abs_coef, int* stop, cudaStream_t stream);

// values (S × 4, column-major, as [D; E] · [φ | ψ] leaves them): f_z, f_zz, conj f_zbar,
// (conj f_zbar)' at the breakpoints ([a | a1 | b | b1]); errs (the same layout):
// [WD; WE] · [|φ| | |ψ|], their rounding weights (hsi::certificate_weights); lip: S × 2
// (La, Lb) before rounding up; touches: per segment, 1 where a distance bound is not
// positive. stop: device flag, set by a failing segment when stop_at_first_failure,
// read by all (may be null otherwise).
cudaError_t certify_segments(CageView cage, SegmentsView seg, const double2* coef, const double2* values, const double* errs,
                             const double* lip, const char* touches, int max_depth, long long max_pieces, int* stop,
                             SegmentOutcome* out, cudaStream_t stream);

// The summary of all outcomes plus the observed values at the breakpoints: one launch of
// up to kReducePartials blocks whose last one folds their partials in order
// (deterministic). partials: device scratch of reduce_partials_bytes(); done: a device
// counter, 0 before and again after (newton_kernels.h's one-launch reductions).
constexpr int kReducePartials = 64;
size_t reduce_partials_bytes();
cudaError_t reduce_certificate(int S, const SegmentOutcome* outcomes, const double2* values, void* partials, unsigned* done,
                               CertifySummary* out, cudaStream_t stream);

// Lockstep batches (newton_kernels.h): `systems` maps of one setup certified in one launch
// per call. System s's arrays at fixed strides from the pointers given: coef, jumps and
// abs_coef 2M, values and errs 4S, lip 2S, outcomes S, the summary one, the flag stop[s]
// (stop may be null), partials reduce_partials_bytes() and its own counter done[s]. Each
// system's results bit for bit the one-system call's (which are these with systems = 1),
// but where stop is given: which segments still run after one fails depends on timing,
// in a batch as alone (the verdict and the first failing segment do not).
cudaError_t lipschitz_jumps_batched(int systems, CageView cage, const double2* coef, double* jumps, double* abs_coef, int* stop,
                                    cudaStream_t stream);
cudaError_t certify_segments_batched(int systems, CageView cage, SegmentsView seg, const double2* coef, const double2* values,
                                     const double* errs, const double* lip, const char* touches, int max_depth, long long max_pieces,
                                     int* stop, SegmentOutcome* out, cudaStream_t stream);
cudaError_t reduce_certificate_batched(int systems, int S, const SegmentOutcome* outcomes, const double2* values, void* partials,
                                       unsigned* done, CertifySummary* out, cudaStream_t stream);

}  // namespace hsi::cuda::kernels
