// CudaNewtonCore::solve: engine/src/newton.cpp's newton_solve with every step on the
// device. Per iteration: gradient (cuBLAS), the PSD Hessian (kernels + ZGEMM), the
// reduced system Tᵀ H T and its Cholesky factor and solve (cuSOLVER), the direction
// and the maximal safe step; then the Armijo trials, a batch of step sizes per launch;
// then the certificate of the trial map (certify_kernels.cu). The host sees three small
// downloads per iteration: {slope, |g|², s_max, diag, info} with the direction d
// (dim doubles), the trial energies, and the certificate's summary.
//
// Same arithmetic and decisions as the host loop, so the two agree to round-off (the
// tests compare them frame by frame).
#include <chrono>
#include <cmath>
#include <limits>

#include "cuda_newton_core.h"
#include "newton_kernels.h"

namespace hsi::cuda {

using Clock = std::chrono::steady_clock;
namespace {
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
constexpr int kBatch = 4;  // Armijo trial steps evaluated per launch
// Scalar slots of DeviceSpace::sc.
enum Slot { kSlope = 0, kGradNorm2 = 1, kSafeStep = 2, kDiagMax = 3, kEnergy0 = 4, kTrials = 5, kSlots = kTrials + kBatch };
}  // namespace


CudaNewtonCore::~CudaNewtonCore() { cudaStreamSynchronize(stream_); }

DeviceSpace& CudaNewtonCore::device_space(const MapSpace& space) {
  auto& slot = spaces_[&space];
  if (slot) return *slot;
  auto ds = std::make_unique<DeviceSpace>();
  const int dim = space.dim(), n = n_;
  if (space.n() != n) throw InputError("hsi::cuda: the map space has " + std::to_string(space.n()) + " active columns, the core " + std::to_string(n));
  const int M = space.full_size();
  ds->dim = dim;
  ds->n4 = 4 * n;
  ds->M4 = 4 * M;
  const Eigen::MatrixXd T = Eigen::MatrixXd(space.T());
  // Tc: row 2j ← Re φ_j (row j of T), 2j+1 ← Im φ_j (n + j), 2n+2j ← Re ψ_j, 2n+2j+1 ← Im ψ_j.
  Eigen::MatrixXd Tc(4 * n, dim);
  for (int j = 0; j < n; ++j) {
    Tc.row(2 * j) = T.row(j);
    Tc.row(2 * j + 1) = T.row(n + j);
    Tc.row(2 * n + 2 * j) = T.row(2 * n + j);
    Tc.row(2 * n + 2 * j + 1) = T.row(3 * n + j);
  }
  // expand() is affine in x: probe it at 0 and at each unit vector.
  auto flat = [&](const HarmonicMap& h) {
    Eigen::VectorXd v(4 * M);
    for (int j = 0; j < M; ++j) {
      v(2 * j) = h.phi(j).real();
      v(2 * j + 1) = h.phi(j).imag();
      v(2 * M + 2 * j) = h.psi(j).real();
      v(2 * M + 2 * j + 1) = h.psi(j).imag();
    }
    return v;
  };
  Eigen::VectorXd e = Eigen::VectorXd::Zero(dim);
  const Eigen::VectorXd x0 = flat(space.expand(e));
  Eigen::MatrixXd X(4 * M, dim);
  for (int k = 0; k < dim; ++k) {
    e.setZero();
    e(k) = 1;
    X.col(k) = flat(space.expand(e)) - x0;
  }
  auto upload = [&](DeviceArray<double>& dst, const double* src, size_t count) {
    dst = DeviceArray<double>(count);
    HSI_CUDA_CHECK(cudaMemcpy(dst.get(), src, count * sizeof(double), cudaMemcpyHostToDevice));
  };
  upload(ds->T, T.data(), static_cast<size_t>(T.size()));
  upload(ds->Tc, Tc.data(), static_cast<size_t>(Tc.size()));
  upload(ds->X, X.data(), static_cast<size_t>(X.size()));
  upload(ds->X0, x0.data(), static_cast<size_t>(x0.size()));
  const size_t D = sz(dim);
  ds->x = DeviceArray<double>(D);
  ds->xn = DeviceArray<double>(D);
  ds->g = DeviceArray<double>(D);
  ds->d = DeviceArray<double>(D);
  ds->Hr = DeviceArray<double>(D * D);
  ds->Hr0 = DeviceArray<double>(D * D);
  ds->Y = DeviceArray<double>(4 * sz(n) * D);
  ds->full = DeviceArray<double>(4 * sz(M));
  ds->info = DeviceArray<int>(1);
  ds->sc = DeviceArray<double>(kSlots);
  ds->sc_down = PinnedArray<double>(kSlots);
  ds->d_down = PinnedArray<double>(D);
  ds->info_down = PinnedArray<int>(1);
  ds->x_up = PinnedArray<double>(D);
  HSI_CUDA_CHECK(cusolverDnDpotrf_bufferSize(solver_, CUBLAS_FILL_MODE_LOWER, dim, ds->Hr.get(), dim, &ds->lwork));
  ds->work = DeviceArray<double>(sz(std::max(1, ds->lwork)));
  slot = std::move(ds);
  return *slot;
}

bool CudaNewtonCore::solve(const MapSpace& space, const Certifier* certifier, const QuadraticTerm* quad,
                           const Eigen::VectorXd& x0, const NewtonOptions& opt, NewtonResult* out) {
  // Only for the setup this core was made with: its certifier is the one on the device.
  if (!setup_ || (certifier && certifier != &setup_->certifier)) return false;
  if (&space != &setup_->map_space && &space != &setup_->metric_space) return false;
  const auto t_start = Clock::now();
  DeviceSpace& S = device_space(space);
  const int dim = S.dim;
  if (x0.size() != dim) throw InputError("hsi::cuda: the start vector has " + std::to_string(x0.size()) + " entries, the space " + std::to_string(dim));
  const cudaStream_t st = stream_;
  const bool certify = opt.certify && certifier;
  const double one = 1, zero = 0, minus_one = -1;
  const double count = static_cast<double>(G_);

  if (quad) {
    if (quad->Q.rows() != dim || quad->Q.cols() != dim || quad->c.size() != dim)
      throw InputError("hsi::cuda: the quadratic term does not match the space");
    if (S.Q.size() != sz(dim) * sz(dim)) {
      S.Q = DeviceArray<double>(sz(dim) * sz(dim));
      S.c = DeviceArray<double>(sz(dim));
    }
    HSI_CUDA_CHECK(cudaMemcpyAsync(S.Q.get(), quad->Q.data(), S.Q.bytes(), cudaMemcpyHostToDevice, st));
    HSI_CUDA_CHECK(cudaMemcpyAsync(S.c.get(), quad->c.data(), S.c.bytes(), cudaMemcpyHostToDevice, st));
  }
  auto quad_value = [&](const Eigen::VectorXd& x) { return quad ? quad->value(x) : 0.0; };

  NewtonResult res;
  res.x = x0;
  // ab = D · (Tc x) for the device's current x.
  auto set_coefficients = [&](const double* x) {
    HSI_CUDA_CHECK(cublasDgemv(blas_, CUBLAS_OP_N, 4 * n_, dim, &one, S.Tc.get(), 4 * n_, x, 1, &zero,
                               reinterpret_cast<double*>(coef_.get()), 1));
    HSI_CUDA_CHECK(cublasZgemm(blas_, CUBLAS_OP_N, CUBLAS_OP_N, G_, 2, n_, &kOne, D_.get(), G_, coef_.get(), n_, &kZero,
                               ab_.get(), G_));
  };
  // Full coefficients of x (device) into S.full, then the certificate.
  CertificateOptions fast;
  fast.stop_at_first_failure = true;
  CertificateResult last_pass;
  bool last_pass_is_x = false;  // last_pass certifies the current res.x
  auto certify_device = [&](const double* x, bool full) {
    const auto t0 = Clock::now();
    HSI_CUDA_CHECK(cudaMemcpyAsync(S.full.get(), S.X0.get(), S.full.bytes(), cudaMemcpyDeviceToDevice, st));
    HSI_CUDA_CHECK(cublasDgemv(blas_, CUBLAS_OP_N, S.M4, dim, &one, S.X.get(), S.M4, x, 1, &one, S.full.get(), 1));
    certifier_->enqueue(reinterpret_cast<const double2*>(S.full.get()), full ? CertificateOptions{} : fast);
    CertificateResult c = certifier_->fetch();
    res.timing.certificate += ms_since(t0);
    return c;
  };

  auto t0 = Clock::now();
  std::copy(x0.data(), x0.data() + dim, S.x_up.get());
  HSI_CUDA_CHECK(cudaMemcpyAsync(S.x.get(), S.x_up.get(), S.x.bytes(), cudaMemcpyHostToDevice, st));
  set_coefficients(S.x.get());
  HSI_CUDA_CHECK(kernels::mean_energy(G_, g_.get(), ab_.get(), dab_.get(), 0.0, part_sum_.get(), part_bad_.get(),
                                      S.sc.get() + kEnergy0, st));
  HSI_CUDA_CHECK(cudaMemcpyAsync(S.sc_down.get() + kEnergy0, S.sc.get() + kEnergy0, sizeof(double), cudaMemcpyDeviceToHost, st));
  HSI_CUDA_CHECK(cudaStreamSynchronize(st));
  double E = S.sc_down[kEnergy0] + quad_value(res.x);
  res.timing.energy_gradient += ms_since(t0);
  auto finish = [&]() {
    res.energy = E;
    res.ms = ms_since(t_start);
    *out = std::move(res);
    return true;
  };
  if (!std::isfinite(E)) {
    res.message = "the starting map folds or degenerates at a sample (infinite energy)";
    return finish();
  }
  if (certify) {
    res.certificate = opt.start_certificate && opt.start_certificate->certified ? *opt.start_certificate
                                                                                : certify_device(S.x.get(), true);
    if (!res.certificate.certified) {
      res.message = "the starting map is not certified: " + res.certificate.reason;
      return finish();
    }
    last_pass = res.certificate;
    last_pass_is_x = true;
  }

  Event ev[5] = {Event(true), Event(true), Event(true), Event(true), Event(true)};
  for (int it = 0; it < opt.max_iterations; ++it) {
    const auto t_it = Clock::now();
    NewtonIteration log;
    t0 = Clock::now();
    HSI_CUDA_CHECK(cudaEventRecord(ev[0], st));
    // Gradient: [gφ | gψ] = Dᴴ [ga | gb], then g = Tcᵀ (·) / |G| (+ Q x + c).
    HSI_CUDA_CHECK(kernels::gradient_samples(G_, g_.get(), ab_.get(), gab_.get(), st));
    HSI_CUDA_CHECK(cublasZgemm(blas_, CUBLAS_OP_C, CUBLAS_OP_N, n_, 2, G_, &kOne, D_.get(), G_, gab_.get(), G_, &kZero,
                               coef_.get(), n_));
    const double inv_count = 1 / count;
    HSI_CUDA_CHECK(cublasDgemv(blas_, CUBLAS_OP_T, 4 * n_, dim, &inv_count, S.Tc.get(), 4 * n_,
                               reinterpret_cast<const double*>(coef_.get()), 1, &zero, S.g.get(), 1));
    if (quad) {
      HSI_CUDA_CHECK(cublasDgemv(blas_, CUBLAS_OP_N, dim, dim, &one, S.Q.get(), dim, S.x.get(), 1, &one, S.g.get(), 1));
      HSI_CUDA_CHECK(cublasDaxpy(blas_, dim, &one, S.c.get(), 1, S.g.get(), 1));
    }
    HSI_CUDA_CHECK(cudaEventRecord(ev[1], st));
    // Hessian: Hv (4n × 4n) as in hessian(), then Hr = Tᵀ Hv T (+ Q).
    HSI_CUDA_CHECK(kernels::weighted_rows(G_, h_, n_, H_.get(), g_.get(), ab_.get(), to_device(opt.projection), false,
                                          DH_.get(), W_.get(), Wt_.get(), st));
    HSI_CUDA_CHECK(cublasZgemm(blas_, CUBLAS_OP_C, CUBLAS_OP_N, n_, 6 * n_, h_, &kOne, DH_.get(), h_, Wt_.get(), h_, &kZero,
                               R_.get(), n_));
    HSI_CUDA_CHECK(kernels::real_hessian(n_, R_.get(), static_cast<double>(h_), Hv_.get(), st));
    HSI_CUDA_CHECK(cublasDgemm(blas_, CUBLAS_OP_N, CUBLAS_OP_N, 4 * n_, dim, 4 * n_, &one, Hv_.get(), 4 * n_, S.T.get(), 4 * n_,
                               &zero, S.Y.get(), 4 * n_));
    HSI_CUDA_CHECK(cublasDgemm(blas_, CUBLAS_OP_T, CUBLAS_OP_N, dim, dim, 4 * n_, &one, S.T.get(), 4 * n_, S.Y.get(), 4 * n_,
                               &zero, S.Hr0.get(), dim));
    if (quad)
      HSI_CUDA_CHECK(cublasDgeam(blas_, CUBLAS_OP_N, CUBLAS_OP_N, dim, dim, &one, S.Hr0.get(), dim, &one, S.Q.get(), dim,
                                 S.Hr0.get(), dim));
    HSI_CUDA_CHECK(kernels::diag_abs_max(dim, S.Hr0.get(), S.sc.get() + kDiagMax, st));
    HSI_CUDA_CHECK(cudaEventRecord(ev[2], st));
    // Cholesky of the reduced system; a ridge only when it fails (as on the host).
    double ridge = 0, scale = 0;
    bool solved = false;
    float ms_grad = 0, ms_hess = 0, ms_solve = 0, ms_dir = 0;
    for (int attempt = 0; attempt < 12 && !solved; ++attempt) {
      if (attempt > 0) HSI_CUDA_CHECK(cudaEventRecord(ev[2], st));
      HSI_CUDA_CHECK(kernels::add_ridge(dim, S.Hr0.get(), ridge, S.Hr.get(), st));
      HSI_CUDA_CHECK(cusolverDnDpotrf(solver_, CUBLAS_FILL_MODE_LOWER, dim, S.Hr.get(), dim, S.work.get(), S.lwork, S.info.get()));
      // d = −g, solved in place; potrs after a failed potrf gives garbage that info flags.
      HSI_CUDA_CHECK(cudaMemcpyAsync(S.d.get(), S.g.get(), S.d.bytes(), cudaMemcpyDeviceToDevice, st));
      HSI_CUDA_CHECK(cublasDscal(blas_, dim, &minus_one, S.d.get(), 1));
      HSI_CUDA_CHECK(cusolverDnDpotrs(solver_, CUBLAS_FILL_MODE_LOWER, dim, 1, S.Hr.get(), dim, S.d.get(), dim, S.info.get() + 0));
      HSI_CUDA_CHECK(kernels::dot(dim, S.g.get(), S.d.get(), S.sc.get() + kSlope, st));
      HSI_CUDA_CHECK(kernels::dot(dim, S.g.get(), S.g.get(), S.sc.get() + kGradNorm2, st));
      HSI_CUDA_CHECK(cudaEventRecord(ev[3], st));
      // Direction in the samples and the largest safe step along it.
      HSI_CUDA_CHECK(cublasDgemv(blas_, CUBLAS_OP_N, 4 * n_, dim, &one, S.Tc.get(), 4 * n_, S.d.get(), 1, &zero,
                                 reinterpret_cast<double*>(coef_.get()), 1));
      HSI_CUDA_CHECK(cublasZgemm(blas_, CUBLAS_OP_N, CUBLAS_OP_N, G_, 2, n_, &kOne, D_.get(), G_, coef_.get(), n_, &kZero,
                                 dab_.get(), G_));
      HSI_CUDA_CHECK(kernels::max_safe_step(G_, ab_.get(), dab_.get(), part_sum_.get(), S.sc.get() + kSafeStep, st));
      HSI_CUDA_CHECK(cudaEventRecord(ev[4], st));
      HSI_CUDA_CHECK(cudaMemcpyAsync(S.sc_down.get(), S.sc.get(), kSlots * sizeof(double), cudaMemcpyDeviceToHost, st));
      HSI_CUDA_CHECK(cudaMemcpyAsync(S.info_down.get(), S.info.get(), sizeof(int), cudaMemcpyDeviceToHost, st));
      HSI_CUDA_CHECK(cudaMemcpyAsync(S.d_down.get(), S.d.get(), S.d.bytes(), cudaMemcpyDeviceToHost, st));
      HSI_CUDA_CHECK(cudaStreamSynchronize(st));
      if (attempt == 0) {
        HSI_CUDA_CHECK(cudaEventElapsedTime(&ms_grad, ev[0], ev[1]));
        HSI_CUDA_CHECK(cudaEventElapsedTime(&ms_hess, ev[1], ev[2]));
      }
      float a = 0, b = 0;
      HSI_CUDA_CHECK(cudaEventElapsedTime(&a, ev[2], ev[3]));
      HSI_CUDA_CHECK(cudaEventElapsedTime(&b, ev[3], ev[4]));
      ms_solve += a;
      ms_dir += b;
      solved = S.info_down[0] == 0 && std::isfinite(S.sc_down[kSlope]);
      if (!solved) {
        scale = std::max(S.sc_down[kDiagMax], 1e-300);
        ridge = ridge == 0 ? 1e-12 * scale : ridge * 10;
      }
    }
    res.timing.energy_gradient += ms_grad;
    res.timing.hessian += ms_hess;
    res.timing.solve += ms_solve;
    res.timing.line_search += ms_dir;
    if (!solved) {
      res.message = "the Newton system could not be factored";
      break;
    }
    log.gradient_norm = std::sqrt(S.sc_down[kGradNorm2]);
    const double slope = S.sc_down[kSlope];
    if (!(slope < -1e-14 * std::max(1.0, std::abs(E)))) {
      res.converged = true;
      res.message = "no descent direction left (gradient at round-off level)";
      break;
    }
    const Eigen::Map<const Eigen::VectorXd> d(S.d_down.get(), dim);
    log.max_safe_step = S.sc_down[kSafeStep];
    double s = std::min(1.0, opt.safe_fraction * log.max_safe_step);
    double E_new = E;
    bool accepted = false;
    // Trial steps s, s·shrink, …: their energies a batch at a time, then the first
    // that passes Armijo is certified (on failure the backtracking goes on).
    int bt = 0;
    int batch_begin = 0, batch_size = 0;
    t0 = Clock::now();
    for (; bt <= opt.max_backtracks; ++bt, s *= opt.shrink) {
      if (bt >= batch_begin + batch_size) {
        batch_begin = bt;
        batch_size = std::min(kBatch, opt.max_backtracks + 1 - bt);
        double sj = s;
        for (int j = 0; j < batch_size; ++j, sj *= opt.shrink) {
          HSI_CUDA_CHECK(kernels::mean_energy(G_, g_.get(), ab_.get(), dab_.get(), sj, part_sum_.get(), part_bad_.get(),
                                              S.sc.get() + kTrials + j, st));
        }
        HSI_CUDA_CHECK(cudaMemcpyAsync(S.sc_down.get() + kTrials, S.sc.get() + kTrials, sz(batch_size) * sizeof(double),
                                       cudaMemcpyDeviceToHost, st));
        HSI_CUDA_CHECK(cudaStreamSynchronize(st));
      }
      const int j = bt - batch_begin;
      const Eigen::VectorXd x_new = res.x + s * d;
      E_new = S.sc_down[kTrials + j] + quad_value(x_new);
      if (!(E_new <= E + opt.armijo * s * slope)) {
        log.backtracks++;
        continue;
      }
      // x_new on the device: xn = x + s d.
      HSI_CUDA_CHECK(cudaMemcpyAsync(S.xn.get(), S.x.get(), S.x.bytes(), cudaMemcpyDeviceToDevice, st));
      HSI_CUDA_CHECK(cublasDaxpy(blas_, dim, &s, S.d.get(), 1, S.xn.get(), 1));
      res.timing.line_search += ms_since(t0);
      bool ok = true;
      if (certify) {
        CertificateResult c = certify_device(S.xn.get(), false);
        ok = c.certified;
        if (ok) last_pass = std::move(c);
      }
      t0 = Clock::now();
      if (!ok) {
        log.backtracks++;
        log.certificate_rejections++;
        continue;
      }
      accepted = true;
      break;
    }
    res.timing.line_search += ms_since(t0);
    if (!accepted) {
      res.converged = std::abs(slope) < 1e-12 * std::max(1.0, std::abs(E));
      res.message = res.converged ? "converged (no further decrease at round-off level)" : "line search found no certified decrease";
      break;
    }
    res.x += s * d;
    std::swap(S.x, S.xn);
    last_pass_is_x = certify;
    t0 = Clock::now();
    set_coefficients(S.x.get());
    res.timing.energy_gradient += ms_since(t0);
    const double dE = E - E_new;
    E = E_new;
    log.energy = E;
    log.step = s;
    log.ms = ms_since(t_it);
    res.log.push_back(log);
    res.iterations++;
    if (dE < opt.tolerance) {
      res.converged = true;
      res.message = "converged (energy decrease below tolerance)";
      break;
    }
  }
  if (res.message.empty()) res.message = "stopped at the iteration limit";
  if (certify) {
    if (last_pass_is_x) {
      res.certificate = last_pass;
    } else {
      res.certificate = certify_device(S.x.get(), true);
    }
    res.certified = res.certificate.certified;
  }
  // The certificate is of the device's x (its own x + s d sums): hand back that one.
  if (res.iterations > 0) {
    HSI_CUDA_CHECK(cudaMemcpyAsync(S.x_up.get(), S.x.get(), S.x.bytes(), cudaMemcpyDeviceToHost, st));
    HSI_CUDA_CHECK(cudaStreamSynchronize(st));
    std::copy(S.x_up.get(), S.x_up.get() + dim, res.x.data());
  }
  return finish();
}

}  // namespace hsi::cuda
