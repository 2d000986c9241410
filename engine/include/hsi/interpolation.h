// Harmonic shape interpolation (paper §4–5, Algorithm 1): blend the keyframes'
// pull-back metrics at the boundary samples, project onto the harmonic map space by
// certified Newton on the isometric energy, warm-started frame to frame; place each
// frame by a rigid pose interpolated across the keyframes (math.md §3).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hsi/newton.h"
#include "hsi/shape_setup.h"

namespace hsi {

struct InterpolationOptions {
  double tolerance = 5e-8;    // relative: NewtonOptions::tolerance (the paper's absolute 1e-7 at E = 2)
  int max_iterations = 100;
  HessianProjection projection = HessianProjection::PartProj;
  // NewtonOptions::exact_hessian_when_definite and free_rotation: both off is the
  // paper's plain projected Newton (which crawls on some inputs, issue #20).
  bool exact_hessian_when_definite = true;
  bool free_rotation = true;
};

// Pose of a map: the centroid of the boundary's image (by arc length) and the
// Procrustes angle of the image against the rest boundary.
struct Pose {
  cd centroid{0, 0};
  double angle = 0;
};

// Distortion over the boundary (so over Ω, by Theorem 2).
struct Distortion {
  double sigma1_max = 0;     // largest singular value
  double sigma2_min = 0;     // smallest singular value
  double conformal_max = 0;  // σ1/σ2 (the paper's κ)
  double isometric_max = 0;  // symmetric Dirichlet ½(σ1² + σ1⁻² + σ2² + σ2⁻²)… per point, max
};

struct FrameResult {
  double t = 0;
  HarmonicMap map;           // the frame, posed
  Eigen::VectorXd x;         // its reduced coefficients (ModuloRigid gauge), the next warm start
  bool keyframe = false;     // t is a keyframe time: the keyframe itself
  bool certified = false;
  bool converged = false;
  CertificateResult certificate;
  int iterations = 0;
  double energy = 0;         // mean isometric energy against the blended metric (2 = exact)
  double ms = 0;
  Distortion distortion;     // observed at the certificate's breakpoints
  Distortion bound;          // the two neighbouring keyframes' envelope
  double bound_excess = 0;   // how far the frame leaves that envelope (relative; 0 = bounded)
  std::string message;
  NewtonResult::Timing timing;
  // Whether the image of ∂Ω crosses itself (the frame overlaps itself: locally but not
  // globally injective), sampled at the certificate's breakpoints (overlap.h). Checked
  // for keyframes and solved frames alike; it does not change `certified`.
  OverlapResult overlap;
};

class Interpolator {
 public:
  // keyframes: certified maps at increasing times (at least two).
  Interpolator(const ShapeSetup& setup, std::vector<double> times, std::vector<HarmonicMap> keyframes,
               const InterpolationOptions& options = {}, std::unique_ptr<NewtonCore> core = nullptr);
  ~Interpolator();

  double t_begin() const { return times_.front(); }
  double t_end() const { return times_.back(); }

  // One frame from a warm start (reduced x; empty = the nearest earlier keyframe).
  // warm_certificate: the certificate of warm_start's map when already known (the
  // previous frame's), so the solve does not certify its start again.
  FrameResult frame(double t, const Eigen::VectorXd& warm_start = {}, const CertificateResult* warm_certificate = nullptr);
  // F frames uniform over [t_begin, t_end], each warm-started from the previous one.
  std::vector<FrameResult> sequence(int frames, const std::function<void(const FrameResult&, int, int)>& progress = {});

  // The blended metric at every sample of G (paper §4.1).
  std::vector<Metric> blended_metric(double t) const;
  Pose pose_of(const HarmonicMap& map) const;
  Pose interpolated_pose(double t) const;
  const Distortion& keyframe_distortion(int k) const { return key_distortion_[static_cast<size_t>(k)]; }
  NewtonCore& core() { return *core_; }

 private:
  int segment(double t) const;
  Distortion measure(const CertificateResult& c) const;

  const ShapeSetup& setup_;
  std::vector<double> times_;
  std::vector<HarmonicMap> keys_;
  std::vector<Eigen::VectorXd> key_x_;
  std::vector<std::vector<Metric>> key_metrics_;
  std::vector<Pose> key_poses_;  // angles unwrapped across keyframes
  std::vector<Distortion> key_distortion_;
  InterpolationOptions options_;
  std::unique_ptr<NewtonCore> core_;
  // Poses are linear in the coefficients: centroid = c_mean·φ + conj(c_mean·ψ) and the
  // Procrustes sum Σ f_i conj(w_i − w̄) = c_rot·φ + conj(c_rot_bar·ψ), with these rows
  // (sums over G of the basis rows C), so a pose costs O(m), not O(|G| m).
  Eigen::RowVectorXcd c_mean_, c_rot_, c_rot_bar_;
};

}  // namespace hsi
