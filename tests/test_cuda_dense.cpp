// The GPU's dense Cholesky factor and solve (cuda/src/dense_cholesky.h) against Eigen's
// LLT: the factor of well- and ill-conditioned SPD matrices at every tile boundary, the
// solve's residual, the first failing column of matrices that are not positive definite
// (LAPACK's info), the untouched upper triangle, and the same results from a CUDA graph
// that captured the calls. Tests that need a GPU skip with a warning where there is none.
#include <catch2/catch.hpp>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <cuda_runtime.h>

#include "dense_cholesky.h"
#include "device.h"
#include "cuda_test.h"
#include "hsi/cuda/newton_core.h"

namespace hc = hsi::cuda;
namespace hk = hsi::cuda::kernels;

namespace {

constexpr int kOrders[] = {1, 2, 3, 31, 32, 33, 63, 64, 65, 100, 255, 256, 257, 305, 400, 700, 1200};
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A = B Bᵀ + m I: eigenvalues in [m, ~2m], well conditioned.
Eigen::MatrixXd well_conditioned(int m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixXd B(m, m);
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) B(i, j) = u(rng);
  Eigen::MatrixXd A = B * B.transpose();
  A.diagonal().array() += m;
  return A;
}

// A = Q diag(λ) Qᵀ, Q random orthogonal, λ log-spaced from 1 down to 1/cond.
Eigen::MatrixXd ill_conditioned(int m, double cond, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd R(m, m);
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) R(i, j) = g(rng);
  const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(R).householderQ();
  Eigen::VectorXd lambda(m);
  for (int i = 0; i < m; ++i) lambda(i) = m == 1 ? 1.0 : std::pow(cond, -static_cast<double>(i) / (m - 1));
  Eigen::MatrixXd A = Q * lambda.asDiagonal() * Q.transpose();
  return 0.5 * (A + A.transpose());
}

Eigen::VectorXd random_vector(int m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::VectorXd b(m);
  for (int i = 0; i < m; ++i) b(i) = u(rng);
  return b;
}

// A column-major m × m matrix with leading dimension lda on the device; the strictly
// upper triangle and the rows past m hold NaN, which the factor must neither read nor
// overwrite.
// A plain cudaMemcpy runs on the legacy default stream: host to device from pageable
// memory may return before its DMA lands, device to device returns at once, and the
// kernels below run on a non-blocking stream that is not ordered after either. Seen on an
// H200: a good matrix uploaded over a failed factor's output was factored while the
// copy's tail was still in flight, and reported a failing column (256, 289, 230 at m = 305).
void copies_landed() { HSI_CUDA_CHECK(cudaDeviceSynchronize()); }

struct DeviceSystem {
  int m, lda;
  std::vector<double> host;  // lda × m, what was uploaded
  hc::DeviceArray<double> A, b;
  hc::DeviceArray<int> info{1};
  DeviceSystem(const Eigen::MatrixXd& M, int lda_, const Eigen::VectorXd& rhs)
      : m(static_cast<int>(M.rows())), lda(lda_), host(static_cast<size_t>(lda_) * M.cols(), kNaN),
        A(host.size()), b(static_cast<size_t>(M.rows())) {
    for (int j = 0; j < m; ++j)
      for (int i = j; i < m; ++i) host[static_cast<size_t>(i) + static_cast<size_t>(j) * lda] = M(i, j);
    upload(rhs);
  }
  void upload(const Eigen::VectorXd& rhs) {
    HSI_CUDA_CHECK(cudaMemcpy(A.get(), host.data(), A.bytes(), cudaMemcpyHostToDevice));
    HSI_CUDA_CHECK(cudaMemcpy(b.get(), rhs.data(), b.bytes(), cudaMemcpyHostToDevice));
    const int minus_one = -1;  // the factor must overwrite it
    HSI_CUDA_CHECK(cudaMemcpy(info.get(), &minus_one, sizeof(int), cudaMemcpyHostToDevice));
    copies_landed();
  }
  std::vector<double> matrix() const {
    std::vector<double> out(host.size());
    HSI_CUDA_CHECK(cudaMemcpy(out.data(), A.get(), A.bytes(), cudaMemcpyDeviceToHost));
    return out;
  }
  Eigen::MatrixXd lower() const {
    const std::vector<double> a = matrix();
    Eigen::MatrixXd L = Eigen::MatrixXd::Zero(m, m);
    for (int j = 0; j < m; ++j)
      for (int i = j; i < m; ++i) L(i, j) = a[static_cast<size_t>(i) + static_cast<size_t>(j) * lda];
    return L;
  }
  Eigen::VectorXd solution() const {
    Eigen::VectorXd x(m);
    HSI_CUDA_CHECK(cudaMemcpy(x.data(), b.get(), b.bytes(), cudaMemcpyDeviceToHost));
    return x;
  }
  int info_value() const {
    int v = -2;
    HSI_CUDA_CHECK(cudaMemcpy(&v, info.get(), sizeof(int), cudaMemcpyDeviceToHost));
    return v;
  }
  // Every entry outside the lower triangle still the NaN uploaded (bit for bit).
  bool outside_lower_untouched() const {
    const std::vector<double> a = matrix();
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < lda; ++i) {
        if (i >= j && i < m) continue;
        if (!std::isnan(a[static_cast<size_t>(i) + static_cast<size_t>(j) * lda])) return false;
      }
    return true;
  }
  void factor_and_solve(cudaStream_t s) {
    HSI_CUDA_CHECK(hk::cholesky_factor(m, A.get(), lda, info.get(), s));
    HSI_CUDA_CHECK(hk::cholesky_solve(m, A.get(), lda, b.get(), s));
  }
};

double max_abs(const Eigen::MatrixXd& M) { return M.size() ? M.cwiseAbs().maxCoeff() : 0.0; }

// |A x − b|∞ / (|A|∞ |x|∞): the solve's normwise backward error.
double residual(const Eigen::MatrixXd& A, const Eigen::VectorXd& x, const Eigen::VectorXd& b) {
  const double a_norm = A.cwiseAbs().rowwise().sum().maxCoeff();
  return (A * x - b).cwiseAbs().maxCoeff() / (a_norm * x.cwiseAbs().maxCoeff());
}

// LAPACK's dpotrf2 rule, written out (unblocked, left-looking): the 1-based column of
// the first pivot that is not > 0 (NaN included) or is infinite, 0 if none.
int reference_info(const Eigen::MatrixXd& A) {
  const int m = static_cast<int>(A.rows());
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(m, m);
  for (int j = 0; j < m; ++j) {
    double pivot = A(j, j);
    for (int p = 0; p < j; ++p) pivot -= L(j, p) * L(j, p);
    if (!(pivot > 0.0) || std::isinf(pivot)) return j + 1;
    L(j, j) = std::sqrt(pivot);
    for (int i = j + 1; i < m; ++i) {
      double s = A(i, j);
      for (int p = 0; p < j; ++p) s -= L(i, p) * L(j, p);
      L(i, j) = s / L(j, j);
    }
  }
  return 0;
}

}  // namespace

TEST_CASE("dense Cholesky: bad arguments are refused before any launch", "[cuda][dense]") {
  // No GPU needed: the checks come first.
  int* info = nullptr;
  double* A = nullptr;
  CHECK(hk::cholesky_factor(-1, A, 1, info, nullptr) == cudaErrorInvalidValue);
  CHECK(hk::cholesky_factor(10, A, 9, info, nullptr) == cudaErrorInvalidValue);
  CHECK(hk::cholesky_factor(0, A, 0, info, nullptr) == cudaErrorInvalidValue);
  CHECK(hk::cholesky_solve(-1, A, 1, A, nullptr) == cudaErrorInvalidValue);
  CHECK(hk::cholesky_factor_solve(-1, A, 1, A, info, nullptr) == cudaErrorInvalidValue);
  CHECK(hk::cholesky_factor_solve(10, A, 9, A, info, nullptr) == cudaErrorInvalidValue);
  CHECK(hk::cholesky_factor_solve(hk::kCholeskySolveMaxOrder + 1, A, hk::kCholeskySolveMaxOrder + 1, A, info, nullptr) ==
        cudaErrorInvalidValue);
  CHECK(hk::cholesky_solve(10, A, 9, A, nullptr) == cudaErrorInvalidValue);
  CHECK(hk::cholesky_solve(hk::kCholeskySolveMaxOrder + 1, A, hk::kCholeskySolveMaxOrder + 1, A, nullptr) ==
        cudaErrorInvalidValue);
}

TEST_CASE("dense Cholesky: the factor matches Eigen's LLT and the solve's residual is at rounding level", "[cuda][dense]") {
  HSI_REQUIRE_GPU();
  hc::Stream stream;
  for (const int m : kOrders) {
    for (const bool ill : {false, true}) {
      const double cond = 1e10;
      const Eigen::MatrixXd A = ill ? ill_conditioned(m, cond, 100u + static_cast<unsigned>(m)) : well_conditioned(m, static_cast<unsigned>(m));
      const Eigen::VectorXd b = random_vector(m, 7u + static_cast<unsigned>(m));
      const Eigen::LLT<Eigen::MatrixXd> llt(A);
      REQUIRE(llt.info() == Eigen::Success);
      const Eigen::MatrixXd L_eigen = llt.matrixL();
      for (const int pad : {0, 3}) {  // lda = m (the Newton system's) and lda > m
        if (pad && m % 2 == 0 && m > 64) continue;  // a padded leading dimension at a subset of orders is enough
        INFO("m = " << m << (ill ? ", cond 1e10" : ", well conditioned") << ", lda = m + " << pad);
        DeviceSystem sys(A, m + pad, b);
        sys.factor_and_solve(stream);
        HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
        CHECK(sys.info_value() == 0);
        CHECK(sys.outside_lower_untouched());
        const Eigen::MatrixXd L = sys.lower();
        // Backward error of the factor: a stable Cholesky gives |A − L Lᵀ| ≲ m ε |A|.
        const double backward = max_abs(A - L * L.transpose()) / max_abs(A);
        CHECK(backward < 1e-15 * (m + 16));
        // Two stable factors differ by up to ~ cond · ε (perturbation bound).
        const double rel = max_abs(L - L_eigen) / max_abs(L_eigen);
        CHECK(rel < (ill ? 1e-15 * cond : 1e-13));
        const Eigen::VectorXd x = sys.solution();
        CHECK(residual(A, x, b) < 1e-12);
        // The fused call: the same factor bit for bit (the extra row of b changes no
        // entry of L's arithmetic), and a solution at rounding level.
        DeviceSystem fused(A, m + pad, b);
        HSI_CUDA_CHECK(hk::cholesky_factor_solve(m, fused.A.get(), fused.lda, fused.b.get(), fused.info.get(), stream));
        HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
        CHECK(fused.info_value() == 0);
        CHECK(fused.outside_lower_untouched());
        const std::vector<double> want_A = sys.matrix(), got_A = fused.matrix();
        CHECK(std::memcmp(got_A.data(), want_A.data(), got_A.size() * sizeof(double)) == 0);
        const Eigen::VectorXd x_fused = fused.solution();
        CHECK(residual(A, x_fused, b) < 1e-12);
        if (!ill) CHECK((x_fused - x).cwiseAbs().maxCoeff() <= 1e-12 * x.cwiseAbs().maxCoeff());
      }
    }
  }
}

TEST_CASE("dense Cholesky: a matrix that is not positive definite gives LAPACK's first failing column", "[cuda][dense]") {
  HSI_REQUIRE_GPU();
  hc::Stream stream;
  struct Case {
    int m, row, col;  // the entry (0-based, row ≥ col) made bad
    double value;
    int want;         // 1-based first failing column
  };
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<Case> cases;
  for (const int m : {1, 2, 33, 64, 65, 305, 700})
    for (const int k : {1, 2, 32, 33, 64, 65, 200, m})  // k: the 1-based column of the negative pivot
      if (k <= m) {
        cases.push_back({m, k - 1, k - 1, -1.0, k});
        cases.push_back({m, k - 1, k - 1, kNaN, k});
        cases.push_back({m, k - 1, k - 1, inf, k});
        if (k < m) cases.push_back({m, m - 1, k - 1, kNaN, m});  // NaN below the diagonal fails its row's pivot
      }
  for (const Case& c : cases) {
    INFO("m = " << c.m << ", A(" << c.row << ", " << c.col << ") = " << c.value << ", want info " << c.want);
    Eigen::MatrixXd A = well_conditioned(c.m, 11u);
    A(c.row, c.col) = c.value;
    A(c.col, c.row) = c.value;
    REQUIRE(reference_info(A) == c.want);
    if (c.value == -1.0) {  // Eigen's own unblocked LLT agrees (it stops at a pivot ≤ 0)
      Eigen::MatrixXd E = A;
      CHECK(Eigen::internal::llt_inplace<double, Eigen::Lower>::unblocked(E) == c.want - 1);
    }
    DeviceSystem sys(A, c.m, random_vector(c.m, 3u));
    HSI_CUDA_CHECK(hk::cholesky_factor(c.m, sys.A.get(), c.m, sys.info.get(), stream));
    HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
    CHECK(sys.info_value() == c.want);
    // The fused factor and solve reports the same column (not the bordered pivot of b).
    DeviceSystem fused(A, c.m, random_vector(c.m, 3u));
    HSI_CUDA_CHECK(hk::cholesky_factor_solve(c.m, fused.A.get(), c.m, fused.b.get(), fused.info.get(), stream));
    HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
    CHECK(fused.info_value() == c.want);
    // The same info buffer is reset by the next, successful, factorisation.
    sys.host.assign(sys.host.size(), kNaN);
    const Eigen::MatrixXd good = well_conditioned(c.m, 12u);
    for (int j = 0; j < c.m; ++j)
      for (int i = j; i < c.m; ++i) sys.host[static_cast<size_t>(i) + static_cast<size_t>(j) * c.m] = good(i, j);
    HSI_CUDA_CHECK(cudaMemcpy(sys.A.get(), sys.host.data(), sys.A.bytes(), cudaMemcpyHostToDevice));
    copies_landed();
    HSI_CUDA_CHECK(hk::cholesky_factor(c.m, sys.A.get(), c.m, sys.info.get(), stream));
    HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
    CHECK(sys.info_value() == 0);
  }
}

TEST_CASE("dense Cholesky: the calls captured into a CUDA graph give the same results, replay after replay", "[cuda][dense]") {
  HSI_REQUIRE_GPU();
  hc::Stream stream;
  for (const int m : {1, 33, 305, 700}) {
    for (const bool fails : {false, true})
    for (const bool fused : {false, true}) {  // factor + solve, or cholesky_factor_solve
      INFO("m = " << m << (fails ? ", pivot " + std::to_string(m / 2 + 1) + " negative" : ", SPD") << (fused ? ", fused" : ""));
      Eigen::MatrixXd A = well_conditioned(m, 21u);
      if (fails) A(m / 2, m / 2) = -1.0;
      const Eigen::VectorXd b = random_vector(m, 22u);
      // Direct calls: the reference.
      DeviceSystem direct(A, m, b);
      if (fused) HSI_CUDA_CHECK(hk::cholesky_factor_solve(m, direct.A.get(), m, direct.b.get(), direct.info.get(), stream));
      else direct.factor_and_solve(stream);
      HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
      const std::vector<double> want_A = direct.matrix();
      const Eigen::VectorXd want_x = direct.solution();
      const int want_info = direct.info_value();
      CHECK(want_info == (fails ? m / 2 + 1 : 0));

      // The graph restores A and b from pristine copies, then factors and solves.
      DeviceSystem sys(A, m, b);
      hc::DeviceArray<double> A0(sys.A.size()), b0(sys.b.size());
      HSI_CUDA_CHECK(cudaMemcpy(A0.get(), sys.A.get(), sys.A.bytes(), cudaMemcpyDeviceToDevice));
      HSI_CUDA_CHECK(cudaMemcpy(b0.get(), sys.b.get(), sys.b.bytes(), cudaMemcpyDeviceToDevice));
      copies_landed();
      cudaGraph_t graph = nullptr;
      HSI_CUDA_CHECK(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal));
      HSI_CUDA_CHECK(cudaMemcpyAsync(sys.A.get(), A0.get(), sys.A.bytes(), cudaMemcpyDeviceToDevice, stream));
      HSI_CUDA_CHECK(cudaMemcpyAsync(sys.b.get(), b0.get(), sys.b.bytes(), cudaMemcpyDeviceToDevice, stream));
      const cudaError_t factor = fused ? hk::cholesky_factor_solve(m, sys.A.get(), m, sys.b.get(), sys.info.get(), stream)
                                       : hk::cholesky_factor(m, sys.A.get(), m, sys.info.get(), stream);
      const cudaError_t solve = fused ? cudaSuccess : hk::cholesky_solve(m, sys.A.get(), m, sys.b.get(), stream);
      HSI_CUDA_CHECK(cudaStreamEndCapture(stream, &graph));
      REQUIRE(factor == cudaSuccess);
      REQUIRE(solve == cudaSuccess);
      cudaGraphExec_t exec = nullptr;
      HSI_CUDA_CHECK(cudaGraphInstantiate(&exec, graph, 0));
      for (int replay = 0; replay < 2; ++replay) {
        INFO("replay " << replay);
        const int stale = 12345;  // each replay must write info afresh
        HSI_CUDA_CHECK(cudaMemcpy(sys.info.get(), &stale, sizeof(int), cudaMemcpyHostToDevice));
        copies_landed();
        HSI_CUDA_CHECK(cudaGraphLaunch(exec, stream));
        HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
        CHECK(sys.info_value() == want_info);
        // Bit for bit (memcmp: the NaN of the upper triangle, and of a failed factor's
        // columns, compare unequal as doubles): the same kernels on the same data.
        const std::vector<double> got_A = sys.matrix();
        CHECK(std::memcmp(got_A.data(), want_A.data(), got_A.size() * sizeof(double)) == 0);
        const Eigen::VectorXd x = sys.solution();
        CHECK(std::memcmp(x.data(), want_x.data(), static_cast<size_t>(m) * sizeof(double)) == 0);
      }
      cudaGraphExecDestroy(exec);
      cudaGraphDestroy(graph);
    }
  }
}

TEST_CASE("dense Cholesky: the solve with a given factor (cuSOLVER's potrf) agrees with Eigen's at every order the cluster takes",
          "[cuda][dense]") {
  HSI_REQUIRE_GPU();
  hc::Stream stream;
  int device = 0, major = 0;
  HSI_CUDA_CHECK(cudaGetDevice(&device));
  HSI_CUDA_CHECK(cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, device));
  // The CUDA core solves with factors it did not make (potrf's, the kept one): L from
  // Eigen here, the strictly upper triangle NaN (never read), at the orders around each
  // tile and around the cluster's limit, where the one-block kernel takes over.
  std::vector<int> orders = {1, 2, 31, 32, 33, 95, 96, 97, 124, 166, 174, 208, 216, 250, 255, 256, 257, 292, 293, 300, 416,
                             480, 511, 512, 513, 600};
  for (const int m : orders) {
    INFO("m = " << m);
    if (major >= 9 && m <= hk::kCholeskySolveClusterMaxOrder) CHECK(hk::cholesky_solve_in_cluster(m));
    if (m > hk::kCholeskySolveClusterMaxOrder) CHECK_FALSE(hk::cholesky_solve_in_cluster(m));
    for (const bool ill : {false, true}) {
      INFO((ill ? "cond 1e8" : "well conditioned"));
      const Eigen::MatrixXd A = ill ? ill_conditioned(m, 1e8, 300u + static_cast<unsigned>(m)) : well_conditioned(m, 301u + static_cast<unsigned>(m));
      const Eigen::LLT<Eigen::MatrixXd> llt(A);
      REQUIRE(llt.info() == Eigen::Success);
      const Eigen::MatrixXd L = llt.matrixL();
      const Eigen::VectorXd b = random_vector(m, 302u + static_cast<unsigned>(m));
      const Eigen::VectorXd want = llt.solve(b);
      const int lda = m + (m % 3 == 0 ? 5 : 0);  // a padded leading dimension at some orders
      DeviceSystem sys(L, lda, b);
      HSI_CUDA_CHECK(hk::cholesky_solve(m, sys.A.get(), lda, sys.b.get(), stream));
      HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
      CHECK(sys.outside_lower_untouched());
      const Eigen::VectorXd x = sys.solution();
      CHECK(x.allFinite());
      CHECK(residual(A, x, b) < 1e-12);
      // Two backward-stable triangular solves with the same L differ by ~cond(A) ε.
      CHECK((x - want).cwiseAbs().maxCoeff() <= (ill ? 1e-6 : 1e-12) * want.cwiseAbs().maxCoeff());
      // The same bits on a second run: every sum in a fixed order, whatever the timing
      // between the cluster's warps.
      sys.upload(b);
      HSI_CUDA_CHECK(hk::cholesky_solve(m, sys.A.get(), lda, sys.b.get(), stream));
      HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
      const Eigen::VectorXd again = sys.solution();
      CHECK(std::memcmp(again.data(), x.data(), static_cast<size_t>(m) * sizeof(double)) == 0);
      // The two substitutions apart (the Newton decrement ‖L⁻¹b‖² before the direction):
      // the forward one gives L⁻¹ b, and the back one after it the whole solve's bits.
      sys.upload(b);
      HSI_CUDA_CHECK(hk::cholesky_solve(m, sys.A.get(), lda, sys.b.get(), stream, hk::Substitution::Forward));
      HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
      const Eigen::VectorXd y = sys.solution(), y_want = L.triangularView<Eigen::Lower>().solve(b);
      CHECK((y - y_want).cwiseAbs().maxCoeff() <= (ill ? 1e-6 : 1e-12) * y_want.cwiseAbs().maxCoeff());
      CHECK(std::abs(y.squaredNorm() - b.dot(want)) <= (ill ? 1e-6 : 1e-11) * std::abs(b.dot(want)));
      HSI_CUDA_CHECK(hk::cholesky_solve(m, sys.A.get(), lda, sys.b.get(), stream, hk::Substitution::Back));
      HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
      CHECK(sys.outside_lower_untouched());
      const Eigen::VectorXd parts = sys.solution();
      CHECK(std::memcmp(parts.data(), x.data(), static_cast<size_t>(m) * sizeof(double)) == 0);
    }
  }
}

TEST_CASE("dense Cholesky, batched: each matrix's factor, status and solve are the single call's, bit for bit",
          "[cuda][dense][batched]") {
  // Bad arguments first (no GPU needed): overlapping strides, a batch out of range.
  {
    double* A = nullptr;
    int* info = nullptr;
    CHECK(hk::cholesky_factor_batched(10, A, 10, 99, info, 2, nullptr) == cudaErrorInvalidValue);
    CHECK(hk::cholesky_factor_batched(10, A, 10, 100, info, -1, nullptr) == cudaErrorInvalidValue);
    CHECK(hk::cholesky_factor_batched(10, A, 10, 100, info, 65536, nullptr) == cudaErrorInvalidValue);
    CHECK(hk::cholesky_solve_batched(10, A, 10, 100, A, 9, 2, nullptr) == cudaErrorInvalidValue);
    CHECK(hk::cholesky_solve_batched(10, A, 10, 99, A, 10, 2, nullptr) == cudaErrorInvalidValue);
  }
  HSI_REQUIRE_GPU();
  hc::Stream stream;
  // Orders inside the cluster kernel (one launch) and one above it (one matrix after the
  // other); in each batch one matrix is not positive definite, at a column of its own.
  for (const int m : {1, 33, 100, 292, 305, 512, 700}) {
    const int batch = m > 400 ? 3 : 9, lda = m + 1;
    const long long stride = static_cast<long long>(lda) * m + 5;  // a gap between matrices, NaN
    const int bad = batch / 2, bad_column = (m + 1) / 2;
    std::vector<double> host(static_cast<size_t>(stride) * batch, kNaN), rhs(static_cast<size_t>(m + 2) * batch, kNaN);
    std::vector<Eigen::MatrixXd> mats;
    for (int k = 0; k < batch; ++k) {
      Eigen::MatrixXd A = k % 2 ? ill_conditioned(m, 1e8, 300u + static_cast<unsigned>(k)) : well_conditioned(m, 200u + static_cast<unsigned>(k));
      if (k == bad) A(bad_column - 1, bad_column - 1) = -1e6;  // fails at that column or before it
      mats.push_back(A);
      for (int j = 0; j < m; ++j)
        for (int i = j; i < m; ++i) host[static_cast<size_t>(k * stride + i + static_cast<long long>(j) * lda)] = A(i, j);
      const Eigen::VectorXd b = random_vector(m, 400u + static_cast<unsigned>(k));
      for (int i = 0; i < m; ++i) rhs[static_cast<size_t>(k * (m + 2) + i)] = b(i);
    }
    hc::DeviceArray<double> A(host.size()), b(rhs.size());
    hc::DeviceArray<int> info(static_cast<size_t>(batch));
    HSI_CUDA_CHECK(cudaMemcpy(A.get(), host.data(), A.bytes(), cudaMemcpyHostToDevice));
    HSI_CUDA_CHECK(cudaMemcpy(b.get(), rhs.data(), b.bytes(), cudaMemcpyHostToDevice));
    HSI_CUDA_CHECK(cudaMemset(info.get(), 0xff, info.bytes()));
    copies_landed();
    HSI_CUDA_CHECK(hk::cholesky_factor_batched(m, A.get(), lda, stride, info.get(), batch, stream));
    HSI_CUDA_CHECK(hk::cholesky_solve_batched(m, A.get(), lda, stride, b.get(), m + 2, batch, stream));
    HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
    std::vector<double> factors(host.size()), solutions(rhs.size());
    std::vector<int> infos(static_cast<size_t>(batch));
    HSI_CUDA_CHECK(cudaMemcpy(factors.data(), A.get(), A.bytes(), cudaMemcpyDeviceToHost));
    HSI_CUDA_CHECK(cudaMemcpy(solutions.data(), b.get(), b.bytes(), cudaMemcpyDeviceToHost));
    HSI_CUDA_CHECK(cudaMemcpy(infos.data(), info.get(), info.bytes(), cudaMemcpyDeviceToHost));
    INFO("m = " << m << ", batch " << batch << (hk::cholesky_batched_in_cluster(m) ? " (one launch)" : " (one by one)"));
    for (int k = 0; k < batch; ++k) {
      INFO("matrix " << k);
      // The same matrix alone through the single calls.
      const Eigen::VectorXd bk = random_vector(m, 400u + static_cast<unsigned>(k));
      DeviceSystem one(mats[static_cast<size_t>(k)], lda, bk);
      one.factor_and_solve(stream);
      HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
      CHECK(infos[static_cast<size_t>(k)] == one.info_value());
      if (k == bad) {
        CHECK(infos[static_cast<size_t>(k)] == reference_info(mats[static_cast<size_t>(k)]));
        CHECK(infos[static_cast<size_t>(k)] >= 1);
      } else {
        CHECK(infos[static_cast<size_t>(k)] == 0);
      }
      const std::vector<double> alone = one.matrix();
      bool same = true, untouched = true;
      for (int j = 0; j < m; ++j)
        for (int i = 0; i < lda; ++i) {
          const double v = factors[static_cast<size_t>(k * stride + i + static_cast<long long>(j) * lda)];
          if (i >= j && i < m) same = same && std::memcmp(&v, &alone[static_cast<size_t>(i + j * lda)], sizeof v) == 0;
          else untouched = untouched && std::isnan(v);
        }
      CHECK(same);
      CHECK(untouched);
      if (k != bad) {
        const Eigen::VectorXd x = one.solution();
        bool same_x = true;
        for (int i = 0; i < m; ++i) same_x = same_x && std::memcmp(&solutions[static_cast<size_t>(k * (m + 2) + i)], &x(i), sizeof(double)) == 0;
        CHECK(same_x);
        CHECK(residual(mats[static_cast<size_t>(k)], x, bk) < 1e-12);
      }
      // The gaps between matrices and right-hand sides are never written.
      for (long long g = k * stride + static_cast<long long>(lda) * m; g < (k + 1) * stride; ++g)
        CHECK(std::isnan(factors[static_cast<size_t>(g)]));
      CHECK(std::isnan(solutions[static_cast<size_t>(k * (m + 2) + m)]));
    }
  }
}
