// The per-sample isometric energy of the paper (Eq. 5, 10, 15–21, Appendix B):
// the symmetric Dirichlet distortion of a map h, with pull-back metric M_h, measured
// against a reference metric M_g at one boundary sample. With g = identity it is the
// plain symmetric Dirichlet energy used to author keyframes (math.md §7).
//
// The variables at a sample are v = (Re a, Im a, Re b, Im b), a = f_z, b = conj(f_zbar).
#pragma once

#include <Eigen/Core>
#include <complex>
#include <string>
#include <vector>

namespace hsi {

using cd = std::complex<double>;

// Symmetric 2×2 metric [[m1, m2], [m2, m3]] stored as (m1, m2, m3).
using Metric = Eigen::Vector3d;

// Paper Eq. 5: the pull-back metric J^T J of the map with f_z = a, conj(f_zbar) = b.
Metric pullback_metric(cd a, cd b);
// The same at every point of a map's values (f_z and conj(f_zbar), as MapValues holds them).
std::vector<Metric> pullback_metrics(const Eigen::VectorXcd& f_z, const Eigen::VectorXcd& fzbar_conj);

// How the per-sample Hessian is made positive semi-definite (paper Table 1).
enum class HessianProjection {
  Delete,    // H = H2 only (drops the α-term)
  FullProj,  // numerical eigen-projection of H1 + H2 per sample
  PartProj   // analytic projection of K1 (paper Eq. 21), H2 as is: the default
};
const char* to_string(HessianProjection p);
HessianProjection parse_projection(const std::string& name);  // "delete" | "fullproj" | "partproj"

struct SampleDerivatives {
  double e = 0;
  Eigen::Vector4d grad = Eigen::Vector4d::Zero();  // ∂e/∂v
  Eigen::Matrix4d hess = Eigen::Matrix4d::Zero();  // (projected) ∂²e/∂v²
};

// Energy (paper Eq. 10) at one sample; +inf where the map folds or degenerates
// (|a| ≤ |b|) or g is not positive definite.
double isometric_energy(const Metric& g, cd a, cd b);

// Energy, gradient and Hessian at one sample. With `exact` the Hessian is the true
// one (2 K1 + 4 K2, for finite-difference tests), otherwise projected as chosen.
SampleDerivatives isometric_derivatives(const Metric& g, cd a, cd b, HessianProjection projection, bool exact = false,
                                        bool with_hessian = true);

// The analytic PSD projection of K1 = Σ α_i F_i (paper Eq. 21; math.md §4 on the third case).
Eigen::Matrix4d project_K1(const Eigen::Vector3d& alpha);

}  // namespace hsi
