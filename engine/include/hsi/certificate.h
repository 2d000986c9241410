// The local injectivity certificate (paper Theorem 2 and §4.3.3; CW17 §8; math.md
// §6). A harmonic map on Ω is locally injective iff f_z has no zero in Ω (the
// argument principle on ∂Ω) and |f_z| > |f_zbar| on all of ∂Ω. Condition (b) is
// proved between samples with a Lipschitz bound on every boundary segment and
// adaptive subdivision; nothing is certified that the bound does not prove. The bound
// is evaluated in double precision with every rounding on the conservative side (error
// bounds on the values at the breakpoints and midpoints, distances rounded down,
// Lipschitz constants and a few operations' rounding rounded up), so a map whose margin
// |f_z| − |f_zbar| is at the level of its own round-off (~1e-13 relative) is not
// certified: it may fold, and no floating-point evaluation can tell.
//
// This is the CPU reference that every other backend is checked against.
#pragma once

#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "hsi/harmonic_map.h"
#include "hsi/samples.h"

namespace hsi {

struct CertificateOptions {
  int max_depth = 14;              // subdivision levels per segment before giving up
  long max_pieces_per_segment = 4096;  // work budget per segment; exhausting it means "not certified"
  bool stop_at_first_failure = false;  // for line searches: the verdict is all that matters
};

struct CertificateResult {
  bool certified = false;
  std::string reason;   // empty when certified; otherwise what failed and where
  // Where (b) could not be proved: loop, polygon edge, point; -1 if not applicable.
  int fail_loop = -1, fail_edge = -1;
  cd fail_point{0, 0};
  int winding = 0;      // zeros of f_z inside Ω by the argument principle
  // Certified bounds over ∂Ω (so over Ω by Theorem 2), valid when certified:
  double min_margin = 0;      // min over ∂Ω of (lower |f_z| − upper |f_zbar|) = lower bound of σ2
  double sigma1_max = 0;      // upper bound of the large singular value |f_z| + |f_zbar|
  double sigma2_min = 0;      // lower bound of the small singular value |f_z| − |f_zbar|
  double k_max = 0;           // upper bound of the dilatation |f_zbar| / |f_z| (< 1)
  double conformal_max = 0;   // upper bound of σ1/σ2 = (1 + k)/(1 − k)
  // Observed at the breakpoints (samples and polygon vertices), for reports:
  double observed_sigma1_max = 0, observed_sigma2_min = 0, observed_k_max = 0;
  double observed_isometric_max = 0;  // max of ½(σ1² + σ1⁻² + σ2² + σ2⁻²)
  long segments = 0, subdivisions = 0;
};

// --- The certificate's parts, shared by every backend (the CPU Certifier below and
// the Vulkan backend's dense certify), so that both work on
// the same segments and reduce to the same verdict.

// The boundary broken at polygon vertices and samples (a sample equal to its edge's
// first vertex is dropped), loop by loop. Segment i joins points[i] to points[next[i]]
// (the next breakpoint of the same loop) and lies on polygon edge edge[i] of loop loop[i].
struct CertificateSegments {
  std::vector<cd> points;
  std::vector<int> next, loop, edge;
  size_t size() const { return points.size(); }
};
CertificateSegments certificate_segments(const Shape& shape, const BoundarySamples& samples);

// |S_j| per cage vertex (full column index), from summation by parts over each cage
// loop: S_j = δ_{j+1} − δ_j, δ_j = (c_j − c_{j−1}) / (z_j − z_{j−1}) (math.md §6).
// With `rounding`: also an upper bound on the floating-point error of each |S_j|.
Eigen::VectorXd certificate_jumps(const Cage& cage, const VectorXcd& coefficients, Eigen::VectorXd* rounding = nullptr);

// The rounding allowances' building blocks, shared by the CPU and CUDA certifiers.
constexpr double kCertificateRoundoff = std::numeric_limits<double>::epsilon() / 2;  // u = 2^-53
// segment_distance rounded down by a bound on its rounding error: never above the true
// distance from z to [p, q].
double distance_lower(cd z, cd p, cd q);
// Per shape, per segment i (breakpoint i to its successor) and column j:
//   W (S × m) = 1/dist(z_j, σ_i)², Wh (S × N) = 1/dist(ρ_h, σ_i)³ from distance_lower,
//     0 where that bound is not positive, and touches[i] = 1 then (the segment's
//     Lipschitz constants are infinite: it cannot be certified);
//   WD, WE (S × (m + N)): rounding weights of the basis rows D and E at breakpoint i.
//     A computed entry is within 16 u of its weight of the exact one, and the weight
//     bounds the entry's magnitude, so a computed value Σ_j D_ij c_j is within
//     (2 (m + N) + 72) u Σ_j WD_ij |c_j| of the exact one (the same for E). WD:
//     ((1 + |log(B_j/B_{j−1})|)/|A_j| + (1 + |log(B_{j+1}/B_j)|)/|A_{j+1}|) / 2π,
//     WE: (|B_{j+1}| + |B_{j−1}|) / |B_{j−1} B_j B_{j+1}| / 2π (B_j = z_j − w, A_j =
//     z_j − z_{j−1}); hole columns 1/|w − ρ| and 1/|w − ρ|².
struct CertificateWeights {
  Eigen::MatrixXd W, Wh, WD, WE;
  std::vector<char> touches;
};
CertificateWeights certificate_weights(const Cage& cage, const CertificateSegments& segments);

// What the Lipschitz test with adaptive subdivision found on one segment: its pieces
// in depth-first order, up to the first one that failed.
struct SegmentCertificate {
  bool ok = true;   // (b) and the arg condition proved on every piece (also: never tried, stopped early)
  double arg = 0;   // change of arg f_z along the proved pieces
  double margin = std::numeric_limits<double>::infinity();  // min over pieces of (lower |f_z| − upper |f_zbar|)
  double sigma1 = 0, sigma2 = std::numeric_limits<double>::infinity(), k = 0;  // certified bounds over the pieces
  long pieces = 0;
  cd fail_point{0, 0};  // midpoint of the failing piece
};

// The verdict from every segment's outcome and |f_z|, |f_zbar| at each breakpoint
// (= the start of each segment): the first failing segment in breakpoint order names
// the failure; otherwise the argument principle on the summed arg increments.
CertificateResult reduce_certificate(const CertificateSegments& segments, std::span<const SegmentCertificate> outcomes,
                                     std::span<const double> abs_fz, std::span<const double> abs_fzbar_conj);
// The last step of every backend's reduction: from a result whose verdict (b), failing
// place and bounds are filled in, and the total change of arg f_z over ∂Ω, the reason
// text, the winding number (argument principle) and the conformal bound.
CertificateResult finish_certificate(CertificateResult partial, double arg_total);

// The certificate as every backend gives it: the CPU reference (make_cpu_certifier
// below, over Certifier), the CUDA backend's and the Vulkan backend's dense certify.
// The runtime layer makes one by name (hsi/runtime/certifiers.h). Each gives the CPU's
// verdict, failing place and bounds (up to the round-off its header states); none is
// thread-safe.
class MapCertifier {
 public:
  virtual ~MapCertifier() = default;
  virtual const char* name() const = 0;  // "cpu", "cuda", "vulkan"
  virtual CertificateResult certify(const HarmonicMap& map, const CertificateOptions& options = {}) = 0;
};

// Precomputed per shape and cage: the boundary broken at polygon vertices and
// samples, the basis rows there, and the distance weights of the Lipschitz bound.
class Certifier {
 public:
  Certifier(const Shape& shape, const Cage& cage, const BoundarySamples& samples);
  ~Certifier();
  Certifier(Certifier&&) noexcept;
  Certifier& operator=(Certifier&&) noexcept;

  CertificateResult certify(const HarmonicMap& map, const CertificateOptions& options = {}) const;
  int breakpoint_count() const;
  const CertificateSegments& segments() const;
  // What certify reads besides the map, for another backend's certificate made from
  // this one rather than evaluated again (the CUDA core's: 0.3-0.8 s on one thread per
  // core made): the basis rows at the breakpoints (breakpoint_count() × (m + N), every
  // column) and the Lipschitz bound's distance weights.
  const MatrixXcd& breakpoint_D() const;
  const MatrixXcd& breakpoint_E() const;
  const CertificateWeights& weights() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The CPU reference behind the MapCertifier interface: a Certifier of its own.
std::unique_ptr<MapCertifier> make_cpu_certifier(const Shape& shape, const Cage& cage, const BoundarySamples& samples);

}  // namespace hsi
