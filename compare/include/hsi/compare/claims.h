// hsi compare, stage 5: the paper's claims about the mesh baselines and ours (§5, Figs 3–5
// and 10, Tables 3–4), each decided on the scene from the numbers the runs measured: holds
// or does not hold here, the number that decides it and the definition used. The
// thresholds are in one place (ClaimThresholds) and the report prints them.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hsi::compare {

struct Comparison;  // report.h

// The lines the claims are decided by.
struct ClaimThresholds {
  // "ARAP fails": a frame with a flipped triangle, or its largest per-triangle κ above this
  // many times the keyframes' largest per-triangle κ on the same mesh (their envelope).
  double arap_kappa_factor = 2.0;
  // "large rotations": some triangle turns by more than this between neighbouring keyframes.
  double large_turn_deg = 90;
  // "FFMP scales unnaturally": some triangle shrinks below both neighbouring keyframes' area
  // on it by more than this (relative), and by more than ours does (MeshKeyframes::area_shrink:
  // the metric blend never shrinks a triangle below both keyframes; a linear blend of turning
  // frames, FFMP's, does).
  double ffmp_shrink = 0.10;
  // "GE is close to ours": its largest vertex distance to ours after the best rigid
  // alignment, over the sequence, below this fraction of the shape's size.
  double ge_close = 0.02;
  // "with distortion peaks": its largest per-triangle κ exceeds the keyframes' envelope on
  // the mesh by more than this (relative) in some frame.
  double ge_peak = 0.01;
  // "by the paper's margin": GE's time per frame over our solve's at least the paper's
  // smallest ratio, Table 4's Archery, 1804.9 ms / 87.7 ms.
  double paper_margin = 1804.9 / 87.7;
};

struct Claim {
  std::string id;          // arap_fails, ffmp_scales, ge_close_with_peaks, ours_within_bounds, ours_faster_than_ge
  std::string claim;       // the paper's claim
  std::string definition;  // what is measured and the test applied
  bool holds = false;
  std::string verdict;     // "holds", "does not hold", or a qualified verdict ("holds only as sampled")
  std::string evidence;    // the deciding numbers, each named (sampled, certified, per triangle)
  double value = 0;        // the deciding number ...
  double threshold = 0;    // ... and the line it is held against
};

std::vector<Claim> decide_claims(const Comparison& c, const ClaimThresholds& th = {});
nlohmann::json claims_json(const std::vector<Claim>& claims);
std::string claims_markdown(const std::vector<Claim>& claims);

}  // namespace hsi::compare
