// The CPU Newton core's dense linear algebra: the Hessian's products over the samples
// (CpuNewtonCore::hessian: for a range of samples, Cᵀ W_aa, Cᵀ W_ab, Cᵀ W_bb, which sum
// B_sᵀ K_s B_s) and the Cholesky solve of the reduced Newton system (HostStepper::solve).
//
// dense_kernels.cpp is built twice: for the baseline instruction set, and on x86-64
// once more with AVX2 and FMA (four doubles a lane and fused multiply-adds: the Hessian
// call 1.8× faster than the baseline build on the 2-core development machine), in which build Eigen's namespace is renamed so that its
// templates never mix with the baseline's (ctest avx2_kernels_symbols checks). The
// dispatching functions pick the second where the processor has AVX2 and FMA. The two
// differ in rounding (FMA rounds once), not in what they compute.
//
// No Eigen types here: the two builds see different Eigens.
#pragma once

namespace hsi::detail {

// P (m × 3m, column-major) += [lower(Cᵀ W_aa), Cᵀ W_ab, lower(Cᵀ W_bb)], where
// C (rows × m) and W = [W_aa W_ab W_bb] (rows × 3m) are row-major. Only the lower
// triangles of the first and last blocks are written.
void hessian_accumulate(const double* C, const double* W, long rows, long m, double* P);

// x = (A + ridge I)⁻¹ b for a symmetric A (m × m, column-major; its lower triangle is
// read), by Cholesky. False, x untouched, where A + ridge I is not positive definite.
bool cholesky_solve(const double* A, long m, double ridge, const double* b, double* x);

// The same in two parts, for a factor solved with more than once (chord steps,
// NewtonOptions::kept_system): L (m × m, column-major) = the lower Cholesky factor of
// A + ridge I (L's strictly upper triangle is set to 0); false, L unspecified, where
// A + ridge I is not positive definite. Then x = (L Lᵀ)⁻¹ b.
bool cholesky_factor(const double* A, long m, double ridge, double* L);
void cholesky_solve_factored(const double* L, long m, const double* b, double* x);

// The builds, for tests and benchmarks; the _avx2_fma ones only on processors with both.
void hessian_accumulate_baseline(const double* C, const double* W, long rows, long m, double* P);
void hessian_accumulate_avx2_fma(const double* C, const double* W, long rows, long m, double* P);
bool cholesky_solve_baseline(const double* A, long m, double ridge, const double* b, double* x);
bool cholesky_solve_avx2_fma(const double* A, long m, double ridge, const double* b, double* x);
bool cholesky_factor_baseline(const double* A, long m, double ridge, double* L);
bool cholesky_factor_avx2_fma(const double* A, long m, double ridge, double* L);
void cholesky_solve_factored_baseline(const double* L, long m, const double* b, double* x);
void cholesky_solve_factored_avx2_fma(const double* L, long m, const double* b, double* x);
bool dense_kernels_have_avx2_fma();  // the AVX2 + FMA build exists and this processor runs it
const char* dense_kernels_name();     // "avx2+fma" or "baseline": the build the dispatchers run

}  // namespace hsi::detail
