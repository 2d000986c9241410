// The dense part of the CPU Newton core's Hessian (CpuNewtonCore::hessian): for a range
// of samples, the three products Cᵀ W_aa, Cᵀ W_ab, Cᵀ W_bb that sum B_sᵀ K_s B_s.
//
// hessian_kernel.cpp is built twice: for the baseline instruction set, and on x86-64
// once more with AVX2 and FMA (four doubles a lane and fused multiply-adds: about
// three times the baseline's speed on these products), in which build Eigen's
// namespace is renamed so that its templates never mix with the baseline's.
// hessian_accumulate picks the second where the processor has AVX2 and FMA. The two
// differ in rounding (FMA rounds once), not in what they compute.
//
// No Eigen types here: the two builds see different Eigens.
#pragma once

namespace hsi::detail {

// P (m × 3m, column-major) += [lower(Cᵀ W_aa), Cᵀ W_ab, lower(Cᵀ W_bb)], where
// C (rows × m) and W = [W_aa W_ab W_bb] (rows × 3m) are row-major. Only the lower
// triangles of the first and last blocks are written.
void hessian_accumulate(const double* C, const double* W, long rows, long m, double* P);

// The variants, for tests and benchmarks.
void hessian_accumulate_baseline(const double* C, const double* W, long rows, long m, double* P);
void hessian_accumulate_avx2_fma(const double* C, const double* W, long rows, long m, double* P);  // AVX2 processors only
bool hessian_kernel_has_avx2_fma();  // the AVX2 + FMA build exists and this processor runs it
const char* hessian_kernel_name();   // "avx2+fma" or "baseline": the one hessian_accumulate runs

}  // namespace hsi::detail
