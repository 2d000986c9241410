// Per-sample isometric energy, gradient and PSD Hessian (paper §4.3, Appendix B).
#include "hsi/energy.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "hsi/domain.h"

namespace hsi {
namespace {

// Appendix B: h_i = vᵀ F_i v.
const Eigen::Matrix4d& F(int i) {
  static const Eigen::Matrix4d F1 = (Eigen::Matrix4d() << 1, 0, 1, 0, 0, 1, 0, -1, 1, 0, 1, 0, 0, -1, 0, 1).finished();
  static const Eigen::Matrix4d F2 = (Eigen::Matrix4d() << 0, 0, 0, -1, 0, 0, -1, 0, 0, -1, 0, 0, -1, 0, 0, 0).finished();
  static const Eigen::Matrix4d F3 = (Eigen::Matrix4d() << 1, 0, -1, 0, 0, 1, 0, 1, -1, 0, 1, 0, 0, 1, 0, 1).finished();
  return i == 0 ? F1 : i == 1 ? F2 : F3;
}

}  // namespace

Metric pullback_metric(cd a, cd b) {
  // Eq. 5 with A = a b, S = |a|² + |b|²: m1 = S + 2 Re A, m2 = −2 Im A, m3 = S − 2 Re A.
  const cd A = a * b;
  const double S = std::norm(a) + std::norm(b);
  return {S + 2 * A.real(), -2 * A.imag(), S - 2 * A.real()};
}

std::vector<Metric> pullback_metrics(const Eigen::VectorXcd& f_z, const Eigen::VectorXcd& fzbar_conj) {
  std::vector<Metric> g(static_cast<size_t>(f_z.size()));
  for (Eigen::Index i = 0; i < f_z.size(); ++i) g[static_cast<size_t>(i)] = pullback_metric(f_z(i), fzbar_conj(i));
  return g;
}

const char* to_string(HessianProjection p) {
  switch (p) {
    case HessianProjection::Delete: return "delete";
    case HessianProjection::FullProj: return "fullproj";
    case HessianProjection::PartProj: return "partproj";
  }
  return "?";
}

HessianProjection parse_projection(const std::string& name) {
  if (name == "delete") return HessianProjection::Delete;
  if (name == "fullproj") return HessianProjection::FullProj;
  if (name == "partproj") return HessianProjection::PartProj;
  throw InputError("unknown Hessian projection '" + name + "' (use delete, fullproj or partproj)");
}

double isometric_energy(const Metric& g, cd a, cd b) {
  const double det_g = g(0) * g(2) - g(1) * g(1);
  const double s = std::norm(a) - std::norm(b);
  if (!(s > 0) || !(det_g > 0)) return std::numeric_limits<double>::infinity();
  const Metric h = pullback_metric(a, b);
  const double det_h = s * s;  // h1 h3 − h2² = (|a|² − |b|²)²
  // Eq. 10.
  return (g(2) * h(0) - 2 * g(1) * h(1) + g(0) * h(2)) / 2 * (1 / det_g + 1 / det_h);
}

Eigen::Matrix4d project_K1(const Eigen::Vector3d& alpha) {
  const double a1 = alpha(0), a2 = alpha(1), a3 = alpha(2);
  const double R = std::hypot(a1 - a3, a2);
  const double l1 = a1 + a3 + R, l3 = a1 + a3 - R;  // Eq. 21, each of multiplicity 2
  Eigen::Matrix4d K1 = a1 * F(0) + a2 * F(1) + a3 * F(2);
  if (l3 >= 0) return K1;
  if (l1 <= 0) return Eigen::Matrix4d::Zero();
  // λ1 times the projector (I + N/R)/2 onto K1's positive eigenspace, N = K1 − (α1 + α3) I.
  const Eigen::Matrix4d N = K1 - (a1 + a3) * Eigen::Matrix4d::Identity();
  return l1 * (Eigen::Matrix4d::Identity() + N / R) / 2;
}

SampleDerivatives isometric_derivatives(const Metric& g, cd a, cd b, HessianProjection projection, bool exact,
                                        bool with_hessian) {
  SampleDerivatives d;
  d.e = isometric_energy(g, a, b);
  if (!std::isfinite(d.e)) return d;
  const Eigen::Vector4d v(a.real(), a.imag(), b.real(), b.imag());
  const Metric h = pullback_metric(a, b);
  const double det_g = g(0) * g(2) - g(1) * g(1);
  const double det_h = h(0) * h(2) - h(1) * h(1);
  // E = T · P with T = (g3 h1 − 2 g2 h2 + g1 h3)/2 and P = 1/det g + 1/det h.
  const double T = (g(2) * h(0) - 2 * g(1) * h(1) + g(0) * h(2)) / 2;
  const double P = 1 / det_g + 1 / det_h;
  const Eigen::Vector3d t(g(2) / 2, -g(1), g(0) / 2);   // ∂T/∂h
  const Eigen::Vector3d q(h(2), -2 * h(1), h(0));       // ∂det h/∂h
  Eigen::Matrix3d dq;                                   // ∂q/∂h
  dq << 0, 0, 1, 0, -2, 0, 1, 0, 0;
  const double ih = 1 / det_h;
  const Eigen::Vector3d alpha = t * P - T * ih * ih * q;  // α_i = ∂E/∂h_i
  if (!with_hessian) {
    d.grad = 2 * (alpha(0) * F(0) + alpha(1) * F(1) + alpha(2) * F(2)) * v;
    return d;
  }
  const Eigen::Matrix3d beta = -(t * q.transpose() + q * t.transpose()) * ih * ih +
                               T * (2 * ih * ih * ih * q * q.transpose() - ih * ih * dq);  // β_ij = ∂²E/∂h_i∂h_j
  // ∇_v h_i = 2 F_i v, so ∇_v E = 2 K1 v (Appendix B).
  const Eigen::Matrix4d K1 = alpha(0) * F(0) + alpha(1) * F(1) + alpha(2) * F(2);
  d.grad = 2 * K1 * v;
  Eigen::Matrix<double, 3, 4> J;  // rows (F_i v)ᵀ
  for (int i = 0; i < 3; ++i) J.row(i) = (F(i) * v).transpose();
  const Eigen::Matrix4d K2 = J.transpose() * beta * J;  // Σ β_ij F_i v vᵀ F_j
  // The Hessian is 2 K1 + 4 K2 (math.md §4 on the typo in Appendix B).
  if (exact) {
    d.hess = 2 * K1 + 4 * K2;
    return d;
  }
  switch (projection) {
    case HessianProjection::Delete: d.hess = 4 * K2; break;
    case HessianProjection::PartProj: d.hess = 2 * project_K1(alpha) + 4 * K2; break;
    case HessianProjection::FullProj: {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(2 * K1 + 4 * K2);
      const Eigen::Vector4d lam = es.eigenvalues().cwiseMax(0.0);
      d.hess = es.eigenvectors() * lam.asDiagonal() * es.eigenvectors().transpose();
      break;
    }
  }
  // H2 = 4 K2 is PSD in exact arithmetic (Theorem 3); symmetrise against round-off.
  d.hess = (d.hess + d.hess.transpose()) / 2;
  return d;
}

}  // namespace hsi
