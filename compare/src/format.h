// hsi compare's number formatting and reductions, shared by its stages (private).
#pragma once

#include "hsi/stopwatch.h"
#include <algorithm>
#include <chrono>
#include <cstdarg>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hsi/compare/compare.h"

namespace hsi::compare {

using Clock = std::chrono::steady_clock;
inline double s_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// For report.md: NaN as "n/a", ±inf as "∞" / "−∞".
inline std::string fixed(double v, int digits) {
  if (std::isnan(v)) return "n/a";
  if (std::isinf(v)) return v > 0 ? "∞" : "−∞";
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}
inline std::string sci(double v) {
  if (std::isnan(v)) return "n/a";
  if (std::isinf(v)) return v > 0 ? "∞" : "−∞";
  char b[64];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}
// JSON has no infinity: +inf (a folded frame) is written as the string "inf", NaN as "nan".
inline nlohmann::json num(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(std::isnan(v) ? "nan" : v > 0 ? "inf" : "-inf");
}
inline nlohmann::json nums(const std::vector<double>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (double x : v) a.push_back(num(x));
  return a;
}
// The largest value but NaN (−inf for none); the mean of the finite values (NaN for none).
inline double max_of(const std::vector<double>& v) {
  double m = -std::numeric_limits<double>::infinity();
  for (double x : v)
    if (!std::isnan(x)) m = std::max(m, x);
  return m;
}
inline double mean_of(const std::vector<double>& v) {
  double s = 0;
  int n = 0;
  for (double x : v)
    if (std::isfinite(x)) s += x, ++n;
  return n ? s / n : std::numeric_limits<double>::quiet_NaN();
}

// Frames whose value is > 0 (e.g. with flipped triangles), and GE's frames that did not converge.
inline int count_positive(const std::vector<double>& v) {
  return static_cast<int>(std::count_if(v.begin(), v.end(), [](double x) { return x > 0; }));
}
inline int count_not_converged(const std::vector<double>& converged) {
  return static_cast<int>(converged.size()) - count_positive(converged);
}

// A progress line, printf-formatted (nothing without a progress callback).
__attribute__((format(printf, 3, 4))) inline void say(const Progress& progress, bool transient, const char* f, ...) {
  if (!progress) return;
  char b[1024];
  va_list ap;
  va_start(ap, f);
  std::vsnprintf(b, sizeof b, f, ap);
  va_end(ap);
  progress(b, transient);
}

}  // namespace hsi::compare
