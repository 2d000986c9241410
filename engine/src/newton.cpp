// CPU Newton core (the reference for every backend) and the certified Newton loop.
#include "hsi/stopwatch.h"
#include "hsi/newton.h"
#include "hsi/timing.h"
#include "dense_kernels.h"
#include "row_parallel.h"

#include <atomic>
#include <cmath>
#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <optional>
#include <omp.h>

namespace hsi {
namespace {

using Clock = std::chrono::steady_clock;
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

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
    times(phi, psi, a_, b_);
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
    const ColumnPair g = adjoint_times(ga, gb) / static_cast<double>(G);
    Eigen::VectorXd out(4 * n);
    out << g.col(0).real(), g.col(0).imag(), g.col(1).real(), g.col(1).imag();
    return out;
  }

  Eigen::MatrixXd hessian(HessianProjection projection, bool exact, bool all_samples) override {
    // Σ_H B_sᵀ K_s B_s (paper Eq. 13, 20), in real arithmetic. With D_s = x + i y the
    // sample's basis row, (Re a, Im a) = c_s (Re φ, Im φ) for the 2 × 2n block
    // c_s = [[x, −y], [y, x]], and likewise for b and ψ. So the (a, a) block of the
    // Hessian is Σ c_sᵀ K_aa c_s = Cᵀ W_aa with C the c_s stacked and W_aa's rows K_aa c_s;
    // (a, b) and (b, b) the same. Two of the three blocks are symmetric (only their lower
    // triangles are multiplied out), and the products are real GEMMs, which Eigen
    // vectorises, where a complex product with an adjoint falls to a scalar path; with
    // AVX2 and FMA where the processor has them (dense_kernels.h).
    // The subset H's rows, or with all_samples every row of G; each thread sums its own
    // range of samples and the ranges are added.
    const Eigen::Index h = all_samples ? D_.rows() : DH_.rows(), n = D_.cols(), m = 2 * n;
    const int chunks = static_cast<int>(std::clamp<Eigen::Index>(h / 64, 1, omp_get_max_threads()));
    std::vector<Eigen::MatrixXd> parts(static_cast<size_t>(chunks));
#pragma omp parallel for schedule(static)
    for (int c = 0; c < chunks; ++c) {
      const Eigen::Index k0 = h * c / chunks, k1 = h * (c + 1) / chunks, len = k1 - k0;
      // The range's blocks c_s, rows 2k and 2k + 1 of C, from its rows of D (made here:
      // a copy is O(n) a sample against the product's O(n²)).
      RowMatrix C(2 * len, m), W(2 * len, 3 * m);
      const Eigen::OuterStride<> every_other(2 * m);
      Eigen::Map<RowMatrix, 0, Eigen::OuterStride<>> even(C.data(), len, m, every_other), odd(C.data() + m, len, m, every_other);
      auto fill = [&](const auto& rows) {
        even.leftCols(n) = rows.real();
        even.rightCols(n) = -rows.imag();
        odd.leftCols(n) = rows.imag();
        odd.rightCols(n) = rows.real();
      };
      if (all_samples) fill(D_.middleRows(k0, len));
      else fill(DH_.middleRows(k0, len));
      for (Eigen::Index k = k0; k < k1; ++k) {
        const Eigen::Index s = all_samples ? k : H_[static_cast<size_t>(k)];
        const Eigen::Matrix4d K = isometric_derivatives(g_[static_cast<size_t>(s)], a_(s), b_(s), projection, exact).hess;
        const auto cs = C.middleRows(2 * (k - k0), 2);
        auto w = W.middleRows(2 * (k - k0), 2);
        w.leftCols(m).noalias() = K.topLeftCorner<2, 2>() * cs;
        w.middleCols(m, m).noalias() = K.topRightCorner<2, 2>() * cs;
        w.rightCols(m).noalias() = K.bottomRightCorner<2, 2>() * cs;
      }
      Eigen::MatrixXd& P = parts[static_cast<size_t>(c)];
      P.setZero(m, 3 * m);
      detail::hessian_accumulate(C.data(), W.data(), 2 * len, m, P.data());
    }
    Eigen::MatrixXd P(m, 3 * m);  // the ranges' sums added, by columns over the threads
#pragma omp parallel for schedule(static)
    for (Eigen::Index j = 0; j < 3 * m; ++j) {
      P.col(j) = parts[0].col(j);
      for (int c = 1; c < chunks; ++c) P.col(j) += parts[static_cast<size_t>(c)].col(j);
    }
    Eigen::MatrixXd Hv(2 * m, 2 * m);
    Hv.topLeftCorner(m, m) = P.leftCols(m).selfadjointView<Eigen::Lower>();
    Hv.topRightCorner(m, m) = P.middleCols(m, m);
    Hv.bottomLeftCorner(m, m) = P.middleCols(m, m).transpose();
    Hv.bottomRightCorner(m, m) = P.rightCols(m).selfadjointView<Eigen::Lower>();
    return Hv / static_cast<double>(h);
  }

  Eigen::VectorXd hessian_times(HessianProjection projection, bool exact, bool all_samples, const Eigen::VectorXd& p) override {
    const Eigen::Index n = D_.cols();
    if (p.size() != 4 * n)
      throw InputError("hessian_times: a vector of " + std::to_string(p.size()) + " entries, expected " + std::to_string(4 * n));
    // The samples' parts of p, (da, db) = D_rows (p_φ, p_ψ), their 4×4 Hessians applied
    // ((Re, Im) of a, then of b, as hessian() orders them), and Σ conj(D) (w_a, w_b), as
    // gradient() maps its per-sample derivatives back; both products are the thin ones
    // the other calls use (row_parallel.h). (D_H is stored by rows, D by columns.)
    ColumnPair pq(n, 2);
    pq.col(0) = p.segment(0, n).cast<cd>() + cd(0, 1) * p.segment(n, n).cast<cd>();
    pq.col(1) = p.segment(2 * n, n).cast<cd>() + cd(0, 1) * p.segment(3 * n, n).cast<cd>();
    auto apply = [&](const auto& rows) {
      const Eigen::Index h = rows.rows();
      const ColumnPair d = detail::rows_times(rows, pq);
      ColumnPair w(h, 2);
#pragma omp parallel for schedule(static)
      for (Eigen::Index k = 0; k < h; ++k) {
        const Eigen::Index s = all_samples ? k : H_[static_cast<size_t>(k)];
        const Eigen::Matrix4d K = isometric_derivatives(g_[static_cast<size_t>(s)], a_(s), b_(s), projection, exact).hess;
        const Eigen::Vector4d y = K * Eigen::Vector4d(d(k, 0).real(), d(k, 0).imag(), d(k, 1).real(), d(k, 1).imag());
        w(k, 0) = cd(y(0), y(1));
        w(k, 1) = cd(y(2), y(3));
      }
      return ColumnPair(detail::rows_adjoint_times(rows, w) / static_cast<double>(h));
    };
    const ColumnPair r = all_samples ? apply(D_) : apply(DH_);
    Eigen::VectorXd out(4 * n);
    out << r.col(0).real(), r.col(0).imag(), r.col(1).real(), r.col(1).imag();
    return out;
  }

  void set_direction(const Eigen::VectorXd& dv) override {
    const Eigen::Index n = D_.cols();
    times(dv.segment(0, n).cast<cd>() + cd(0, 1) * dv.segment(n, n).cast<cd>(),
          dv.segment(2 * n, n).cast<cd>() + cd(0, 1) * dv.segment(3 * n, n).cast<cd>(), da_, db_);
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
  using ColumnPair = Eigen::Matrix<cd, Eigen::Dynamic, 2>;

  // (D u, D w), one pass over D.
  void times(const VectorXcd& u, const VectorXcd& w, VectorXcd& Du, VectorXcd& Dw) const {
    ColumnPair uw(D_.cols(), 2);
    uw << u, w;
    const ColumnPair out = detail::rows_times(D_, uw);
    Du = out.col(0);
    Dw = out.col(1);
  }

  // Dᴴ [u, w].
  ColumnPair adjoint_times(const VectorXcd& u, const VectorXcd& w) const {
    ColumnPair uw(D_.rows(), 2);
    uw << u, w;
    return detail::rows_adjoint_times(D_, uw);
  }

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

  MatrixXcd D_;
  Eigen::Matrix<cd, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> DH_;  // the subset H's rows of D, in H's order
  std::vector<int> H_;
  std::vector<Metric> g_;
  VectorXcd a_, b_, da_, db_;
};

}  // namespace

std::unique_ptr<NewtonCore> make_cpu_newton_core(MatrixXcd D, std::vector<int> H) {
  return std::make_unique<CpuNewtonCore>(std::move(D), std::move(H));
}

namespace {

// x ⊕ s·d over the core's per-call interface, the reduced algebra with Eigen.
class HostStepper final : public NewtonStepper {
 public:
  HostStepper(NewtonCore& core, const MapSpace& space, const Certifier* certifier, const QuadraticTerm* quad)
      : core_(core), space_(space), certifier_(certifier), quad_(quad), T_(space.T()) {
    if (quad_ && (quad_->Q.rows() != space.dim() || quad_->c.size() != space.dim()))
      throw InputError("the quadratic term does not match the map space");
  }

  double start(const Eigen::VectorXd& x0) override {
    if (x0.size() != space_.dim())
      throw InputError("the start vector has " + std::to_string(x0.size()) + " entries, the space " + std::to_string(space_.dim()));
    x_ = x0;
    core_.set_coefficients(T_ * x_);
    gradient_valid_ = false;
    return core_.energy() + quad_value(x_);
  }

  void linearize(const HessianChoice& choice) override {
    kept_.reset();
    exact_ = choice.exact;
    const Eigen::VectorXd& gv = gradient_at_x();
    const Eigen::MatrixXd Hv = core_.hessian(choice.projection, choice.exact, choice.all_samples);
    Eigen::VectorXd g = T_.transpose() * gv;
    Eigen::MatrixXd H = T_.transpose() * Hv * T_;
    if (quad_) {
      g += quad_->Q * x_ + quad_->c;
      H += quad_->Q;
    }
    rotation_ = choice.free_rotation;
    if (rotation_) {  // one more unknown along the rotation u: [T u]ᵀ Hv [T u], [T u]ᵀ gv
      u_ = space_.rotation_generator(T_ * x_);
      const Eigen::VectorXd w = Hv * u_;
      const Eigen::Index m = H.rows();
      H.conservativeResize(m + 1, m + 1);
      H.col(m).head(m) = T_.transpose() * w;
      H.row(m).head(m) = H.col(m).head(m).transpose();
      H(m, m) = u_.dot(w);
      g.conservativeResize(m + 1);
      g(m) = u_.dot(gv);
    }
    horizontal_ = rotation_ && choice.exact;
    if (horizontal_) {
      // The exact Hessian on the quotient by the rotation (HessianChoice::free_rotation):
      // steps dv = T d + θ u kept orthogonal to u (θ = −aᵀd/|u|², a = Tᵀu). The energy is
      // rotation invariant, so H u = J g and uᵀHu = gᵀv: away from the solution the
      // gauged slice mixes that orbit curvature into its system, which then stays
      // indefinite for more iterations than this one.
      const Eigen::Index m = H.rows() - 1;
      a_ = T_.transpose() * u_;
      uu_ = u_.squaredNorm();
      const Eigen::VectorXd k = H.col(m).head(m);
      const double c = H(m, m);
      Eigen::MatrixXd M = H.topLeftCorner(m, m);
      M.noalias() -= (a_ * k.transpose() + k * a_.transpose()) / uu_;
      M.noalias() += (c / (uu_ * uu_)) * a_ * a_.transpose();
      gh_ = g.head(m) - (g(m) / uu_) * a_;
      H = (M + M.transpose()) / 2;
    }
    g_ = std::move(g);
    H_ = std::move(H);
  }

  bool linearize_kept(const KeptSystem& slot) override {
    const auto* kept = slot.owner == &space_ ? static_cast<const Kept*>(slot.data.get()) : nullptr;
    const Eigen::Index dim = space_.dim();
    if (!kept || kept->L.rows() != dim || (slot.free_rotation && !slot.modulo_rotation) ||
        (slot.free_rotation && quad_))
      return false;
    const Eigen::VectorXd& gv = gradient_at_x();
    Eigen::VectorXd g = T_.transpose() * gv;
    if (quad_) g += quad_->Q * x_ + quad_->c;
    rotation_ = horizontal_ = slot.free_rotation;
    if (rotation_) {
      // The kept system's own rotation frame (u, a = Tᵀu at the point it was built):
      // its system is the Hessian on steps T d + θ u orthogonal to that u, nearly
      // singular along the d whose T d is nearly u; with this point's u instead, g has
      // a part along that d and the chord step runs far along it (twist scene: |d| 1381
      // against 1.6 for the exact step, the energy up by 141).
      u_ = kept->u;
      g.conservativeResize(dim + 1);
      g(dim) = u_.dot(gv);
      a_ = kept->a;
      uu_ = kept->uu;
      gh_ = g.head(dim) - (g(dim) / uu_) * a_;
    }
    g_ = std::move(g);
    kept_ = std::static_pointer_cast<const Kept>(slot.data);
    exact_ = false;
    return true;
  }

  bool keep(KeptSystem& slot) override {
    if (!factored_exact_ || kept_) return false;
    auto kept = std::make_shared<Kept>();
    kept->L.swap(L_);  // solve() factors anew into L_ each time
    kept->diagonal_max = H_.diagonal().cwiseAbs().maxCoeff();
    if (horizontal_) {
      kept->u = u_;
      kept->a = a_;
      kept->uu = uu_;
    }
    slot.owner = &space_;
    slot.generation = 0;
    slot.order = static_cast<int>(kept->L.rows());
    slot.free_rotation = rotation_;
    slot.modulo_rotation = horizontal_;
    slot.data = std::move(kept);
    factored_exact_ = false;
    return true;
  }

  NewtonSystem solve(double ridge) override {
    const NewtonSystem sys = factor_and_solve(ridge);
    return sys.factored ? direction() : sys;
  }

  // d is made here too (the host's back substitution costs little); direction() sets
  // it in the samples and finds the safe step. The decrement is ‖L⁻¹g‖² from a forward
  // substitution of its own, as on the GPU, so both backends stop on the same number.
  NewtonSystem decrement(double ridge) override {
    NewtonSystem sys = factor_and_solve(ridge);
    if (!sys.factored) return sys;
    if (kept_) return direction();  // (a kept factor's solve is a chord step's: never split)
    const Eigen::Index m = L_.rows();
    const Eigen::VectorXd y =
        Eigen::Map<const Eigen::MatrixXd>(L_.data(), m, m).triangularView<Eigen::Lower>().solve(horizontal_ ? gh_ : g_);
    sys.slope = -y.squaredNorm();
    if (!std::isfinite(sys.slope)) sys.factored = factored_exact_ = false;
    sys.has_direction = false;
    return sys;
  }

  NewtonSystem direction() override {
    NewtonSystem sys = pending_;
    if (!sys.factored) throw std::logic_error("newton: direction() without a factored system");
    sys.slope = g_.dot(d_);
    dv_ = T_ * d_.head(space_.dim());
    if (rotation_) dv_ += d_(space_.dim()) * u_;
    core_.set_direction(dv_);
    sys.max_safe_step = core_.max_safe_step();
    sys.has_direction = true;
    return sys;
  }

  void trial_energies(std::span<const double> steps, std::span<double> energies) override {
    for (size_t j = 0; j < steps.size(); ++j) {
      energies[j] = core_.energy_at(steps[j]);
      if (quad_) energies[j] += quad_value(trial(steps[j]));
    }
  }

  CertificateResult certify(double step, bool full) override {
    if (!certifier_) throw InputError("newton: no certifier to certify with");
    CertificateOptions o;
    o.stop_at_first_failure = !full;
    return certifier_->certify(space_.expand(step == 0 ? x_ : trial(step)), o);
  }

  void accept(double step) override {
    x_ = trial(step);
    core_.set_coefficients(T_ * x_);
    gradient_valid_ = false;
  }

  Eigen::VectorXd x() override { return x_; }

 private:
  // The factor (or the kept one) and d; the system's scalars but the slope and the safe
  // step, kept as pending_ for direction().
  NewtonSystem factor_and_solve(double ridge) {
    NewtonSystem sys;
    factored_exact_ = false;
    pending_ = NewtonSystem{};
    sys.diagonal_max = kept_ ? kept_->diagonal_max : H_.diagonal().cwiseAbs().maxCoeff();
    sys.gradient_norm = horizontal_ ? gh_.norm() : g_.head(space_.dim()).norm();
    const Eigen::VectorXd rhs = horizontal_ ? Eigen::VectorXd(-gh_) : Eigen::VectorXd(-g_);
    Eigen::VectorXd sol(rhs.size());
    if (kept_) {
      detail::cholesky_solve_factored(kept_->L.data(), kept_->L.rows(), rhs.data(), sol.data());
    } else {
      L_.resize(H_.rows(), H_.cols());
      if (!detail::cholesky_factor(H_.data(), H_.rows(), ridge * std::max(sys.diagonal_max, 1e-300), L_.data())) return sys;
      detail::cholesky_solve_factored(L_.data(), L_.rows(), rhs.data(), sol.data());
    }
    if (horizontal_) {
      d_.resize(sol.size() + 1);
      d_ << sol, -a_.dot(sol) / uu_;
    } else {
      d_ = std::move(sol);
    }
    if (!d_.allFinite()) return sys;
    sys.factored = true;
    factored_exact_ = exact_ && !kept_;
    pending_ = sys;
    return sys;
  }

  // A factor kept past its solve (keep, KeptSystem::data).
  struct Kept {
    Eigen::MatrixXd L;
    double diagonal_max = 0;
    Eigen::VectorXd u, a;  // the rotation frame it was built in (horizontal systems)
    double uu = 1;
  };

  const Eigen::VectorXd& gradient_at_x() {
    if (!gradient_valid_) {
      gv_ = core_.gradient();
      gradient_valid_ = true;
    }
    return gv_;
  }
  double quad_value(const Eigen::VectorXd& x) const { return quad_ ? quad_->value(x) : 0.0; }
  Eigen::VectorXd trial(double step) const {
    if (!rotation_) return x_ + step * d_;
    return space_.regauge(T_ * x_ + step * dv_);
  }

  NewtonCore& core_;
  const MapSpace& space_;
  const Certifier* certifier_;
  const QuadraticTerm* quad_;
  const Eigen::SparseMatrix<double>& T_;
  Eigen::VectorXd x_, g_, d_, dv_, u_, gv_, a_, gh_;
  double uu_ = 1;
  bool horizontal_ = false;  // the system is the exact one on the quotient by the rotation (H_ is m × m)
  Eigen::MatrixXd H_, L_;  // the system, and its factor from the last solve()
  std::shared_ptr<const Kept> kept_;  // linearize_kept's: the next solve() solves with it
  bool exact_ = false;           // the last linearize() built the exact Hessian
  bool factored_exact_ = false;  // the last solve() factored it (keep() may take L_)
  NewtonSystem pending_;         // the last factor_and_solve()'s system, for direction()
  bool rotation_ = false;
  bool gradient_valid_ = false;  // gv_ is the core's gradient at x_
};

constexpr int kTrialBatch = 4;  // Armijo trial energies asked for at a time

}  // namespace

std::unique_ptr<NewtonStepper> make_host_stepper(NewtonCore& core, const MapSpace& space, const Certifier* certifier,
                                                 const QuadraticTerm* quad) {
  return std::make_unique<HostStepper>(core, space, certifier, quad);
}

namespace {

// The core's own stepper for these arguments where it has one, else the host stepper.
std::unique_ptr<NewtonStepper> stepper_for(NewtonCore& core, const MapSpace& space, const Certifier* certifier,
                                           const QuadraticTerm* quad) {
  std::unique_ptr<NewtonStepper> st = core.make_stepper(space, certifier, quad);
  return st ? std::move(st) : make_host_stepper(core, space, certifier, quad);
}

// ExactSamples::Auto resolved by the core (the subset H where the core has no preference).
ExactSamples resolved_exact_samples(const NewtonCore& core, ExactSamples s) {
  if (s == ExactSamples::Auto) s = core.preferred_exact_samples();
  return s == ExactSamples::Auto ? ExactSamples::Subset : s;
}

}  // namespace

NewtonResult newton_solve(NewtonCore& core, const MapSpace& space, const Certifier* certifier, const QuadraticTerm* quad,
                          const Eigen::VectorXd& x0, const NewtonOptions& opt) {
  std::unique_ptr<NewtonStepper> stepper = stepper_for(core, space, certifier, quad);
  const bool rotation_invariant = space.gauge() == Gauge::ModuloRigid && !quad;
  NewtonOptions o = opt;
  o.exact_samples = resolved_exact_samples(core, o.exact_samples);
  if (o.carry_all_samples == AllSamplesCarry::Auto)
    o.carry_all_samples = o.exact_samples == ExactSamples::All ? AllSamplesCarry::On : AllSamplesCarry::Off;
  return newton_run(*stepper, o.certify && certifier, rotation_invariant, x0, o);
}

bool newton_seed_kept_system(NewtonCore& core, const MapSpace& space, const Eigen::VectorXd& x, const NewtonOptions& opt,
                             KeptSystem& slot) {
  std::unique_ptr<NewtonStepper> st = stepper_for(core, space, nullptr, nullptr);
  const ExactSamples samples = resolved_exact_samples(core, opt.exact_samples);
  const bool rotation_invariant = space.gauge() == Gauge::ModuloRigid;
  slot = KeptSystem{};
  if (!std::isfinite(st->start(x))) return false;
  const auto attempt = [&](bool all) {
    st->linearize({true, opt.projection, rotation_invariant && opt.exact_modulo_rotation, all});
    return st->decrement(opt.exact_ridge).factored;
  };
  bool factored = attempt(samples == ExactSamples::All);
  if (!factored && samples == ExactSamples::SubsetThenAll) factored = attempt(true);
  return factored && st->keep(slot);
}

NewtonResult newton_run(NewtonStepper& st, bool certify, bool rotation_invariant, const Eigen::VectorXd& x0,
                        const NewtonOptions& opt) {
  const auto t_start = Clock::now();
  NewtonResult res;
  auto finish = [&](double E) {
    res.converged = res.stop == NewtonStop::Converged;
    res.energy = E;
    res.x = st.x();
    res.ms = ms_since(t_start);
    return res;
  };
  auto t0 = Clock::now();
  KeptSystem* const kept = opt.kept_system;  // chord steps (NewtonOptions::kept_system)
  // A solve that begins with a chord step from a start that needs no certificate of its
  // own (a warm frame): the start, the chord's gradient and its solve asked together,
  // so that the device is waited for once (NewtonStepper::start_deferred); a start that
  // folds is still stopped below, the chord's numbers unused.
  std::optional<NewtonSystem> chord_first;
  double E = 0;
  if (kept && !kept->empty() && opt.chord_from_start && (!certify || opt.start_certificate)) {
    st.start_deferred(x0);
    const bool solvable = st.linearize_kept(*kept);
    res.timing.energy_gradient += ms_since(t0);
    t0 = Clock::now();
    chord_first = solvable ? st.solve(0) : NewtonSystem{};
    E = st.start_energy();
    res.timing.solve += ms_since(t0);
  } else {
    E = st.start(x0);
    res.timing.energy_gradient += ms_since(t0);
  }
  if (!std::isfinite(E)) {
    res.stop = NewtonStop::StartFolds;
    res.message = "the starting map folds or degenerates at a sample (infinite energy)";
    return finish(E);
  }
  // NewtonOptions::min_margin for the steps (0 until the start is certified; the start
  // itself is not held to it): a step's certified map must keep at least this share of
  // σ1 as margin, or the start's own share where that is smaller (a start closer to the
  // fold than min_margin may still move, never closer to it).
  double step_margin = 0;
  auto timed_certify = [&](double step, bool full) {
    const auto tc = Clock::now();
    CertificateResult c = st.certify(step, full);
    res.timing.certificate += ms_since(tc);
    if (step != 0 && c.certified && step_margin > 0 && !(c.min_margin >= step_margin * c.sigma1_max)) {
      char why[200];
      std::snprintf(why, sizeof why, "certified, but its margin min(|f_z| - |f_zbar|) = %.3g is below %.3g of sigma1 = %.3g (min_margin)",
                    c.min_margin, step_margin, c.sigma1_max);
      c.certified = false;
      c.reason = why;
    }
    return c;
  };
  // A start the certificate refuses is not yet a failed solve (NewtonOptions::
  // from_uncertified_start): the line search accepts certified steps only, so the first
  // step it takes leaves the solve on a certified map; without one the solve stops as
  // StartNotCertified, whatever else ended it.
  std::string start_refusal;  // why the start is not certified (empty: it is, or no certifier)
  if (certify) {
    res.certificate = opt.start_certificate ? *opt.start_certificate : timed_certify(0, true);
    if (!res.certificate.certified) {
      start_refusal = res.certificate.reason.empty() ? "not certified" : res.certificate.reason;
      if (!opt.from_uncertified_start) {
        res.stop = NewtonStop::StartNotCertified;
        res.message = "the starting map is not certified: " + start_refusal;
        return finish(E);
      }
    }
  }
  if (certify && opt.min_margin > 0)
    step_margin = res.certificate.certified && res.certificate.sigma1_max > 0
                      ? std::min(opt.min_margin, res.certificate.min_margin / res.certificate.sigma1_max)
                      : opt.min_margin;
  // A certificate that passes has looked at every segment, so the line search's verdict
  // on the accepted step is the final map's full certificate: res.certificate follows x.
  double dE_prev = -1;  // the previous step's decrease (none yet)
  int crawling = 0;     // accepted steps in a row at a linear rate ≥ stagnation_rate
  // The subset H's model failed (in this solve, or in an earlier one of the sequence:
  // NewtonOptions::carry_all_samples): Hessians over all of G from now on.
  KeptSystem* const carry = kept && opt.carry_all_samples == AllSamplesCarry::On ? kept : nullptr;
  bool all_samples = carry && carry->all_samples;
  const auto escalate_to_all = [&] {
    all_samples = true;
    if (carry) carry->all_samples = true;
  };
  int cut_iterations = 0;    // iterations whose step Armijo cut (NewtonOptions::escalate_after_cut_iterations)
  HessianProjection projection = opt.projection;  // NewtonOptions::escalate_projection once it failed too

  for (int it = 0; it < opt.max_iterations; ++it) {
    const auto t_it = Clock::now();
    NewtonIteration log;
    log.projection = projection;
    const double scale = std::max(1.0, std::abs(E));
    // 1. The system: the exact Hessian where it is positive definite, else the projection
    //    (with the rotation freed), with a ridge when round-off makes it singular.
    NewtonSystem sys;
    auto build = [&](const HessianChoice& choice) {
      t0 = Clock::now();
      st.linearize(choice);
      res.timing.hessian += ms_since(t0);
    };
    auto factor = [&](double ridge) {
      t0 = Clock::now();
      sys = st.solve(ridge);
      res.timing.solve += ms_since(t0);
    };
    // The stopping tests on a system's slope (−gᵀd, or the decrement alone: NewtonSystem::
    // has_direction), asked where the exact system is factored and again below.
    const double stop_tol = opt.tolerance * std::max(std::abs(E), 1e-300);
    const auto no_descent = [&](const NewtonSystem& s) { return !(s.slope < -opt.descent_slope * scale); };
    const auto decrement_below = [&](const NewtonSystem& s) { return -s.slope / 2 < stop_tol; };
    // A projected (or kept) system's: below its share (NewtonOptions::projected_decrement_stop).
    const auto projected_decrement_below = [&](const NewtonSystem& s) {
      return opt.projected_decrement_stop > 0 &&
             -s.slope / 2 < opt.projected_decrement_stop * opt.tolerance * std::max(std::abs(E), 1e-300);
    };
    // The exact system: its factor and decrement first; d only where the solve goes on.
    auto factor_exact = [&](double ridge) {
      t0 = Clock::now();
      sys = st.decrement(ridge);
      if (sys.factored && !sys.has_direction && !no_descent(sys) && !decrement_below(sys)) sys = st.direction();
      res.timing.solve += ms_since(t0);
    };
    // The exact Hessian is tried once Newton takes full steps (near the solution, where
    // it is definite and converges quadratically; a first iteration seldom gets there),
    // and after a projected step that Armijo cut (the projection's model overshot; with
    // an exact step that Armijo cut the projection comes next): NewtonOptions::exact_after_cut.
    const NewtonIteration* prev = res.log.empty() ? nullptr : &res.log.back();
    // The previous step's model error, for the decrement stops that read it (NewtonOptions::
    // checked_decrement_stop, chord_decrement_stop): after a full step of this solve (step
    // 1, no backtrack) that lowered the energy by r times its model's −gᵀd/2 (r taken as at
    // least 1), a model as stiff leaves 1/(2 − r) times its decrement. The divisor 2 − r,
    // or 0 where no full step tells or r ≥ 2 (no stop).
    const double model_error_divisor = [&] {
      if (!prev || prev->step != 1.0 || prev->backtracks != 0 || !(prev->decrement2 > 0) || !(dE_prev > 0)) return 0.0;
      const double r = std::max(1.0, dE_prev / (prev->decrement2 / 2));
      return r < 2 ? 2 - r : 0.0;
    }();
    // 1a. A chord step, first in the solve: the kept factor (the last exact system of an
    //     earlier solve, NewtonOptions::kept_system) with the gradient at x. Its first
    //     trial step (the line search's first batch, asked now) must pass Armijo, or the
    //     iteration builds its system at x instead, as without a slot.
    std::array<double, kTrialBatch> steps{}, energies{};
    int batch_begin = 0, batch_size = 0;  // the line search's trial batch (its first one asked here for a chord)
    if (kept && !kept->empty() && !prev && opt.chord_from_start) {
      if (chord_first) {
        sys = *chord_first;  // (asked with the start)
      } else {
        t0 = Clock::now();
        const bool solvable = st.linearize_kept(*kept);
        res.timing.energy_gradient += ms_since(t0);
        if (solvable) factor(0);
      }
      // Nothing worth a step at the start: the kept system's decrement below the share of
      // the tolerance a projected system's must be under (NewtonOptions::
      // projected_decrement_stop; a kept factor may be stiffer than the energy here, as a
      // projection). Frames that do not move the metric (a rigid motion between keyframes)
      // end here, as they end on a projected system without one.
      if (sys.factored && projected_decrement_below(sys)) {
        res.stop = NewtonStop::Converged;
        res.message = "converged (chord decrement below its share of the tolerance)";
        break;
      }
      if (sys.factored && sys.slope < -opt.descent_slope * scale) {
        t0 = Clock::now();
        batch_size = std::min(kTrialBatch, opt.max_backtracks + 1);
        double sj = std::min(1.0, opt.safe_fraction * sys.max_safe_step);
        for (int j = 0; j < batch_size; ++j, sj *= opt.shrink) steps[static_cast<size_t>(j)] = sj;
        if (certify) st.certify_ahead(steps[0]);  // the step the line search certifies first
        st.trial_energies(std::span<const double>(steps.data(), static_cast<size_t>(batch_size)),
                          std::span<double>(energies.data(), static_cast<size_t>(batch_size)));
        res.timing.line_search += ms_since(t0);
        if (!(energies[0] <= E + opt.armijo * steps[0] * sys.slope)) {
          sys = NewtonSystem{};  // overshoots: built at x instead
          batch_size = 0;
        }
      } else {
        sys = NewtonSystem{};  // (no descent along it: the system at x decides)
      }
      log.chord = sys.factored;
    }
    // 1b. After a full chord step: the kept system's decrement at x, scaled by that
    //     step's model error (NewtonOptions::chord_decrement_stop), may end the solve
    //     before any system of its own is built.
    if (!log.chord && opt.chord_decrement_stop > 0 && model_error_divisor > 0 && prev->chord && kept && !kept->empty()) {
      t0 = Clock::now();
      const bool solvable = st.linearize_kept(*kept);
      res.timing.energy_gradient += ms_since(t0);
      if (solvable) {
        t0 = Clock::now();
        const NewtonSystem chord = st.decrement(0);
        res.timing.solve += ms_since(t0);
        if (chord.factored && chord.slope < 0 && -chord.slope / 2 / model_error_divisor < opt.chord_decrement_stop * stop_tol) {
          res.stop = NewtonStop::Converged;
          res.message = "converged (chord decrement, scaled by the chord step's model error, below its share of the tolerance)";
          break;
        }
      }
    }
    bool exact_on_all = false;  // the exact system (tried below) summed over all of G
    const bool prev_full = prev && prev->step >= 1.0;
    const bool prev_cut = prev && opt.exact_after_cut && !prev->exact_hessian && prev->backtracks > prev->certificate_rejections;
    if (!log.chord && opt.exact_hessian_when_definite && (prev_full || prev_cut)) {
      // Over H or over all of G (NewtonOptions::exact_samples).
      const bool exact_modulo = rotation_invariant && opt.exact_modulo_rotation;
      exact_on_all = all_samples || opt.exact_samples == ExactSamples::All;
      build({true, projection, exact_modulo, exact_on_all});
      factor_exact(opt.exact_ridge);
      if (!sys.factored && !exact_on_all && opt.exact_samples == ExactSamples::SubsetThenAll) {
        exact_on_all = true;
        build({true, projection, exact_modulo, true});
        factor_exact(opt.exact_ridge);
      }
      log.exact_hessian = sys.factored;
      if (sys.factored && kept) st.keep(*kept);  // the next solve's chord steps start from it
      // Indefinite, and the projections have not converged in shift_after iterations: the
      // exact system shifted past its lowest eigenvalue (NewtonOptions::shift_after).
      if (!sys.factored && opt.shift_after > 0 && it >= opt.shift_after) {
        double shift = 1e-9;  // (relative to max |diag H|, as every ridge)
        for (int attempt = 0; attempt < 9; ++attempt, shift *= 10) {
          factor(shift);
          if (sys.factored) break;
        }
        if (sys.factored) factor(2 * shift);
        log.exact_hessian = log.shifted = sys.factored;
      }
    }
    if (!sys.factored) {  // (a chord system is factored)
      build({false, projection, rotation_invariant && opt.free_rotation && projection != HessianProjection::Delete, all_samples});
      double ridge = 0;
      for (int attempt = 0; attempt < opt.max_ridge_attempts; ++attempt) {
        factor(ridge);
        if (sys.factored) break;
        ridge = ridge == 0 ? 1e-12 : ridge * 10;
      }
    }
    if (!sys.factored) {
      res.stop = NewtonStop::NotFactored;
      res.message = "the Newton system could not be factored";
      break;
    }
    log.gradient_norm = sys.gradient_norm;
    if (no_descent(sys)) {
      res.stop = NewtonStop::Converged;
      res.message = "converged (no descent direction left: gradient at round-off level)";
      break;
    }
    // With the exact Hessian the Newton decrement is the decrease a full step would
    // bring (−gᵀd / 2): below the tolerance there is nothing left to take. (A projected
    // Hessian overestimates curvature, so its decrement can understate what is left.)
    if (log.exact_hessian && !log.shifted && decrement_below(sys)) {
      res.stop = NewtonStop::Converged;
      res.message = "converged (Newton decrement below tolerance)";
      break;
    }
    // (factor_exact made d wherever neither test stops: a system without one is a bug.)
    if (!sys.has_direction) throw std::logic_error("newton: a system without a direction reached the line search");
    log.decrement2 = -sys.slope;
    log.max_safe_step = sys.max_safe_step;
    const double slope = sys.slope;
    if (!log.exact_hessian && !log.chord && projected_decrement_below(sys)) {
      res.stop = NewtonStop::Converged;
      res.message = "converged (projected Newton decrement below its share of the tolerance)";
      break;
    }
    // The same with the stiffness the previous full step showed (NewtonOptions::
    // checked_decrement_stop): its decrease over its model's, r, says the model's
    // decrement understates what the energy offers by 1/(2 − r).
    if (!log.exact_hessian && !log.chord && opt.checked_decrement_stop && model_error_divisor > 0 &&
        -slope / 2 / model_error_divisor < stop_tol) {
      res.stop = NewtonStop::Converged;
      res.message = "converged (projected Newton decrement, scaled by the last step's model error, below tolerance)";
      break;
    }

    // 2. Armijo backtracking from min(1, safe_fraction · s_max); a step is taken only if
    //    the certificate passes at the new map.
    t0 = Clock::now();
    log.all_samples = all_samples || (log.exact_hessian && exact_on_all);
    double s = std::min(1.0, opt.safe_fraction * sys.max_safe_step);
    double E_new = E;
    bool accepted = false;
    std::string last_refusal;  // the certificate's reason for the last step it refused
    for (int bt = 0; bt <= opt.max_backtracks; ++bt, s *= opt.shrink) {
      if (bt >= batch_begin + batch_size) {
        batch_begin = bt;
        batch_size = std::min(kTrialBatch, opt.max_backtracks + 1 - bt);
        double sj = s;
        for (int j = 0; j < batch_size; ++j, sj *= opt.shrink) steps[static_cast<size_t>(j)] = sj;
        if (certify && bt == 0) st.certify_ahead(s);  // the step the line search certifies first
        st.trial_energies(std::span<const double>(steps.data(), static_cast<size_t>(batch_size)),
                          std::span<double>(energies.data(), static_cast<size_t>(batch_size)));
      }
      E_new = energies[static_cast<size_t>(bt - batch_begin)];
      if (!(E_new <= E + opt.armijo * s * slope)) {
        log.backtracks++;
        continue;
      }
      // A full step that beat its model's decrease −gᵀd/2 by expand_ratio: longer steps
      // too (NewtonOptions::expand_ratio), the best one certified first.
      if (bt == 0 && s == 1.0 && opt.expand_ratio > 0 && E - E_new > opt.expand_ratio * (-slope / 2)) {
        std::array<double, kTrialBatch> longer{}, longer_E{};
        size_t m = 0;
        for (double sj = 2; m < longer.size() && static_cast<int>(m) < opt.expand_steps && sj <= opt.safe_fraction * sys.max_safe_step; sj *= 2)
          longer[m++] = sj;
        if (m > 0) {
          st.trial_energies(std::span<const double>(longer.data(), m), std::span<double>(longer_E.data(), m));
          size_t best = m;
          for (size_t j = 0; j < m; ++j)
            if (longer_E[j] < (best < m ? longer_E[best] : E_new) && longer_E[j] <= E + opt.armijo * longer[j] * slope) best = j;
          if (best < m) {
            res.timing.line_search += ms_since(t0);
            CertificateResult c;
            if (certify) c = timed_certify(longer[best], false);
            t0 = Clock::now();
            if (!certify || c.certified) {
              if (certify) res.certificate = std::move(c);
              s = longer[best];
              E_new = longer_E[best];
              accepted = true;
              break;
            }
            // (rejected: the full step is certified next)
          }
        }
      }
      res.timing.line_search += ms_since(t0);
      if (certify) {
        CertificateResult c = timed_certify(s, false);
        t0 = Clock::now();
        if (!c.certified) {
          log.backtracks++;
          log.certificate_rejections++;
          last_refusal = std::move(c.reason);
          continue;
        }
        res.certificate = std::move(c);
      }
      accepted = true;
      break;
    }
    res.timing.line_search += ms_since(t0);
    if (!accepted) {
      if (std::abs(slope) < 1e-12 * scale) {
        res.stop = NewtonStop::Converged;
        res.message = "converged (no further decrease at round-off level)";
      } else if (log.certificate_rejections > 0) {
        res.stop = NewtonStop::CertificateRefused;
        // The energy falls along the step, but every step that lowers it enough folds
        // (or comes within round-off of folding) where the energy has no sample: the
        // solve is pressed against the certificate between samples.
        res.message = "line search found no certified decrease: the certificate refused " +
                      std::to_string(log.certificate_rejections) +
                      " step(s) that lowered the energy enough (the map is close to folding between boundary samples, where "
                      "the energy does not look; more samples let it see there); last refusal: " + last_refusal;
      } else {
        res.stop = NewtonStop::NoDecrease;
        res.message = "line search found no certified decrease";
      }
      break;
    }
    t0 = Clock::now();
    st.accept(s);
    res.timing.energy_gradient += ms_since(t0);
    const double dE = E - E_new;
    E = E_new;
    log.energy = E;
    log.step = s;
    log.ms = ms_since(t_it);
    res.log.push_back(log);
    res.iterations++;
    // The model overshot: the subset's Hessian is wrong (or the step is near a fold,
    // where all of G is the better model too).
    // Over all of G and still cut: the projection is the wrong model (escalate_projection).
    // (A chord step that Armijo cut says the kept system is off, not the subset H: the
    // solve goes on with systems built at x, and the escalation rules count those only.)
    const int cuts = log.chord ? 0 : log.backtracks - log.certificate_rejections;
    if (opt.escalate_after_cuts > 0 && cuts >= opt.escalate_after_cuts) {
      if (all_samples && !log.exact_hessian) projection = opt.escalate_projection;
      escalate_to_all();
    }
    // Cut again and again, if only once each time: the subset's model too.
    cut_iterations += cuts > 0 ? 1 : 0;
    if (opt.escalate_after_cut_iterations > 0 && cut_iterations >= opt.escalate_after_cut_iterations) escalate_to_all();
    // Still running: the projection may be too stiff (NewtonOptions::escalate_after_iterations).
    if (opt.escalate_after_iterations > 0 && res.iterations >= opt.escalate_after_iterations) projection = opt.escalate_projection;

    // 3. Stopping: a small decrease that is not a slow linear crawl (the decrease still
    //    to come at rate ρ is ΔE ρ/(1 − ρ)); a long crawl is stagnation.
    const double rate = dE_prev > 0 ? std::clamp(dE / dE_prev, 0.0, 1.0) : 0.0;
    dE_prev = dE;
    const double to_come = rate < 1 ? dE * rate / (1 - rate) : std::numeric_limits<double>::infinity();
    const double tol = opt.tolerance * std::max(std::abs(E), 1e-300);
    // Only a step the line search took as first offered counts: a cut one's small
    // decrease says nothing about what is left (NewtonOptions::tolerance).
    if (log.backtracks == 0 && dE + to_come < tol) {  // (dE > 0: the step passed Armijo with slope < 0)
      res.stop = NewtonStop::Converged;
      res.message = "converged (energy decrease below tolerance)";
      break;
    }
    crawling = rate >= opt.stagnation_rate && dE < 10 * tol ? crawling + 1 : 0;
    if (crawling >= opt.stagnation_steps) {
      res.stop = NewtonStop::Stagnated;
      char why[200];
      std::snprintf(why, sizeof why, "stagnated: %d steps in a row each lowered the energy at a linear rate >= %.2f (last decrease %.3g)",
                    crawling, opt.stagnation_rate, dE);
      res.message = why;
      break;
    }
  }
  if (res.message.empty()) {
    res.stop = NewtonStop::IterationLimit;
    res.message = "stopped at the iteration limit";
  }
  if (certify) {
    res.certified = res.certificate.certified;
    // Never left an uncertified start: whatever stopped the loop, the map it leaves is
    // the start, and the certificate refuses it.
    if (!res.certified && !start_refusal.empty()) {
      res.stop = NewtonStop::StartNotCertified;
      res.message = "the starting map is not certified (" + start_refusal + ") and no certified step left it: " + res.message;
    }
  }
  return finish(E);
}

const char* to_string(NewtonStop stop) {
  switch (stop) {
    case NewtonStop::Converged: return "converged";
    case NewtonStop::IterationLimit: return "iteration limit";
    case NewtonStop::Stagnated: return "stagnated";
    case NewtonStop::CertificateRefused: return "certificate refused";
    case NewtonStop::NoDecrease: return "no decrease";
    case NewtonStop::NotFactored: return "not factored";
    case NewtonStop::StartFolds: return "start folds";
    case NewtonStop::StartNotCertified: return "start not certified";
  }
  return "?";
}

const char* to_string(ExactSamples e) {
  switch (e) {
    case ExactSamples::Subset: return "subset";
    case ExactSamples::SubsetThenAll: return "subset-then-all";
    case ExactSamples::All: return "all";
    case ExactSamples::Auto: return "auto";
  }
  return "?";
}

namespace {
constexpr std::array kExactSamples{ExactSamples::Subset, ExactSamples::SubsetThenAll, ExactSamples::All, ExactSamples::Auto};
}  // namespace

const std::vector<std::string>& exact_samples_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (ExactSamples e : kExactSamples) v.emplace_back(to_string(e));
    return v;
  }();
  return names;
}

ExactSamples parse_exact_samples(const std::string& name) {
  for (ExactSamples e : kExactSamples)
    if (name == to_string(e)) return e;
  std::string valid;
  for (const std::string& n : exact_samples_names()) valid += (valid.empty() ? "" : ", ") + n;
  throw InputError("unknown exact-Hessian samples '" + name + "' (use " + valid + ")");
}

std::uint64_t NewtonCore::next_target_token() {
  static std::atomic<std::uint64_t> next{1};
  return next.fetch_add(1);
}

std::uint64_t NewtonCore::set_target_keys(std::vector<std::vector<Metric>> keys, std::vector<std::vector<Metric>> log_keys) {
  keys_ = std::move(keys);
  log_keys_ = std::move(log_keys);
  return token_ = next_target_token();
}

bool NewtonCore::blend_targets(std::uint64_t token, std::span<const double> w, bool exponential) {
  if (token == 0 || token != token_) return false;  // 0: no sets given yet
  const auto& keys = exponential ? log_keys_ : keys_;
  if (keys.size() != w.size()) throw InputError("blend_targets: " + std::to_string(w.size()) + " weights for " + std::to_string(keys.size()) + " metric sets");
  // Linear, Ease, Hold: a convex combination, so positive definite; Smooth: exp of a
  // combination of logs, positive definite for any weights (timing.h).
  std::vector<Metric> m(keys.empty() ? 0 : keys.front().size(), Metric::Zero());
  for (size_t j = 0; j < w.size(); ++j)
    if (w[j] != 0)
      for (size_t i = 0; i < m.size(); ++i) m[i] += w[j] * keys[j][i];
  if (exponential)
    for (Metric& mi : m) mi = metric_exp(mi);
  set_targets(m);
  return true;
}

namespace {
// A core lent (borrow_core): every call forwarded.
class BorrowedCore final : public NewtonCore {
 public:
  explicit BorrowedCore(NewtonCore& core) : core_(core) {}
  int n() const override { return core_.n(); }
  const char* name() const override { return core_.name(); }
  void set_targets(const std::vector<Metric>& g) override { core_.set_targets(g); }
  void set_coefficients(const Eigen::VectorXd& v) override { core_.set_coefficients(v); }
  double energy() override { return core_.energy(); }
  Eigen::VectorXd gradient() override { return core_.gradient(); }
  Eigen::MatrixXd hessian(HessianProjection projection, bool exact, bool all_samples) override {
    return core_.hessian(projection, exact, all_samples);
  }
  void set_direction(const Eigen::VectorXd& dv) override { core_.set_direction(dv); }
  double max_safe_step() override { return core_.max_safe_step(); }
  double energy_at(double s) override { return core_.energy_at(s); }
  ExactSamples preferred_exact_samples() const override { return core_.preferred_exact_samples(); }
  std::uint64_t set_target_keys(std::vector<std::vector<Metric>> keys, std::vector<std::vector<Metric>> log_keys) override {
    return core_.set_target_keys(std::move(keys), std::move(log_keys));
  }
  bool blend_targets(std::uint64_t token, std::span<const double> w, bool exponential) override {
    return core_.blend_targets(token, w, exponential);
  }
  std::unique_ptr<NewtonStepper> make_stepper(const MapSpace& space, const Certifier* certifier, const QuadraticTerm* quad) override {
    return core_.make_stepper(space, certifier, quad);
  }
  std::optional<CertificateResult> certify_map(const Certifier& certifier, const HarmonicMap& map) override {
    return core_.certify_map(certifier, map);
  }

 private:
  NewtonCore& core_;
};
}  // namespace

std::unique_ptr<NewtonCore> borrow_core(NewtonCore& core) { return std::make_unique<BorrowedCore>(core); }

}  // namespace hsi
