// One build of the CPU Newton core's dense linear algebra (dense_kernels.h):
// HSI_KERNEL_SUFFIX names the build (its functions are name_suffix); the AVX2 + FMA
// build also renames Eigen's namespace.
#include "dense_kernels.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>

#ifndef HSI_KERNEL_SUFFIX
#define HSI_KERNEL_SUFFIX baseline
#endif
#define HSI_KERNEL_CAT2(name, suffix) name##_##suffix
#define HSI_KERNEL_CAT(name, suffix) HSI_KERNEL_CAT2(name, suffix)
#define HSI_KERNEL(name) HSI_KERNEL_CAT(name, HSI_KERNEL_SUFFIX)

namespace hsi::detail {

void HSI_KERNEL(hessian_accumulate)(const double* C, const double* W, long rows, long m, double* P) {
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::Map<const RowMatrix> c(C, rows, m), w(W, rows, 3 * m);
  Eigen::Map<Eigen::MatrixXd> p(P, m, 3 * m);
  p.leftCols(m).triangularView<Eigen::Lower>() += c.transpose() * w.leftCols(m);
  p.middleCols(m, m).noalias() += c.transpose() * w.middleCols(m, m);
  p.rightCols(m).triangularView<Eigen::Lower>() += c.transpose() * w.rightCols(m);
}

bool HSI_KERNEL(cholesky_factor)(const double* A, long m, double ridge, double* L) {
  Eigen::Map<Eigen::MatrixXd> l(L, m, m);
  l.triangularView<Eigen::Lower>() = Eigen::Map<const Eigen::MatrixXd>(A, m, m);
  l.diagonal().array() += ridge;
  // In place over L's lower triangle (Eigen's LLT on a Ref: no copy of the matrix).
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower> llt(l);
  if (llt.info() != Eigen::Success) return false;
  l.triangularView<Eigen::StrictlyUpper>().setZero();
  return l.diagonal().allFinite();
}

void HSI_KERNEL(cholesky_solve_factored)(const double* L, long m, const double* b, double* x) {
  const Eigen::Map<const Eigen::MatrixXd> l(L, m, m);
  Eigen::Map<Eigen::VectorXd> y(x, m);
  y = Eigen::Map<const Eigen::VectorXd>(b, m);
  l.triangularView<Eigen::Lower>().solveInPlace(y);
  l.triangularView<Eigen::Lower>().transpose().solveInPlace(y);
}

bool HSI_KERNEL(cholesky_solve)(const double* A, long m, double ridge, const double* b, double* x) {
  // The two parts below (the host stepper's path), x written only on success.
  Eigen::MatrixXd L(m, m);
  if (!HSI_KERNEL(cholesky_factor)(A, m, ridge, L.data())) return false;
  Eigen::VectorXd y(m);
  HSI_KERNEL(cholesky_solve_factored)(L.data(), m, b, y.data());
  if (!y.allFinite()) return false;
  Eigen::Map<Eigen::VectorXd>(x, m) = y;
  return true;
}

}  // namespace hsi::detail
