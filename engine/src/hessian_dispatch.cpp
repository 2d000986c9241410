// Which build of the Hessian's dense products runs (hessian_kernel.h).
#include "hessian_kernel.h"

#include <stdexcept>

namespace hsi::detail {

bool hessian_kernel_has_avx2_fma() {
#if defined(HSI_HAVE_AVX2_KERNEL)
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return has;
#else
  return false;
#endif
}

#if !defined(HSI_HAVE_AVX2_KERNEL)
void hessian_accumulate_avx2_fma(const double*, const double*, long, long, double*) {
  throw std::logic_error("this build of hsi has no AVX2 + FMA Hessian kernel");
}
#endif

void hessian_accumulate(const double* C, const double* W, long rows, long m, double* P) {
  if (hessian_kernel_has_avx2_fma()) hessian_accumulate_avx2_fma(C, W, rows, m, P);
  else hessian_accumulate_baseline(C, W, rows, m, P);
}

const char* hessian_kernel_name() { return hessian_kernel_has_avx2_fma() ? "avx2+fma" : "baseline"; }

}  // namespace hsi::detail
