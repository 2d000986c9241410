// Certificate soundness campaign (issue #10), shared by tests/test_soundness.cpp (a
// few hundred maps per shape) and bench/soundness_campaign.cpp (≥ 10,000 per shape):
// random maps near the fold boundary, each certified and compared with a dense
// brute-force check. The certificate must never certify a map the dense check finds
// folded; how many injective maps it fails to certify measures its conservativeness.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "hsi/certificate.h"
#include "hsi/map_space.h"
#include "hsi/shape_setup.h"

namespace hsi::soundness {

// Brute force on ∂Ω (Theorem 2: locally injective iff |f_zbar| < |f_z| on ∂Ω and f_z
// has no zero in Ω): |f_z| − |f_zbar| at `count` points uniform by arc length plus
// every polygon vertex, and the winding number of f_z along the dense boundary
// (zeros of f_z inside Ω, by the argument principle).
class DenseCheck {
 public:
  struct Verdict {
    bool injective = false;
    double min_gap = 0;  // min over the points of |f_z| − |f_zbar|
    int winding = 0;
  };

  DenseCheck(const Shape& shape, const Cage& cage, int count) {
    const BoundarySamples s = sample_boundary(shape, count);
    // Merge the samples and the polygon vertices of each loop, in boundary order.
    for (int l = 0; l < shape.loop_count(); ++l) {
      begin_.push_back(static_cast<int>(points_.size()));
      const Loop& loop = shape.loop(l);
      const int a = s.loop_begin[static_cast<size_t>(l)], b = s.loop_begin[static_cast<size_t>(l) + 1];
      int i = a;
      for (int e = 0; e < static_cast<int>(loop.size()); ++e) {
        points_.push_back(loop[static_cast<size_t>(e)]);
        for (; i < b && s.edge[static_cast<size_t>(i)] == e; ++i) points_.push_back(s.points[static_cast<size_t>(i)]);
      }
    }
    begin_.push_back(static_cast<int>(points_.size()));
    D_ = evaluate_basis(cage, points_, kBasisD).D;
  }

  size_t size() const { return points_.size(); }

  Verdict check(const HarmonicMap& m) const {
    const VectorXcd fz = D_ * m.phi, gz = D_ * m.psi;
    Verdict v;
    v.min_gap = std::numeric_limits<double>::infinity();
    double arg = 0;
    for (size_t l = 0; l + 1 < begin_.size(); ++l)
      for (int i = begin_[l]; i < begin_[l + 1]; ++i) {
        const int j = i + 1 < begin_[l + 1] ? i + 1 : begin_[l];
        v.min_gap = std::min(v.min_gap, std::abs(fz(i)) - std::abs(gz(i)));
        arg += std::arg(fz(j) / fz(i));
      }
    if (!std::isfinite(arg)) {
      v.min_gap = -std::numeric_limits<double>::infinity();
      return v;
    }
    v.winding = static_cast<int>(std::lround(arg / (2 * std::numbers::pi)));
    v.injective = v.min_gap > 0 && v.winding == 0;
    return v;
  }

 private:
  std::vector<cd> points_;
  std::vector<int> begin_;
  MatrixXcd D_;
};

struct Tally {
  long maps = 0, certified = 0, dense_injective = 0;
  long certified_but_folded = 0;     // must stay 0
  long injective_not_certified = 0;  // conservativeness
  long bound_violations = 0;         // certified σ2 lower bound above the dense minimum gap (must stay 0)
  double worst_certified_gap = std::numeric_limits<double>::infinity();  // smallest dense gap of a certified map
  void add(const Tally& o) {
    maps += o.maps;
    certified += o.certified;
    dense_injective += o.dense_injective;
    certified_but_folded += o.certified_but_folded;
    injective_not_certified += o.injective_not_certified;
    bound_violations += o.bound_violations;
    worst_certified_gap = std::min(worst_certified_gap, o.worst_certified_gap);
  }
};

struct Options {
  int maps = 300;               // maps per shape
  int per_direction = 4;        // maps drawn around each direction's fold boundary
  double spread = 0.2;          // ... at t* · (1 ± spread)
  int dense = 40000;            // dense check points
  int coarse = 4000;            // points of the check used to locate the fold boundary
  unsigned seed = 1;
};

// Maps near the fold boundary of one shape: from a base map (the identity or one of
// the scene's keyframes), a direction in the reduced coefficient space (Gauge::Map,
// so ψ_log = conj φ_log holds) — random (coefficient perturbation) or the difference
// of two keyframes plus noise (a handle drag carried on) — the fold boundary t* along
// it (bisection with a coarse dense check), then maps at t* · (1 ± spread).
// `on_map` sees every map with its certificate and dense verdict.
template <class OnMap>
Tally run(const ShapeSetup& setup, const std::vector<HarmonicMap>& keyframes, const Options& o, OnMap&& on_map) {
  const MapSpace& space = setup.map_space;
  const DenseCheck dense(setup.shape, setup.cage, o.dense), coarse(setup.shape, setup.cage, o.coarse);
  std::vector<Eigen::VectorXd> bases{space.reduce(identity_map(setup.cage)).x};
  for (const HarmonicMap& k : keyframes) bases.push_back(space.reduce(k).x);
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> gauss(0, 1);
  std::uniform_real_distribution<double> unit(0, 1);
  Tally t;
  const double scale = setup.size;
  long direction = 0;
  while (t.maps < o.maps && direction < 100L * o.maps) {
    ++direction;
    const bool drag = keyframes.size() >= 2 && (direction % 2 == 0);
    Eigen::VectorXd start = bases[static_cast<size_t>(rng() % bases.size())];
    Eigen::VectorXd dir(start.size());
    for (Eigen::Index i = 0; i < dir.size(); ++i) dir(i) = gauss(rng);
    dir /= dir.norm();
    if (drag) {
      // A handle drag carried on: from keyframe a towards (and past) keyframe b, with a little noise.
      const size_t a = rng() % keyframes.size(), b = (a + 1 + rng() % (keyframes.size() - 1)) % keyframes.size();
      const Eigen::VectorXd d = bases[b + 1] - bases[a + 1];
      start = bases[a + 1];
      dir = d / d.norm() + 0.2 * dir;
    }
    dir *= scale / dir.norm();
    auto map_at = [&](double s) { return space.expand(start + s * dir); };
    if (!coarse.check(map_at(0)).injective) continue;  // a start that folds (cannot happen for certified keyframes)
    double lo = 0, hi = 1e-3;
    while (coarse.check(map_at(hi)).injective && hi < 1e3) lo = hi, hi *= 2;
    if (hi >= 1e3) continue;
    for (int it = 0; it < 20 && hi - lo > 1e-4 * hi; ++it) {
      const double mid = 0.5 * (lo + hi);
      (coarse.check(map_at(mid)).injective ? lo : hi) = mid;
    }
    const double star = 0.5 * (lo + hi);
    for (int k = 0; k < o.per_direction && t.maps < o.maps; ++k) {
      const double s = star * (1 + o.spread * (2 * unit(rng) - 1));
      const HarmonicMap m = map_at(s);
      const CertificateResult c = setup.certifier.certify(m);
      const DenseCheck::Verdict d = dense.check(m);
      ++t.maps;
      t.certified += c.certified;
      t.dense_injective += d.injective;
      if (c.certified && !d.injective) ++t.certified_but_folded;
      if (!c.certified && d.injective) ++t.injective_not_certified;
      if (c.certified) {
        t.worst_certified_gap = std::min(t.worst_certified_gap, d.min_gap);
        if (c.sigma2_min > d.min_gap + 1e-12 * (1 + std::abs(d.min_gap))) ++t.bound_violations;
      }
      on_map(m, c, d, s / star);
    }
  }
  return t;
}

}  // namespace hsi::soundness
