// The certificate's kernels (see certify_kernels.h), line for line the arithmetic of
// engine/src/certificate.cpp so that both backends reach the same verdicts.
#include "certify_kernels.h"
#include "newton_kernels.h"  // kMaxBatchSystems
#include "one_launch.cuh"

#include <algorithm>

#include <cfloat>

namespace hsi::cuda::kernels {
namespace {

constexpr int kThreads = 128;      // segment kernel: long-running threads, small blocks
constexpr int kReduceThreads = 512;  // 9 × 512 doubles of shared memory, under 48 KiB

__device__ __forceinline__ double inf() { return __longlong_as_double(0x7ff0000000000000LL); }
constexpr double kU = DBL_EPSILON / 2;  // unit roundoff 2^-53 (hsi::kCertificateRoundoff)
constexpr double kInv2Pi = 1 / (2 * 3.14159265358979323846);

// Complex arithmetic on double2 (x = real, y = imaginary).
__device__ __forceinline__ double2 operator+(double2 a, double2 b) { return make_double2(a.x + b.x, a.y + b.y); }
__device__ __forceinline__ double2 operator-(double2 a, double2 b) { return make_double2(a.x - b.x, a.y - b.y); }
__device__ __forceinline__ double2 operator*(double2 a, double2 b) {
  return make_double2(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
}
__device__ __forceinline__ double2 scale(double2 a, double s) { return make_double2(a.x * s, a.y * s); }
__device__ __forceinline__ double cabs(double2 a) { return hypot(a.x, a.y); }
// Smith's algorithm: no overflow for large operands.
__device__ __forceinline__ double2 cdiv(double2 a, double2 b) {
  if (fabs(b.x) >= fabs(b.y)) {
    const double r = b.y / b.x, d = b.x + b.y * r;
    return make_double2((a.x + a.y * r) / d, (a.y - a.x * r) / d);
  }
  const double r = b.x / b.y, d = b.y + b.x * r;
  return make_double2((a.x * r + a.y) / d, (a.y * r - a.x) / d);
}
__device__ __forceinline__ double2 clog(double2 a) { return make_double2(log(cabs(a)), atan2(a.y, a.x)); }
__device__ __forceinline__ double carg(double2 a) { return atan2(a.y, a.x); }

struct Values {
  double2 a, b, a1, b1;        // f_z, conj f_zbar and their z-derivatives
  double ea, eb, ea1, eb1;     // bounds on the absolute rounding error of each
};

// f_z, conj f_zbar and their derivatives at w straight from the cage (math.md §2), with
// error bounds from the rounding weights of hsi::certificate_weights.
__device__ Values values_at(const CageView& cage, const double2* __restrict__ coef, int M, double2 w) {
  const double2 inv2pii = make_double2(0, -kInv2Pi);  // 1 / (2πi)
  Values v{};
  for (int l = 0; l < cage.loops; ++l) {
    const int begin = cage.loop_begin[l], k = cage.loop_begin[l + 1] - begin;
    const double2* z = cage.z + begin;
    double2 Bm = z[k - 1] - w, B0 = z[0] - w;
    double2 Lm = clog(cdiv(B0, Bm));
    for (int j = 0; j < k; ++j) {
      const int jp = j + 1 == k ? 0 : j + 1, jm = j == 0 ? k - 1 : j - 1;
      const double2 Bp = z[jp] - w;
      const double2 L0 = clog(cdiv(Bp, B0));
      const double2 A0 = z[j] - z[jm], A1 = z[jp] - z[j];
      const double2 D = inv2pii * (cdiv(Lm, A0) - cdiv(L0, A1));
      const double2 E = inv2pii * cdiv(Bp - Bm, Bm * B0 * Bp);
      const double2 phi = coef[begin + j], psi = coef[M + begin + j];
      v.a = v.a + D * phi;
      v.b = v.b + D * psi;
      v.a1 = v.a1 + E * phi;
      v.b1 = v.b1 + E * psi;
      const double wd = (1 + cabs(Lm)) / cabs(A0) + (1 + cabs(L0)) / cabs(A1);
      const double we = (cabs(Bp) + cabs(Bm)) / (cabs(Bm) * cabs(B0) * cabs(Bp));
      v.ea += wd * cabs(phi);
      v.eb += wd * cabs(psi);
      v.ea1 += we * cabs(phi);
      v.eb1 += we * cabs(psi);
      Bm = B0;
      B0 = Bp;
      Lm = L0;
    }
  }
  v.ea *= kInv2Pi;
  v.eb *= kInv2Pi;
  v.ea1 *= kInv2Pi;
  v.eb1 *= kInv2Pi;
  for (int h = 0; h < cage.N; ++h) {
    const double2 d = w - cage.holes[h];
    const double2 phi = coef[cage.m + h], psi = coef[M + cage.m + h];
    v.a = v.a + cdiv(phi, d);
    v.b = v.b + cdiv(psi, d);
    const double2 d2 = d * d;
    v.a1 = v.a1 - cdiv(phi, d2);
    v.b1 = v.b1 - cdiv(psi, d2);
    const double r = 1 / cabs(d);
    v.ea += cabs(phi) * r;
    v.eb += cabs(psi) * r;
    v.ea1 += cabs(phi) * r * r;
    v.eb1 += cabs(psi) * r * r;
  }
  const double c = (2.0 * M + 72) * kU;
  v.ea *= c;
  v.eb *= c;
  v.ea1 *= c;
  v.eb1 *= c;
  return v;
}

__global__ void jumps_kernel(CageView cage, const double2* __restrict__ coef, double* __restrict__ jumps,
                             double* __restrict__ abs_coef, int* __restrict__ stop) {
  const int M = cage.m + cage.N;
  const size_t sys = blockIdx.y;  // system of a lockstep batch (lipschitz_jumps_batched): its coefficients, jumps and flag
  coef += sys * 2 * static_cast<size_t>(M);
  jumps += sys * 2 * static_cast<size_t>(M);
  abs_coef += sys * 2 * static_cast<size_t>(M);
  if (stop) stop += sys;
  if (stop && blockIdx.x == 0 && threadIdx.x == 0) *stop = 0;  // certify_segments' flag, cleared before it runs
  for (int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x); i < M; i += static_cast<int>(gridDim.x * blockDim.x)) {
    abs_coef[i] = cabs(coef[i]);
    abs_coef[M + i] = cabs(coef[M + i]);
    if (i >= cage.m) {  // the log terms: 2 |φ_log| and 2 |ψ_log| (equal in the map space), rounded up
      jumps[i] = 2 * cabs(coef[i]) * (1 + 4 * kU);
      jumps[M + i] = 2 * cabs(coef[M + i]) * (1 + 4 * kU);
      continue;
    }
    int l = 0;
    while (cage.loop_begin[l + 1] <= i) ++l;
    const int begin = cage.loop_begin[l], k = cage.loop_begin[l + 1] - begin, j = i - begin;
    const double2* z = cage.z + begin;
    for (int c = 0; c < 2; ++c) {
      const double2* cc = coef + c * M + begin;
      // δ_j: the slope on the edge ending at vertex j.
      auto delta = [&](int jj) {
        const int jm = jj == 0 ? k - 1 : jj - 1;
        return cdiv(cc[jj] - cc[jm], z[jj] - z[jm]);
      };
      const double2 d0 = delta(j), d1 = delta(j + 1 == k ? 0 : j + 1);
      const double s = cabs(d1 - d0);
      // An upper bound of |S_j| (hsi::certificate_jumps' rounding), over 2π.
      jumps[c * M + i] = kInv2Pi * (s + 16 * kU * (cabs(d0) + cabs(d1)) + 4 * kU * s) * (1 + 2 * kU);
    }
  }
}

struct Piece {
  double2 q;
  Values vq;
  int depth;
};

__global__ void __launch_bounds__(kThreads) segments_kernel(CageView cage, SegmentsView seg, const double2* __restrict__ coef,
                                                            const double2* __restrict__ values, const double* __restrict__ errs,
                                                            const double* __restrict__ lip, const char* __restrict__ touches,
                                                            int max_depth, long long max_pieces, int* stop,
                                                            SegmentOutcome* __restrict__ out) {
  const int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= seg.S) return;
  const int S = seg.S, M = cage.m + cage.N;
  const size_t sys = blockIdx.y;  // system of a lockstep batch (certify_segments_batched)
  coef += sys * 2 * static_cast<size_t>(M);
  values += sys * 4 * static_cast<size_t>(S);
  errs += sys * 4 * static_cast<size_t>(S);
  lip += sys * 2 * static_cast<size_t>(S);
  if (stop) stop += sys;
  out += sys * static_cast<size_t>(S);
  SegmentOutcome o;
  o.ok = 1;
  o.arg = 0;
  o.margin = inf();
  o.sigma1 = 0;
  o.sigma2 = inf();
  o.k = 0;
  o.pieces = 0;
  o.fail_point = make_double2(0, 0);
  if (stop && *reinterpret_cast<volatile int*>(stop)) {  // another segment failed already
    out[i] = o;
    return;
  }
  const int u = i, v = seg.next[i];
  double2 p = seg.points[u], q = seg.points[v];
  const double value_err = (2.0 * M + 72) * kU;
  Values vp{values[u], values[2 * S + u], values[S + u], values[3 * S + u],
            value_err * errs[u], value_err * errs[2 * S + u], value_err * errs[S + u], value_err * errs[3 * S + u]};
  Values vq{values[v], values[2 * S + v], values[S + v], values[3 * S + v],
            value_err * errs[v], value_err * errs[2 * S + v], value_err * errs[S + v], value_err * errs[3 * S + v]};
  const double lip_up = 1 + (2.0 * M + 32) * kU;
  const double lipA = touches[i] ? inf() : lip[i] * lip_up, lipB = touches[i] ? inf() : lip[S + i] * lip_up;
  Piece stack[kMaxCertifyDepth];
  int top = 0, depth = 0;
  for (;;) {
    // certificate.cpp's bounds, rounding on the conservative side.
    const double abs_ap = cabs(vp.a), abs_aq = cabs(vq.a), abs_bp = cabs(vp.b), abs_bq = cabs(vq.b);
    const double len = cabs(q - p) * (1 + 4 * kU);
    const double fzz_max = (((cabs(vp.a1) + vp.ea1) + (cabs(vq.a1) + vq.ea1)) / 2 + lipA * len / 2) * (1 + 8 * kU);
    const double bz_max = (((cabs(vp.b1) + vp.eb1) + (cabs(vq.b1) + vq.eb1)) / 2 + lipB * len / 2) * (1 + 8 * kU);
    const double a_avg_lo = ((abs_ap - vp.ea) + (abs_aq - vq.ea)) / 2;
    const double a_avg_hi = ((abs_ap + vp.ea) + (abs_aq + vq.ea)) / 2;
    const double b_avg_hi = ((abs_bp + vp.eb) + (abs_bq + vq.eb)) / 2;
    const double tol = 8 * kU * (a_avg_hi + b_avg_hi + fzz_max * len + bz_max * len);
    const double a_lo = a_avg_lo - fzz_max * len / 2 - tol;
    const double a_hi = a_avg_hi + fzz_max * len / 2 + tol;
    const double b_hi = b_avg_hi + bz_max * len / 2 + tol;
    const bool arg_ok = fzz_max * len + vp.ea + tol < abs_ap;
    const bool folds_here = abs_bp >= abs_ap || abs_bq >= abs_aq;
    if (a_lo > b_hi && arg_ok) {
      o.pieces++;
      o.arg += carg(cdiv(vq.a, vp.a));
      o.margin = fmin(o.margin, a_lo - b_hi);
      o.sigma1 = fmax(o.sigma1, a_hi + b_hi);
      o.sigma2 = fmin(o.sigma2, a_lo - b_hi);
      o.k = fmax(o.k, b_hi / a_lo * (1 + 2 * kU));
      if (top == 0) break;
      // The next piece starts where this one ended.
      p = q;
      vp = vq;
      --top;
      q = stack[top].q;
      vq = stack[top].vq;
      depth = stack[top].depth;
      continue;
    }
    const bool stopped = stop && *reinterpret_cast<volatile int*>(stop);
    if (folds_here || depth >= max_depth || o.pieces >= max_pieces || stopped) {
      o.ok = 0;
      o.pieces++;
      o.margin = fmin(o.margin, a_lo - b_hi);
      o.fail_point = scale(p + q, 0.5);
      if (stop) atomicExch(stop, 1);
      break;
    }
    const double2 mid = scale(p + q, 0.5);
    const Values vm = values_at(cage, coef, M, mid);
    stack[top].q = q;
    stack[top].vq = vq;
    stack[top].depth = depth + 1;
    ++top;
    q = mid;
    vq = vm;
    ++depth;
  }
  out[i] = o;
}

// The certificate's summary as a fold: per thread over a strided subset of segments,
// then fixed trees over a block (deterministic for a fixed grid).
struct Fold {
  double v[9];  // arg, margin, σ1, σ2, k, observed σ1, σ2, k, isometric
  long long subdivisions;
  int first;
};

__device__ Fold fold_identity(int S) {
  return {{0, inf(), 0, inf(), 0, 0, inf(), 0, 0}, 0, S};
}

__device__ void fold_combine(Fold& a, const Fold& b) {
  a.v[0] += b.v[0];
  a.v[1] = fmin(a.v[1], b.v[1]);
  a.v[2] = fmax(a.v[2], b.v[2]);
  a.v[3] = fmin(a.v[3], b.v[3]);
  a.v[4] = fmax(a.v[4], b.v[4]);
  a.v[5] = fmax(a.v[5], b.v[5]);
  a.v[6] = fmin(a.v[6], b.v[6]);
  a.v[7] = fmax(a.v[7], b.v[7]);
  a.v[8] = fmax(a.v[8], b.v[8]);
  a.subdivisions += b.subdivisions;
  a.first = min(a.first, b.first);
}

// Block tree over every thread's fold; the result in thread 0.
__device__ Fold block_fold(Fold f) {
  __shared__ double sh[9][kReduceThreads];
  __shared__ long long sh_sub[kReduceThreads];
  __shared__ int sh_first[kReduceThreads];
  const int t = static_cast<int>(threadIdx.x);
  for (int q = 0; q < 9; ++q) sh[q][t] = f.v[q];
  sh_sub[t] = f.subdivisions;
  sh_first[t] = f.first;
  __syncthreads();
  for (int w = static_cast<int>(blockDim.x) / 2; w > 0; w /= 2) {
    if (t < w) {
      Fold a, b;
      for (int q = 0; q < 9; ++q) a.v[q] = sh[q][t], b.v[q] = sh[q][t + w];
      a.subdivisions = sh_sub[t], b.subdivisions = sh_sub[t + w];
      a.first = sh_first[t], b.first = sh_first[t + w];
      fold_combine(a, b);
      for (int q = 0; q < 9; ++q) sh[q][t] = a.v[q];
      sh_sub[t] = a.subdivisions;
      sh_first[t] = a.first;
    }
    __syncthreads();
  }
  Fold r;
  for (int q = 0; q < 9; ++q) r.v[q] = sh[q][0];
  r.subdivisions = sh_sub[0];
  r.first = sh_first[0];
  return r;
}

// Pass 1: each block folds a grid-strided subset of the segments into partials[block].
// A Fold from global memory through L2 (__ldcg, 8 bytes at a time): another block's
// partial, written in this launch, is never read from a stale L1 line.
__device__ Fold load_fold(const Fold* p) {
  static_assert(sizeof(Fold) % sizeof(unsigned long long) == 0 && alignof(Fold) >= alignof(unsigned long long));
  Fold f;
  const auto* src = reinterpret_cast<const unsigned long long*>(p);
  auto* dst = reinterpret_cast<unsigned long long*>(&f);
  for (size_t w = 0; w < sizeof(Fold) / sizeof(unsigned long long); ++w) dst[w] = __ldcg(src + w);
  return f;
}

// One launch: each block folds its segments into partials[block]; the block that
// counts last on `done` (newton_kernels' one-launch reductions: 0 before, 0 again after)
// folds the partials in order, as one finishing block would, and writes the summary.
__global__ void __launch_bounds__(kReduceThreads) reduce_kernel(int S, const SegmentOutcome* __restrict__ outcomes,
                                                                const double2* __restrict__ values, Fold* partials,
                                                                unsigned* __restrict__ done, CertifySummary* out) {
  const size_t sys = blockIdx.y;  // system of a lockstep batch (reduce_certificate_batched): its own partials and counter
  outcomes += sys * static_cast<size_t>(S);
  values += sys * 4 * static_cast<size_t>(S);
  partials += sys * kReducePartials;
  done += sys;
  out += sys;
  Fold f = fold_identity(S);
  for (int i = static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x); i < S; i += static_cast<int>(gridDim.x * blockDim.x)) {
    const SegmentOutcome& o = outcomes[i];
    Fold g = fold_identity(S);
    g.subdivisions = o.pieces > 1 ? o.pieces - 1 : 0;
    if (!o.ok) g.first = i;
    g.v[0] = o.arg;
    g.v[1] = o.margin;
    g.v[2] = o.sigma1;
    g.v[3] = o.sigma2;
    g.v[4] = o.k;
    const double aa = cabs(values[i]), bb = cabs(values[2 * S + i]);
    const double x1 = aa + bb, x2 = aa - bb;
    g.v[5] = x1;
    g.v[6] = x2;
    g.v[7] = bb / aa;
    g.v[8] = 0.5 * (x1 * x1 + 1 / (x1 * x1) + x2 * x2 + 1 / (x2 * x2));
    fold_combine(f, g);
  }
  const Fold block = block_fold(f);
  if (threadIdx.x == 0) partials[blockIdx.x] = block;
  if (!last_block_done(done)) return;
  const int t = static_cast<int>(threadIdx.x), parts = static_cast<int>(gridDim.x);
  const Fold r = block_fold(t < parts ? load_fold(partials + t) : fold_identity(S));
  if (t == 0) {
    CertifySummary c;
    c.arg_total = r.v[0];
    c.min_margin = r.v[1];
    c.sigma1_max = r.v[2];
    c.sigma2_min = r.v[3];
    c.k_max = r.v[4];
    c.observed_sigma1_max = r.v[5];
    c.observed_sigma2_min = r.v[6];
    c.observed_k_max = r.v[7];
    c.observed_isometric_max = r.v[8];
    c.segments = S;
    c.subdivisions = r.subdivisions;
    c.first_fail = r.first;
    c.fail_point = r.first < S ? outcomes[r.first].fail_point : make_double2(0, 0);
    *out = c;
  }
}

unsigned blocks(long long count, int threads) {
  const long long b = (count + threads - 1) / threads;
  return static_cast<unsigned>(b < 1 ? 1 : (b > 65535LL * 32 ? 65535LL * 32 : b));
}

}  // namespace

cudaError_t lipschitz_jumps(CageView cage, const double2* coef, double* jumps, double* abs_coef, int* stop, cudaStream_t stream) {
  return lipschitz_jumps_batched(1, cage, coef, jumps, abs_coef, stop, stream);
}

cudaError_t certify_segments(CageView cage, SegmentsView seg, const double2* coef, const double2* values, const double* errs,
                             const double* lip, const char* touches, int max_depth, long long max_pieces, int* stop,
                             SegmentOutcome* out, cudaStream_t stream) {
  return certify_segments_batched(1, cage, seg, coef, values, errs, lip, touches, max_depth, max_pieces, stop, out, stream);
}

cudaError_t reduce_certificate(int S, const SegmentOutcome* outcomes, const double2* values, void* partials, unsigned* done,
                               CertifySummary* out, cudaStream_t stream) {
  return reduce_certificate_batched(1, S, outcomes, values, partials, done, out, stream);
}

cudaError_t lipschitz_jumps_batched(int systems, CageView cage, const double2* coef, double* jumps, double* abs_coef, int* stop,
                                    cudaStream_t stream) {
  if (systems < 1 || systems > kMaxBatchSystems) return cudaErrorInvalidValue;
  jumps_kernel<<<dim3(blocks(cage.m + cage.N, 128), static_cast<unsigned>(systems)), 128, 0, stream>>>(cage, coef, jumps, abs_coef,
                                                                                                          stop);
  return cudaGetLastError();
}

cudaError_t certify_segments_batched(int systems, CageView cage, SegmentsView seg, const double2* coef, const double2* values,
                                     const double* errs, const double* lip, const char* touches, int max_depth, long long max_pieces,
                                     int* stop, SegmentOutcome* out, cudaStream_t stream) {
  if (max_depth > kMaxCertifyDepth || systems < 1 || systems > kMaxBatchSystems) return cudaErrorInvalidValue;
  segments_kernel<<<dim3(blocks(seg.S, kThreads), static_cast<unsigned>(systems)), kThreads, 0, stream>>>(
      cage, seg, coef, values, errs, lip, touches, max_depth, max_pieces, stop, out);
  return cudaGetLastError();
}

cudaError_t reduce_certificate_batched(int systems, int S, const SegmentOutcome* outcomes, const double2* values, void* partials,
                                       unsigned* done, CertifySummary* out, cudaStream_t stream) {
  static_assert(kReducePartials <= kReduceThreads);
  if (systems < 1 || systems > kMaxBatchSystems) return cudaErrorInvalidValue;
  const long long per_block = 4LL * kReduceThreads;  // a few segments per thread
  const int parts = static_cast<int>(std::min<long long>(std::max<long long>((S + per_block - 1) / per_block, 1), kReducePartials));
  Fold* p = static_cast<Fold*>(partials);
  reduce_kernel<<<dim3(static_cast<unsigned>(parts), static_cast<unsigned>(systems)), kReduceThreads, 0, stream>>>(S, outcomes, values,
                                                                                                                    p, done, out);
  return cudaGetLastError();
}

size_t reduce_partials_bytes() { return sizeof(Fold) * kReducePartials; }

}  // namespace hsi::cuda::kernels
