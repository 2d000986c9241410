// Which build of the CPU Newton core's dense linear algebra runs (dense_kernels.h).
#include "dense_kernels.h"

#include <stdexcept>

namespace hsi::detail {

bool dense_kernels_have_avx2_fma() {
#if defined(HSI_HAVE_AVX2_KERNELS)
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return has;
#else
  return false;
#endif
}

#if !defined(HSI_HAVE_AVX2_KERNELS)
void hessian_accumulate_avx2_fma(const double*, const double*, long, long, double*) {
  throw std::logic_error("this build of hsi has no AVX2 + FMA kernels");
}
bool cholesky_solve_avx2_fma(const double*, long, double, const double*, double*) {
  throw std::logic_error("this build of hsi has no AVX2 + FMA kernels");
}
bool cholesky_factor_avx2_fma(const double*, long, double, double*) {
  throw std::logic_error("this build of hsi has no AVX2 + FMA kernels");
}
void cholesky_solve_factored_avx2_fma(const double*, long, const double*, double*) {
  throw std::logic_error("this build of hsi has no AVX2 + FMA kernels");
}
#endif

void hessian_accumulate(const double* C, const double* W, long rows, long m, double* P) {
  if (dense_kernels_have_avx2_fma()) hessian_accumulate_avx2_fma(C, W, rows, m, P);
  else hessian_accumulate_baseline(C, W, rows, m, P);
}

bool cholesky_solve(const double* A, long m, double ridge, const double* b, double* x) {
  return dense_kernels_have_avx2_fma() ? cholesky_solve_avx2_fma(A, m, ridge, b, x)
                                       : cholesky_solve_baseline(A, m, ridge, b, x);
}

bool cholesky_factor(const double* A, long m, double ridge, double* L) {
  return dense_kernels_have_avx2_fma() ? cholesky_factor_avx2_fma(A, m, ridge, L) : cholesky_factor_baseline(A, m, ridge, L);
}

void cholesky_solve_factored(const double* L, long m, const double* b, double* x) {
  if (dense_kernels_have_avx2_fma()) cholesky_solve_factored_avx2_fma(L, m, b, x);
  else cholesky_solve_factored_baseline(L, m, b, x);
}

const char* dense_kernels_name() { return dense_kernels_have_avx2_fma() ? "avx2+fma" : "baseline"; }

}  // namespace hsi::detail
