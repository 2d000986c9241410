// The per-sample isometric energy, gradient and projected Hessian (paper Eq. 5, 10,
// 15–21, Appendix B) on plain doubles, line for line the twin of engine/src/energy.cpp,
// as __host__ __device__ code: the CUDA kernels call it, and the tests compile it for
// the host and check it against the CPU reference without a GPU (private to cuda/;
// the tests reach it through hsi_cuda_internals).
#pragma once

#include <cfloat>
#include <cmath>
#include <limits>

#if defined(__CUDACC__)
#define HSI_HD __host__ __device__ inline
#else
#define HSI_HD inline
#endif
// Unrolled loops keep the 4×4 arrays in registers on the device; gcc ignores it.
#if defined(__CUDA_ARCH__)
#define HSI_UNROLL _Pragma("unroll")
#else
#define HSI_UNROLL
#endif

namespace hsi::cuda::sample {

// Mirrors hsi::HessianProjection (energy.h); mapped explicitly, not by value.
enum class Projection : int { Delete = 0, FullProj = 1, PartProj = 2 };

struct Mat4 {
  double m[4][4];
};
struct Mat3 {
  double m[3][3];
};

HSI_HD double infinity() {
#if defined(__CUDA_ARCH__)
  return __longlong_as_double(0x7ff0000000000000LL);
#else
  return std::numeric_limits<double>::infinity();
#endif
}
HSI_HD bool is_finite(double x) { return ::fabs(x) <= DBL_MAX; }  // false for ±inf and NaN

HSI_HD Mat4 zero4() {
  Mat4 r;
  HSI_UNROLL for (int i = 0; i < 4; ++i) HSI_UNROLL for (int j = 0; j < 4; ++j) r.m[i][j] = 0;
  return r;
}

// Appendix B: h_i = vᵀ F_i v.
HSI_HD double F(int i, int r, int c) {
  // F1 = [[1,0,1,0],[0,1,0,-1],[1,0,1,0],[0,-1,0,1]], F2 = [[0,0,0,-1],[0,0,-1,0],[0,-1,0,0],[-1,0,0,0]],
  // F3 = [[1,0,-1,0],[0,1,0,1],[-1,0,1,0],[0,1,0,1]].
  const int k = r * 4 + c;
  if (i == 0) {
    const double f[16] = {1, 0, 1, 0, 0, 1, 0, -1, 1, 0, 1, 0, 0, -1, 0, 1};
    return f[k];
  }
  if (i == 1) {
    const double f[16] = {0, 0, 0, -1, 0, 0, -1, 0, 0, -1, 0, 0, -1, 0, 0, 0};
    return f[k];
  }
  const double f[16] = {1, 0, -1, 0, 0, 1, 0, 1, -1, 0, 1, 0, 0, 1, 0, 1};
  return f[k];
}

// K1 = Σ α_i F_i, summed in the CPU's order.
HSI_HD Mat4 sum_alpha_F(const double alpha[3]) {
  Mat4 K;
  HSI_UNROLL for (int r = 0; r < 4; ++r) HSI_UNROLL for (int c = 0; c < 4; ++c)
    K.m[r][c] = alpha[0] * F(0, r, c) + alpha[1] * F(1, r, c) + alpha[2] * F(2, r, c);
  return K;
}

// Paper Eq. 5 with A = a b, S = |a|² + |b|²: m1 = S + 2 Re A, m2 = −2 Im A, m3 = S − 2 Re A.
HSI_HD void pullback_metric(double ar, double ai, double br, double bi, double h[3]) {
  const double Ar = ar * br - ai * bi, Ai = ar * bi + ai * br;
  const double S = (ar * ar + ai * ai) + (br * br + bi * bi);
  h[0] = S + 2 * Ar;
  h[1] = -2 * Ai;
  h[2] = S - 2 * Ar;
}

// Eq. 10 at one sample; +inf where the map folds or degenerates (|a| ≤ |b|) or g is not
// positive definite. g = (g1, g2, g3) of [[g1, g2], [g2, g3]].
HSI_HD double isometric_energy(const double g[3], double ar, double ai, double br, double bi) {
  const double det_g = g[0] * g[2] - g[1] * g[1];
  const double s = (ar * ar + ai * ai) - (br * br + bi * bi);
  if (!(s > 0) || !(det_g > 0)) return infinity();
  double h[3];
  pullback_metric(ar, ai, br, bi, h);
  const double det_h = s * s;  // h1 h3 − h2² = (|a|² − |b|²)²
  return (g[2] * h[0] - 2 * g[1] * h[1] + g[0] * h[2]) / 2 * (1 / det_g + 1 / det_h);
}

// The analytic PSD projection of K1 = Σ α_i F_i (paper Eq. 21; math.md §4 on the third case).
HSI_HD Mat4 project_K1(const double alpha[3]) {
  const double a1 = alpha[0], a2 = alpha[1], a3 = alpha[2];
  const double R = ::hypot(a1 - a3, a2);
  const double l1 = a1 + a3 + R, l3 = a1 + a3 - R;  // Eq. 21, each of multiplicity 2
  Mat4 K1 = sum_alpha_F(alpha);
  if (l3 >= 0) return K1;
  if (l1 <= 0) return zero4();
  // λ1 times the projector (I + N/R)/2 onto K1's positive eigenspace, N = K1 − (α1 + α3) I.
  Mat4 P;
  HSI_UNROLL for (int r = 0; r < 4; ++r) HSI_UNROLL for (int c = 0; c < 4; ++c) {
    const double N = K1.m[r][c] - (r == c ? a1 + a3 : 0.0);
    P.m[r][c] = l1 * ((r == c ? 1.0 : 0.0) + N / R) / 2;
  }
  return P;
}

// The eigen-decomposition A = V diag(w) Vᵀ of a symmetric 4×4 matrix by cyclic Jacobi
// rotations (the device's stand-in for Eigen's SelfAdjointEigenSolver): accurate to
// round-off, which is all the projection V max(w, 0) Vᵀ needs.
HSI_HD void symmetric_eigen4(Mat4 A, double w[4], Mat4& V) {
  HSI_UNROLL for (int i = 0; i < 4; ++i) HSI_UNROLL for (int j = 0; j < 4; ++j) V.m[i][j] = i == j ? 1.0 : 0.0;
  for (int sweep = 0; sweep < 32; ++sweep) {
    double off = 0, diag = 0;
    HSI_UNROLL for (int p = 0; p < 4; ++p) {
      diag += A.m[p][p] * A.m[p][p];
      HSI_UNROLL for (int q = p + 1; q < 4; ++q) off += A.m[p][q] * A.m[p][q];
    }
    if (!(off > 1e-36 * diag)) break;  // converged (NaN input stops at once too)
    HSI_UNROLL for (int p = 0; p < 3; ++p) HSI_UNROLL for (int q = p + 1; q < 4; ++q) {
      const double apq = A.m[p][q];
      if (apq == 0) continue;
      // Rotation in the (p, q) plane zeroing A[p][q] (the smaller root t for stability).
      const double theta = (A.m[q][q] - A.m[p][p]) / (2 * apq);
      const double at = ::fabs(theta);
      const double t = at > 1e150 ? 0.5 / theta : ::copysign(1.0, theta) / (at + ::sqrt(theta * theta + 1));
      const double c = 1 / ::sqrt(t * t + 1), s = t * c;
      HSI_UNROLL for (int k = 0; k < 4; ++k) {  // A ← A J (columns p, q)
        const double akp = A.m[k][p], akq = A.m[k][q];
        A.m[k][p] = c * akp - s * akq;
        A.m[k][q] = s * akp + c * akq;
      }
      HSI_UNROLL for (int k = 0; k < 4; ++k) {  // A ← Jᵀ A (rows p, q)
        const double apk = A.m[p][k], aqk = A.m[q][k];
        A.m[p][k] = c * apk - s * aqk;
        A.m[q][k] = s * apk + c * aqk;
      }
      A.m[p][q] = A.m[q][p] = 0;
      HSI_UNROLL for (int k = 0; k < 4; ++k) {  // V ← V J
        const double vkp = V.m[k][p], vkq = V.m[k][q];
        V.m[k][p] = c * vkp - s * vkq;
        V.m[k][q] = s * vkp + c * vkq;
      }
    }
  }
  HSI_UNROLL for (int i = 0; i < 4; ++i) w[i] = A.m[i][i];
}

struct Derivatives {
  double e = 0;
  double grad[4] = {0, 0, 0, 0};  // ∂e/∂v, v = (Re a, Im a, Re b, Im b)
  Mat4 hess;                      // (projected) ∂²e/∂v²; zero where e is infinite
};

// Energy, gradient and (with_hessian) Hessian at one sample: hsi::isometric_derivatives.
// With `exact` the Hessian is the true one (2 K1 + 4 K2), otherwise projected.
HSI_HD Derivatives isometric_derivatives(const double g[3], double ar, double ai, double br, double bi,
                                         Projection projection, bool exact, bool with_hessian) {
  Derivatives d;
  d.hess = zero4();
  d.e = isometric_energy(g, ar, ai, br, bi);
  if (!is_finite(d.e)) return d;
  const double v[4] = {ar, ai, br, bi};
  double h[3];
  pullback_metric(ar, ai, br, bi, h);
  const double det_g = g[0] * g[2] - g[1] * g[1];
  const double det_h = h[0] * h[2] - h[1] * h[1];
  // E = T · P with T = (g3 h1 − 2 g2 h2 + g1 h3)/2 and P = 1/det g + 1/det h.
  const double T = (g[2] * h[0] - 2 * g[1] * h[1] + g[0] * h[2]) / 2;
  const double P = 1 / det_g + 1 / det_h;
  const double t[3] = {g[2] / 2, -g[1], g[0] / 2};     // ∂T/∂h
  const double q[3] = {h[2], -2 * h[1], h[0]};         // ∂det h/∂h
  const double dq[3][3] = {{0, 0, 1}, {0, -2, 0}, {1, 0, 0}};  // ∂q/∂h
  const double ih = 1 / det_h;
  const double Tih2 = T * ih * ih;
  double alpha[3];  // α_i = ∂E/∂h_i
  HSI_UNROLL for (int i = 0; i < 3; ++i) alpha[i] = t[i] * P - Tih2 * q[i];
  // ∇_v h_i = 2 F_i v, so ∇_v E = 2 K1 v (Appendix B).
  const Mat4 K1 = sum_alpha_F(alpha);
  HSI_UNROLL for (int r = 0; r < 4; ++r) {
    double s = 0;
    HSI_UNROLL for (int c = 0; c < 4; ++c) s += 2 * K1.m[r][c] * v[c];
    d.grad[r] = s;
  }
  if (!with_hessian) return d;
  // β_ij = ∂²E/∂h_i∂h_j
  Mat3 beta;
  const double ih2 = ih * ih, ih3x2 = 2 * ih * ih * ih;
  HSI_UNROLL for (int i = 0; i < 3; ++i) HSI_UNROLL for (int j = 0; j < 3; ++j)
    beta.m[i][j] = -(t[i] * q[j] + q[i] * t[j]) * ih * ih + T * (ih3x2 * q[i] * q[j] - ih2 * dq[i][j]);
  double J[3][4];  // rows (F_i v)ᵀ
  HSI_UNROLL for (int i = 0; i < 3; ++i) HSI_UNROLL for (int c = 0; c < 4; ++c) {
    double s = 0;
    HSI_UNROLL for (int k = 0; k < 4; ++k) s += F(i, c, k) * v[k];
    J[i][c] = s;
  }
  Mat4 K2;  // Jᵀ β J = Σ β_ij F_i v vᵀ F_j
  double BJ[3][4];
  HSI_UNROLL for (int i = 0; i < 3; ++i) HSI_UNROLL for (int c = 0; c < 4; ++c)
    BJ[i][c] = beta.m[i][0] * J[0][c] + beta.m[i][1] * J[1][c] + beta.m[i][2] * J[2][c];
  HSI_UNROLL for (int r = 0; r < 4; ++r) HSI_UNROLL for (int c = 0; c < 4; ++c)
    K2.m[r][c] = J[0][r] * BJ[0][c] + J[1][r] * BJ[1][c] + J[2][r] * BJ[2][c];
  // The Hessian is 2 K1 + 4 K2 (math.md §4 on the typo in Appendix B).
  Mat4 H;
  HSI_UNROLL for (int r = 0; r < 4; ++r) HSI_UNROLL for (int c = 0; c < 4; ++c) H.m[r][c] = 2 * K1.m[r][c] + 4 * K2.m[r][c];
  if (exact) {
    d.hess = H;
    return d;
  }
  switch (projection) {
    case Projection::Delete:
      HSI_UNROLL for (int r = 0; r < 4; ++r) HSI_UNROLL for (int c = 0; c < 4; ++c) H.m[r][c] = 4 * K2.m[r][c];
      break;
    case Projection::PartProj: {
      const Mat4 PK1 = project_K1(alpha);
      HSI_UNROLL for (int r = 0; r < 4; ++r) HSI_UNROLL for (int c = 0; c < 4; ++c)
        H.m[r][c] = 2 * PK1.m[r][c] + 4 * K2.m[r][c];
      break;
    }
    case Projection::FullProj: {
      double lam[4];
      Mat4 V;
      symmetric_eigen4(H, lam, V);
      HSI_UNROLL for (int k = 0; k < 4; ++k) lam[k] = lam[k] > 0 ? lam[k] : 0.0;
      HSI_UNROLL for (int r = 0; r < 4; ++r) HSI_UNROLL for (int c = 0; c < 4; ++c) {
        double s = 0;
        HSI_UNROLL for (int k = 0; k < 4; ++k) s += V.m[r][k] * lam[k] * V.m[c][k];
        H.m[r][c] = s;
      }
      break;
    }
  }
  // H2 = 4 K2 is PSD in exact arithmetic (Theorem 3); symmetrise against round-off.
  HSI_UNROLL for (int r = 0; r < 4; ++r) HSI_UNROLL for (int c = 0; c < 4; ++c) d.hess.m[r][c] = (H.m[r][c] + H.m[c][r]) / 2;
  return d;
}

// A real 2×2 block K acting on u ∈ C ≅ R² as K u = α u + β conj(u) (newton.cpp's
// complex_form): returns (Re α, Im α, Re β, Im β).
HSI_HD void complex_form(double k11, double k12, double k21, double k22, double out[4]) {
  out[0] = (k11 + k22) / 2;
  out[1] = (k21 - k12) / 2;
  out[2] = (k11 - k22) / 2;
  out[3] = (k21 + k12) / 2;
}

// The six complex weights of a sample's 4×4 Hessian for the structured assembly
// Dᴴ [α_aa∘D, β_aa∘D̄, α_ab∘D, β_ab∘D̄, α_bb∘D, β_bb∘D̄]: w[q] = (Re, Im) of weight q.
HSI_HD void hessian_weights(const Mat4& K, double w[6][2]) {
  double f[4];
  complex_form(K.m[0][0], K.m[0][1], K.m[1][0], K.m[1][1], f);
  w[0][0] = f[0], w[0][1] = f[1], w[1][0] = f[2], w[1][1] = f[3];
  complex_form(K.m[0][2], K.m[0][3], K.m[1][2], K.m[1][3], f);
  w[2][0] = f[0], w[2][1] = f[1], w[3][0] = f[2], w[3][1] = f[3];
  complex_form(K.m[2][2], K.m[2][3], K.m[3][2], K.m[3][3], f);
  w[4][0] = f[0], w[4][1] = f[1], w[5][0] = f[2], w[5][1] = f[3];
}

// First s > 0 with |a + s da| = |b + s db| (+inf if none): newton.cpp's max_safe_step
// for one sample. |a + t da|² − |b + t db|² = A t² + B t + C.
HSI_HD double first_fold_step(double ar, double ai, double br, double bi, double dar, double dai, double dbr, double dbi) {
  const double A = (dar * dar + dai * dai) - (dbr * dbr + dbi * dbi);
  const double B = 2 * ((ar * dar + ai * dai) - (br * dbr + bi * dbi));  // Re(a conj da) − Re(b conj db)
  const double C = (ar * ar + ai * ai) - (br * br + bi * bi);
  double t = infinity();
  if (::fabs(A) < 1e-300) {
    if (B < 0) t = -C / B;
  } else {
    const double disc = B * B - 4 * A * C;
    if (disc >= 0) {
      const double sq = ::sqrt(disc);
      const double q = -0.5 * (B + ::copysign(sq, B));
      const double r1 = q / A, r2 = q != 0 ? C / q : infinity();
      if (r1 > 0 && r1 < t) t = r1;
      if (r2 > 0 && r2 < t) t = r2;
    }
  }
  return t;
}

}  // namespace hsi::cuda::sample
