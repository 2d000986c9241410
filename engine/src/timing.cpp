// Keyframe timing weights and the log-Euclidean metric maps (timing.h).
#include "hsi/timing.h"

#include <algorithm>
#include <cmath>

#include "hsi/domain.h"

namespace hsi {

const char* to_string(KeyTiming timing) {
  switch (timing) {
    case KeyTiming::Linear: return "linear";
    case KeyTiming::Smooth: return "smooth";
    case KeyTiming::Ease: return "ease";
    case KeyTiming::Hold: return "hold";
  }
  return "?";
}

std::optional<KeyTiming> parse_key_timing(std::string_view name) {
  for (KeyTiming k : {KeyTiming::Linear, KeyTiming::Smooth, KeyTiming::Ease, KeyTiming::Hold})
    if (name == to_string(k)) return k;
  return std::nullopt;
}

namespace {

KeyTiming timing_of(const std::vector<KeyTiming>& timings, size_t k) {
  if (timings.empty()) return KeyTiming::Linear;
  return timings.size() == 1 ? timings.front() : timings[k];
}

// The interval k with t_k ≤ t ≤ t_k+1 (the earlier one at an interior keyframe), and
// its parameter u ∈ [0, 1].
size_t interval_of(const std::vector<double>& times, double t, double& u) {
  if (times.size() < 2) throw InputError("timing: needs at least two keyframe times");
  size_t k = 0;
  while (k + 2 < times.size() && t > times[k + 1]) ++k;
  u = std::clamp((t - times[k]) / (times[k + 1] - times[k]), 0.0, 1.0);
  return k;
}

// The tangent at keyframe k of the Smooth curve, as weights over keyframes (added,
// times `scale`, into w): the three-point derivative (Δ₋ s₊ + Δ₊ s₋)/(Δ₋ + Δ₊) of the
// secants s₋ = (V_k − V_k−1)/Δ₋, s₊ = (V_k+1 − V_k)/Δ₊ when both intervals are Smooth,
// else the smooth side's secant.
void add_tangent(const std::vector<double>& times, const std::vector<KeyTiming>& timings, size_t k, double scale,
                 std::vector<double>& w) {
  const size_t n = times.size();
  const bool left = k > 0 && timing_of(timings, k - 1) == KeyTiming::Smooth;
  const bool right = k + 1 < n && timing_of(timings, k) == KeyTiming::Smooth;
  const auto secant = [&](size_t a, double s) {  // s·(V_a+1 − V_a)/Δ_a
    const double d = times[a + 1] - times[a];
    w[a + 1] += s / d;
    w[a] -= s / d;
  };
  if (left && right) {
    const double dm = times[k] - times[k - 1], dp = times[k + 1] - times[k];
    secant(k, scale * dm / (dm + dp));
    secant(k - 1, scale * dp / (dm + dp));
  } else if (right) {
    secant(k, scale);
  } else if (left) {
    secant(k - 1, scale);
  }
}

}  // namespace

KeyTiming interval_timing(const std::vector<double>& times, const std::vector<KeyTiming>& timings, double t) {
  double u = 0;
  return timing_of(timings, interval_of(times, t, u));
}

std::vector<double> key_weights(const std::vector<double>& times, const std::vector<KeyTiming>& timings, double t) {
  if (!timings.empty() && timings.size() != 1 && timings.size() != times.size())
    throw InputError("timing: " + std::to_string(timings.size()) + " timings for " + std::to_string(times.size()) +
                     " keyframes (give one per keyframe, or one for all)");
  double u = 0;
  const size_t k = interval_of(times, t, u);
  std::vector<double> w(times.size(), 0.0);
  switch (timing_of(timings, k)) {
    case KeyTiming::Linear:
      w[k] = 1 - u;
      w[k + 1] = u;
      break;
    case KeyTiming::Ease: {
      const double s = u * u * (3 - 2 * u);
      w[k] = 1 - s;
      w[k + 1] = s;
      break;
    }
    case KeyTiming::Hold:
      (u < 1 ? w[k] : w[k + 1]) = 1;
      break;
    case KeyTiming::Smooth: {
      // Cubic Hermite: h00 V_k + h10 Δ m_k + h01 V_k+1 + h11 Δ m_k+1.
      const double u2 = u * u, u3 = u2 * u, d = times[k + 1] - times[k];
      w[k] += 2 * u3 - 3 * u2 + 1;
      w[k + 1] += -2 * u3 + 3 * u2;
      add_tangent(times, timings, k, d * (u3 - 2 * u2 + u), w);
      add_tangent(times, timings, k + 1, d * (u3 - u2), w);
      break;
    }
  }
  return w;
}

Metric metric_log(const Metric& m) {
  // M = μI + (M − μI) with eigenvalues μ ± d: log M = α I + β (M − μI), α = ½ ln det M,
  // β = (ln(μ + d) − ln(μ − d)) / 2d = atanh(d/μ)/d.
  const double mu = 0.5 * (m(0) + m(2)), h = 0.5 * (m(0) - m(2));
  const double d = std::hypot(h, m(1));
  const double det = m(0) * m(2) - m(1) * m(1);
  if (!(mu > 0) || !(det > 0) || !std::isfinite(det))
    throw InputError("metric_log: the metric [[" + std::to_string(m(0)) + ", " + std::to_string(m(1)) + "], [" + std::to_string(m(1)) +
                     ", " + std::to_string(m(2)) + "]] is not positive definite");
  const double x = d / mu;
  const double atanh_x_over_x = x < 1e-4 ? 1 + x * x / 3 + x * x * x * x / 5 : std::atanh(x) / x;
  const double alpha = 0.5 * std::log(det), beta = atanh_x_over_x / mu;
  return {alpha + beta * h, beta * m(1), alpha - beta * h};
}

Metric metric_log(cd a, cd b) {
  // pullback_metric(a, b) = S I + [[2 Re A, −2 Im A], [−2 Im A, −2 Re A]] with A = a b,
  // S = |a|² + |b|²; eigenvalues S ± 2|a||b| = (|a| ± |b|)².
  const double ra = std::abs(a), rb = std::abs(b);
  if (!(ra > rb) || !std::isfinite(ra))
    throw InputError("metric_log: the Jacobian (|f_z| = " + std::to_string(ra) + ", |f_zbar| = " + std::to_string(rb) +
                     ") is not orientation preserving");
  // β = atanh(d/S)/d with d = 2|a||b|, and atanh(d/S) = ln((|a| + |b|)/(|a| − |b|))
  // = 2 atanh(y), y = |b|/|a|: so β = atanh(y)/(y |a|²), with no 1 − d/S formed.
  const cd A = a * b;
  const double y = rb / ra;
  const double atanh_y_over_y = y < 1e-4 ? 1 + y * y / 3 + y * y * y * y / 5 : 0.5 * std::log((ra + rb) / (ra - rb)) / y;
  const double alpha = std::log(ra - rb) + std::log(ra + rb), beta = atanh_y_over_y / (ra * ra);
  return {alpha + beta * 2 * A.real(), beta * -2 * A.imag(), alpha - beta * 2 * A.real()};
}

Metric metric_exp(const Metric& s) {
  // exp S = e^ν (cosh δ I + sinh δ/δ (S − νI)), ν the mean of the eigenvalues, ±δ their spread.
  const double nu = 0.5 * (s(0) + s(2)), h = 0.5 * (s(0) - s(2));
  const double delta = std::hypot(h, s(1));
  const double sinhc = delta < 1e-4 ? 1 + delta * delta / 6 : std::sinh(delta) / delta;
  const double e = std::exp(nu), c = std::cosh(delta);
  return {e * (c + sinhc * h), e * sinhc * s(1), e * (c - sinhc * h)};
}

}  // namespace hsi
