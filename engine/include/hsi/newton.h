// Certified Newton iteration over the reduced coefficients (paper Algorithm 1,
// math.md §5) for energies "mean over samples G of the isometric energy of
// (f_z, conj f_zbar) against a target metric per sample", plus an optional
// quadratic term (positional constraints when authoring keyframes).
//
// The hot loops live behind NewtonCore: energy and gradient over G, the PSD
// Hessian over H, and the line-search evaluations. The CPU core here is the
// readable reference; cuda/ provides a twin with the same interface.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hsi/certificate.h"
#include "hsi/energy.h"
#include "hsi/map_space.h"

namespace hsi {

struct QuadraticTerm;
struct NewtonOptions;
struct NewtonResult;

// Per-iteration sample work. Coefficients are the active real vector
// v = (Re φ_a, Im φ_a, Re ψ_a, Im ψ_a) ∈ R^{4n} of MapSpace.
class NewtonCore {
 public:
  virtual ~NewtonCore() = default;
  virtual int n() const = 0;
  virtual const char* name() const = 0;
  // Reference metric at every sample of G (identity for plain symmetric Dirichlet).
  virtual void set_targets(const std::vector<Metric>& g) = 0;
  virtual void set_coefficients(const Eigen::VectorXd& v) = 0;
  virtual double energy() = 0;                     // mean over G; +inf if a sample folds
  virtual Eigen::VectorXd gradient() = 0;          // ∂E/∂v, mean over G
  // PSD Hessian (mean over H), or with exact = true the unprojected one (tests).
  virtual Eigen::MatrixXd hessian(HessianProjection projection, bool exact = false) = 0;
  virtual void set_direction(const Eigen::VectorXd& dv) = 0;
  virtual double max_safe_step() = 0;              // first s > 0 with |a + s da| = |b + s db| at a sample
  virtual double energy_at(double s) = 0;          // energy at v + s dv

  // A core that can run newton_solve's whole iteration on its own device (the CUDA
  // core made from a ShapeSetup: factorisation, line search and certificate on the
  // GPU) overrides this, fills *out with what newton_solve would return and says
  // true. The default declines and newton_solve drives the core from the host.
  virtual bool solve(const MapSpace& /*space*/, const Certifier* /*certifier*/, const QuadraticTerm* /*quad*/,
                     const Eigen::VectorXd& /*x0*/, const NewtonOptions& /*options*/, NewtonResult* /*out*/) {
    return false;
  }
};

// D: the active basis rows D(w) at the samples G (|G| × n); H: indices into G.
std::unique_ptr<NewtonCore> make_cpu_newton_core(MatrixXcd D, std::vector<int> H);

// ½ xᵀ Q x + cᵀ x + k over the reduced variables.
struct QuadraticTerm {
  Eigen::MatrixXd Q;
  Eigen::VectorXd c;
  double k = 0;
  double value(const Eigen::VectorXd& x) const { return 0.5 * x.dot(Q * x) + c.dot(x) + k; }
};

struct NewtonOptions {
  int max_iterations = 100;
  double tolerance = 1e-7;        // stop when E_k − E_{k+1} < tolerance (paper: 1e-7)
  HessianProjection projection = HessianProjection::PartProj;
  double armijo = 0.2;            // sufficient-decrease factor
  double shrink = 0.5;            // backtracking factor
  double safe_fraction = 0.8;     // first trial step: min(1, 0.8 s_max)
  int max_backtracks = 60;
  bool certify = true;            // accept a step only if the certificate passes
  bool device_loop = true;        // let a core run the whole iteration on its device (NewtonCore::solve)
  // The certificate of x0's map when the caller has it already (a warm start from the
  // previous frame's solution): not computed again. Must be of space.expand(x0) exactly.
  const CertificateResult* start_certificate = nullptr;
};

struct NewtonIteration {
  double energy = 0, gradient_norm = 0, step = 0, max_safe_step = 0;
  int backtracks = 0, certificate_rejections = 0;
  double ms = 0;
};

struct NewtonResult {
  Eigen::VectorXd x;
  double energy = 0;
  int iterations = 0;
  bool converged = false;
  bool certified = false;         // the final map passed the certificate
  CertificateResult certificate;  // of the final map (when certify)
  std::vector<NewtonIteration> log;
  std::string message;            // why it stopped
  double ms = 0;
  struct Timing { double energy_gradient = 0, hessian = 0, solve = 0, line_search = 0, certificate = 0; } timing;
};

// Minimises mean_G E_iso + quad(x) from x0, which must be a certified map.
NewtonResult newton_solve(NewtonCore& core, const MapSpace& space, const Certifier* certifier, const QuadraticTerm* quad,
                          const Eigen::VectorXd& x0, const NewtonOptions& options);

}  // namespace hsi
