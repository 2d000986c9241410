// CPU Newton core (the reference for every backend) and the certified Newton loop.
#include "hsi/newton.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>

namespace hsi {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// A real 2×2 block K acting on u ∈ C ≅ R² as K u = α u + β conj(u).
inline void complex_form(double k11, double k12, double k21, double k22, cd& alpha, cd& beta) {
  alpha = cd((k11 + k22) / 2, (k21 - k12) / 2);
  beta = cd((k11 - k22) / 2, (k21 + k12) / 2);
}

// The real matrix of δ ↦ P δ + Q conj(δ) with complex-packed input and output.
void real_block(const MatrixXcd& P, const MatrixXcd& Q, Eigen::Ref<Eigen::MatrixXd> out) {
  const Eigen::Index n = P.rows();
  out.topLeftCorner(n, n) = P.real() + Q.real();
  out.topRightCorner(n, n) = -P.imag() + Q.imag();
  out.bottomLeftCorner(n, n) = P.imag() + Q.imag();
  out.bottomRightCorner(n, n) = P.real() - Q.real();
}

class CpuNewtonCore final : public NewtonCore {
 public:
  CpuNewtonCore(MatrixXcd D, std::vector<int> H) : D_(std::move(D)), H_(std::move(H)) {
    DH_.resize(static_cast<Eigen::Index>(H_.size()), D_.cols());
    for (size_t k = 0; k < H_.size(); ++k) DH_.row(static_cast<Eigen::Index>(k)) = D_.row(H_[k]);
    g_.assign(static_cast<size_t>(D_.rows()), Metric(1, 0, 1));
  }
  int n() const override { return static_cast<int>(D_.cols()); }
  const char* name() const override { return "cpu"; }

  void set_targets(const std::vector<Metric>& g) override {
    if (static_cast<Eigen::Index>(g.size()) != D_.rows()) throw InputError("target metrics do not match the samples");
    g_ = g;
  }
  void set_coefficients(const Eigen::VectorXd& v) override {
    const Eigen::Index n = D_.cols();
    const VectorXcd phi = v.segment(0, n).cast<cd>() + cd(0, 1) * v.segment(n, n).cast<cd>();
    const VectorXcd psi = v.segment(2 * n, n).cast<cd>() + cd(0, 1) * v.segment(3 * n, n).cast<cd>();
    a_ = D_ * phi;
    b_ = D_ * psi;
  }
  double energy() override { return mean_energy(0.0); }
  double energy_at(double s) override { return mean_energy(s); }

  Eigen::VectorXd gradient() override {
    const Eigen::Index G = D_.rows(), n = D_.cols();
    VectorXcd ga(G), gb(G);
#pragma omp parallel for schedule(static)
    for (Eigen::Index s = 0; s < G; ++s) {
      const SampleDerivatives d = isometric_derivatives(g_[static_cast<size_t>(s)], a_(s), b_(s), HessianProjection::Delete,
                                                        false, /*with_hessian=*/false);
      ga(s) = cd(d.grad(0), d.grad(1));
      gb(s) = cd(d.grad(2), d.grad(3));
    }
    // (∂/∂Re φ + i ∂/∂Im φ) E = Σ conj(D) (∂E/∂Re a + i ∂E/∂Im a).
    const VectorXcd gphi = D_.adjoint() * ga / static_cast<double>(G);
    const VectorXcd gpsi = D_.adjoint() * gb / static_cast<double>(G);
    Eigen::VectorXd out(4 * n);
    out << gphi.real(), gphi.imag(), gpsi.real(), gpsi.imag();
    return out;
  }

  Eigen::MatrixXd hessian(HessianProjection projection, bool exact) override {
    // Σ_H B_sᵀ K_s B_s with B_s = diag(𝐃_s, 𝐃_s) (paper Eq. 13, 20): written in complex
    // form, every block is Dᴴ diag(w) D or Dᴴ diag(w) conj(D), so the whole Hessian is
    // one complex GEMM Dᴴ [α_aa∘D, β_aa∘D̄, α_ab∘D, β_ab∘D̄, α_bb∘D, β_bb∘D̄].
    const Eigen::Index h = DH_.rows(), n = D_.cols();
    MatrixXcd Wt(h, 6 * n);
#pragma omp parallel for schedule(static)
    for (Eigen::Index k = 0; k < h; ++k) {
      const Eigen::Index s = H_[static_cast<size_t>(k)];
      const SampleDerivatives d = isometric_derivatives(g_[static_cast<size_t>(s)], a_(s), b_(s), projection, exact);
      const Eigen::Matrix4d& K = d.hess;
      cd w[6];
      complex_form(K(0, 0), K(0, 1), K(1, 0), K(1, 1), w[0], w[1]);
      complex_form(K(0, 2), K(0, 3), K(1, 2), K(1, 3), w[2], w[3]);
      complex_form(K(2, 2), K(2, 3), K(3, 2), K(3, 3), w[4], w[5]);
      for (int q = 0; q < 6; ++q) {
        if (q % 2 == 0)
          Wt.row(k).segment(q * n, n) = w[q] * DH_.row(k);
        else
          Wt.row(k).segment(q * n, n) = w[q] * DH_.row(k).conjugate();
      }
    }
    // The GEMM, split by column blocks over the threads (Eigen does not parallelise
    // a product this thin on its own).
    MatrixXcd R(n, 6 * n);
#pragma omp parallel for schedule(static)
    for (int q = 0; q < 6; ++q) R.middleCols(q * n, n).noalias() = DH_.adjoint() * Wt.middleCols(q * n, n);
    R /= static_cast<double>(h);
    Eigen::MatrixXd Hv(4 * n, 4 * n);
    real_block(R.middleCols(0, n), R.middleCols(n, n), Hv.block(0, 0, 2 * n, 2 * n));
    real_block(R.middleCols(2 * n, n), R.middleCols(3 * n, n), Hv.block(0, 2 * n, 2 * n, 2 * n));
    real_block(R.middleCols(4 * n, n), R.middleCols(5 * n, n), Hv.block(2 * n, 2 * n, 2 * n, 2 * n));
    Hv.block(2 * n, 0, 2 * n, 2 * n) = Hv.block(0, 2 * n, 2 * n, 2 * n).transpose();
    return (Hv + Hv.transpose()) / 2;
  }

  void set_direction(const Eigen::VectorXd& dv) override {
    const Eigen::Index n = D_.cols();
    da_ = D_ * (dv.segment(0, n).cast<cd>() + cd(0, 1) * dv.segment(n, n).cast<cd>());
    db_ = D_ * (dv.segment(2 * n, n).cast<cd>() + cd(0, 1) * dv.segment(3 * n, n).cast<cd>());
  }

  double max_safe_step() override {
    double smax = std::numeric_limits<double>::infinity();
    const Eigen::Index G = D_.rows();
#pragma omp parallel for reduction(min : smax) schedule(static)
    for (Eigen::Index s = 0; s < G; ++s) {
      // |a + t da|² − |b + t db|² = A t² + B t + C; first positive root.
      const double A = std::norm(da_(s)) - std::norm(db_(s));
      const double B = 2 * ((a_(s) * std::conj(da_(s))).real() - (b_(s) * std::conj(db_(s))).real());
      const double C = std::norm(a_(s)) - std::norm(b_(s));
      double t = std::numeric_limits<double>::infinity();
      if (std::abs(A) < 1e-300) {
        if (B < 0) t = -C / B;
      } else {
        const double disc = B * B - 4 * A * C;
        if (disc >= 0) {
          const double sq = std::sqrt(disc);
          const double q = -0.5 * (B + std::copysign(sq, B));
          for (double r : {q / A, q != 0 ? C / q : std::numeric_limits<double>::infinity()})
            if (r > 0) t = std::min(t, r);
        }
      }
      smax = std::min(smax, t);
    }
    return smax;
  }

 private:
  double mean_energy(double s) const {
    const Eigen::Index G = D_.rows();
    double sum = 0;
    bool bad = false;
#pragma omp parallel for reduction(+ : sum) reduction(|| : bad) schedule(static)
    for (Eigen::Index i = 0; i < G; ++i) {
      const cd a = s == 0 ? a_(i) : a_(i) + s * da_(i);
      const cd b = s == 0 ? b_(i) : b_(i) + s * db_(i);
      const double e = isometric_energy(g_[static_cast<size_t>(i)], a, b);
      if (!std::isfinite(e)) bad = true;
      else sum += e;
    }
    return bad ? std::numeric_limits<double>::infinity() : sum / static_cast<double>(G);
  }

  MatrixXcd D_, DH_;
  std::vector<int> H_;
  std::vector<Metric> g_;
  VectorXcd a_, b_, da_, db_;
};

}  // namespace

std::unique_ptr<NewtonCore> make_cpu_newton_core(MatrixXcd D, std::vector<int> H) {
  return std::make_unique<CpuNewtonCore>(std::move(D), std::move(H));
}

NewtonResult newton_solve(NewtonCore& core, const MapSpace& space, const Certifier* certifier, const QuadraticTerm* quad,
                          const Eigen::VectorXd& x0, const NewtonOptions& opt) {
  if (opt.device_loop) {
    NewtonResult on_device;
    if (core.solve(space, certifier, quad, x0, opt, &on_device)) return on_device;
  }
  const auto t_start = Clock::now();
  const Eigen::SparseMatrix<double>& T = space.T();
  NewtonResult res;
  res.x = x0;
  auto total = [&](const Eigen::VectorXd& x, double sample_energy) {
    return sample_energy + (quad ? quad->value(x) : 0.0);
  };
  CertificateOptions fast;
  fast.stop_at_first_failure = true;
  // A certificate that passes has looked at every segment, so the line search's
  // verdict on the accepted step is also the final report: keep it.
  CertificateResult last_pass;
  Eigen::VectorXd last_pass_x;
  auto certified = [&](const Eigen::VectorXd& x, CertificateResult* full) {
    if (!opt.certify || !certifier) return true;
    if (full && last_pass_x.size() == x.size() && last_pass_x == x) {
      *full = last_pass;
      return true;
    }
    const auto t0 = Clock::now();
    CertificateResult c = certifier->certify(space.expand(x), full ? CertificateOptions{} : fast);
    res.timing.certificate += ms_since(t0);
    if (c.certified) {
      last_pass = c;
      last_pass_x = x;
    }
    if (full) *full = c;
    return c.certified;
  };

  auto t0 = Clock::now();
  core.set_coefficients(T * res.x);
  double E = total(res.x, core.energy());
  res.timing.energy_gradient += ms_since(t0);
  if (!std::isfinite(E)) {
    res.message = "the starting map folds or degenerates at a sample (infinite energy)";
    res.energy = E;
    return res;
  }
  if (opt.certify && certifier && opt.start_certificate && opt.start_certificate->certified) {
    res.certificate = last_pass = *opt.start_certificate;
    last_pass_x = res.x;
  } else if (opt.certify && certifier && !certified(res.x, &res.certificate)) {
    res.message = "the starting map is not certified: " + res.certificate.reason;
    res.energy = E;
    return res;
  }

  for (int it = 0; it < opt.max_iterations; ++it) {
    const auto t_it = Clock::now();
    NewtonIteration log;
    t0 = Clock::now();
    Eigen::VectorXd g = T.transpose() * core.gradient();
    if (quad) g += quad->Q * res.x + quad->c;
    res.timing.energy_gradient += ms_since(t0);

    t0 = Clock::now();
    Eigen::MatrixXd Hr = T.transpose() * core.hessian(opt.projection) * T;
    if (quad) Hr += quad->Q;
    res.timing.hessian += ms_since(t0);

    t0 = Clock::now();
    // Cholesky of the reduced SPD system; a tiny ridge if round-off (or a free
    // direction such as the rotation with a single handle) makes it singular.
    Eigen::VectorXd d;
    double ridge = 0;
    const double scale = std::max(Hr.diagonal().cwiseAbs().maxCoeff(), 1e-300);
    for (int attempt = 0; attempt < 12; ++attempt) {
      Eigen::LLT<Eigen::MatrixXd> llt(Hr + ridge * Eigen::MatrixXd::Identity(Hr.rows(), Hr.cols()));
      if (llt.info() == Eigen::Success) {
        d = llt.solve(-g);
        if (d.allFinite()) break;
      }
      ridge = ridge == 0 ? 1e-12 * scale : ridge * 10;
      d.resize(0);
    }
    res.timing.solve += ms_since(t0);
    if (d.size() == 0) {
      res.message = "the Newton system could not be factored";
      break;
    }
    log.gradient_norm = g.norm();
    const double slope = g.dot(d);
    if (!(slope < -1e-14 * std::max(1.0, std::abs(E)))) {
      res.converged = true;
      res.message = "no descent direction left (gradient at round-off level)";
      break;
    }

    t0 = Clock::now();
    core.set_direction(T * d);
    log.max_safe_step = core.max_safe_step();
    double s = std::min(1.0, opt.safe_fraction * log.max_safe_step);
    double E_new = E;
    bool accepted = false;
    for (int bt = 0; bt <= opt.max_backtracks; ++bt, s *= opt.shrink) {
      const Eigen::VectorXd x_new = res.x + s * d;
      E_new = total(x_new, core.energy_at(s));
      if (!(E_new <= E + opt.armijo * s * slope)) {
        log.backtracks++;
        continue;
      }
      res.timing.line_search += ms_since(t0);
      const bool ok = certified(x_new, nullptr);
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
    t0 = Clock::now();
    core.set_coefficients(T * res.x);
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
  res.energy = E;
  if (opt.certify && certifier) res.certified = certified(res.x, &res.certificate);
  res.ms = ms_since(t_start);
  return res;
}

}  // namespace hsi
