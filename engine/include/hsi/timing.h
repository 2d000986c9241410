// Timing through keyframes (issue #26): how the interval leaving each keyframe is
// travelled. Every mode is an affine combination of keyframe values with weights that
// depend only on the keyframe times and modes (key_weights), applied to the samples'
// metrics (in the log-Euclidean space for Smooth, so every blend stays positive
// definite) and to the rigid pose. Keyframes are reproduced exactly in every mode.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hsi/energy.h"

namespace hsi {

enum class KeyTiming {
  Linear,  // the paper's: metrics blended linearly, constant speed (velocity jumps at keyframes)
  Smooth,  // C¹: cubic Hermite through the keyframes in the log-Euclidean space of the metrics,
           //   tangents from the neighbouring keyframes (three-point, exact for quadratics)
  Ease,    // ease in and out: the linear blend travelled with smoothstep 3u² − 2u³ (zero speed at both ends)
  Hold,    // the keyframe held until the next one's time
};

const char* to_string(KeyTiming timing);
// "linear" | "smooth" | "ease" | "hold"; nullopt for anything else.
std::optional<KeyTiming> parse_key_timing(std::string_view name);
inline constexpr const char* kKeyTimingNames = "linear, smooth, ease, hold";

// Weights w_j (Σ w_j = 1) with value(t) = Σ_j w_j V_j for keyframe values V_j at `times`
// (increasing), the interval [t_k, t_k+1] containing t travelled by timings[k] (one
// per keyframe; the last is unused; a timing vector of size 1 applies to every
// interval, an empty one means Linear). t is clamped to [t_0, t_last]. For Smooth the
// tangent at keyframe k is the three-point derivative when both intervals around k are
// Smooth, the secant of the smooth side otherwise: so the velocity is continuous at a
// keyframe exactly when both of its intervals are Smooth (or both Ease, where it is 0).
std::vector<double> key_weights(const std::vector<double>& times, const std::vector<KeyTiming>& timings, double t);
// The timing of the interval containing t (same conventions as key_weights).
KeyTiming interval_timing(const std::vector<double>& times, const std::vector<KeyTiming>& timings, double t);

// Matrix logarithm and exponential of the 2×2 symmetric metric [[m1, m2], [m2, m3]]
// (closed forms through the eigenvalues; log needs a positive definite metric and throws
// InputError otherwise). exp of any symmetric matrix is positive definite.
// A metric's smaller eigenvalue is known only to eps·(its larger one): for a strongly
// anisotropic metric prefer the Jacobian form below.
Metric metric_log(const Metric& m);
Metric metric_exp(const Metric& s);
// log of the pull-back metric of the Jacobian with f_z = a, conj(f_zbar) = b (energy.h's
// pullback_metric(a, b)), from a and b themselves: its eigenvalues (|a| ± |b|)² and
// their spread are formed without the cancellation of det M = m1 m3 − m2², so the log is
// accurate to rounding however anisotropic the map. Needs |a| > |b| (orientation kept).
Metric metric_log(cd a, cd b);

}  // namespace hsi
