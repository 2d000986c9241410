// One build of the Hessian's dense products (hessian_kernel.h): HSI_KERNEL_NAME names
// the function this build defines; the AVX2 + FMA build also renames Eigen's namespace.
#include "hessian_kernel.h"

#include <Eigen/Core>

#ifndef HSI_KERNEL_NAME
#define HSI_KERNEL_NAME hessian_accumulate_baseline
#endif

namespace hsi::detail {

void HSI_KERNEL_NAME(const double* C, const double* W, long rows, long m, double* P) {
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::Map<const RowMatrix> c(C, rows, m), w(W, rows, 3 * m);
  Eigen::Map<Eigen::MatrixXd> p(P, m, 3 * m);
  p.leftCols(m).triangularView<Eigen::Lower>() += c.transpose() * w.leftCols(m);
  p.middleCols(m, m).noalias() += c.transpose() * w.middleCols(m, m);
  p.rightCols(m).triangularView<Eigen::Lower>() += c.transpose() * w.rightCols(m);
}

}  // namespace hsi::detail
