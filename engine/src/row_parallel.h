// Products of a tall matrix A (a row per sample or breakpoint) with a few columns X,
// split over the OpenMP threads by ranges of rows. Eigen runs a product this thin on
// one thread, and as a GEMM it first copies all of A into packed panels; here each
// range is swept column by column (a column segment stays in cache for every column
// of X), so A is read once from memory and not copied.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <vector>
#include <omp.h>

namespace hsi::detail {

// Ranges of at most 2048 rows (a complex column segment of 32 KiB), and one per thread
// where each gets 256 rows or more.
inline int row_chunks(Eigen::Index rows) {
  const Eigen::Index by_size = (rows + 2047) / 2048;
  return static_cast<int>(std::max<Eigen::Index>({1, by_size, std::min<Eigen::Index>(rows / 256, omp_get_max_threads())}));
}

// A X.
template <class A, class X>
Eigen::Matrix<typename A::Scalar, Eigen::Dynamic, X::ColsAtCompileTime> rows_times(const Eigen::MatrixBase<A>& a,
                                                                                  const Eigen::MatrixBase<X>& x) {
  using Result = Eigen::Matrix<typename A::Scalar, Eigen::Dynamic, X::ColsAtCompileTime>;
  const Eigen::Index rows = a.rows();
  Result out(rows, x.cols());
  const typename X::PlainObject xx = x;  // evaluated once, shared by the threads
  const int chunks = row_chunks(rows);
#pragma omp parallel for schedule(static)
  for (int c = 0; c < chunks; ++c) {
    const Eigen::Index r0 = rows * c / chunks, len = rows * (c + 1) / chunks - r0;
    auto o = out.middleRows(r0, len);
    o.setZero();
    for (Eigen::Index j = 0; j < a.cols(); ++j) {
      const auto col = a.col(j).segment(r0, len);
      for (Eigen::Index k = 0; k < xx.cols(); ++k) o.col(k) += col * xx(j, k);
    }
  }
  return out;
}

// Aᴴ X: each range's dot products summed on its own thread, then the ranges added.
template <class A, class X>
Eigen::Matrix<typename A::Scalar, Eigen::Dynamic, X::ColsAtCompileTime> rows_adjoint_times(const Eigen::MatrixBase<A>& a,
                                                                                          const Eigen::MatrixBase<X>& x) {
  using Result = Eigen::Matrix<typename A::Scalar, Eigen::Dynamic, X::ColsAtCompileTime>;
  const Eigen::Index rows = a.rows();
  const int chunks = row_chunks(rows);
  std::vector<Result> parts(static_cast<size_t>(chunks));
#pragma omp parallel for schedule(static)
  for (int c = 0; c < chunks; ++c) {
    const Eigen::Index r0 = rows * c / chunks, len = rows * (c + 1) / chunks - r0;
    Result& p = parts[static_cast<size_t>(c)];
    p.resize(a.cols(), x.cols());
    for (Eigen::Index j = 0; j < a.cols(); ++j) {
      const auto col = a.col(j).segment(r0, len);
      for (Eigen::Index k = 0; k < x.cols(); ++k) p(j, k) = col.dot(x.col(k).segment(r0, len));  // Σ conj(a) x
    }
  }
  for (int c = 1; c < chunks; ++c) parts[0] += parts[static_cast<size_t>(c)];
  return parts[0];
}

}  // namespace hsi::detail
