// hsi compare, stage 6: the report. Everything the earlier stages measured, as plain values
// (a Comparison), written as report.json (every raw number) and report.md (the figures,
// Fig. 2 or Fig. 8, Tables 1–4, the claims; the README's compare section lists both).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hsi/compare/alignment.h"
#include "hsi/compare/claims.h"
#include "hsi/compare/runs.h"
#include "hsi/compare/tables.h"
#include "hsi/machine.h"

namespace hsi::compare {

struct KeyframeDistortion {
  double time = 0;
  Distortion sampled;    // at the certificate's breakpoints
  Distortion certified;  // the certificate's bounds
};

// CCW16's boundary-metric variant as the report names it.
struct MetricVariantFacts {
  bool applies = false;
  std::string why_not;  // where it does not apply
  int mesh_vertices = 0, mesh_triangles = 0;
  bool own_mesh = false;  // a coarser mesh than the render mesh
  double mb = 0, render_mesh_mb = 0, setup_ms = 0;
};

struct Comparison {
  // What, where, when.
  std::string scene_path, name, date, vulkan_device;
  std::string gpu_clocks;  // after our timed block (runs.h, OurTiming); empty: no GPU
  Machine machine;
  int loops = 1, holes = 0;
  double size = 1;  // the shape's bounding-box diagonal: distances are relative to it
  std::vector<double> times;
  std::vector<KeyframeDistortion> keyframes;
  // Settings.
  int frames = 0, table_frames = 0, samples = 0, hessian_samples = 0, segment = 0, timing_frames = 0;
  int mesh_vertices = 0, mesh_triangles = 0;
  double hessian_ratio = 0, ccw16_memory_mb = 0;
  std::string core;  // our Newton core
  int panel_width = 0, panel_height = 0;
  // Over the sequence.
  PerFrame per_frame;
  SequenceSummary ours;
  int ours_within_bound = 0;
  double arap_setup_ms = 0, ffmp_setup_ms = 0, ge_setup_ms = 0, ccw_setup_ms = 0, arap_key_error = 0;
  double keyframes_max_turn = 0;  // the largest per-triangle turn between neighbouring keyframes on the mesh, radians
  MetricVariantFacts bm;
  // Side by side, Fig. 8 (where the boundary-metric variant applies).
  std::vector<Snapshot> snaps;
  double range_hi = 1;
  Fig8 fig8_log, fig8_bm;
  // Tables.
  std::vector<OurRun> table1, table2;
  std::vector<Table3Row> table3;
  Table3Context table3_context;
  Table4 table4;
  std::vector<Claim> claims;  // decide_claims(*this)
  double total_s = 0;
};

// What each CCW16 variant blends, as report.json and report.md name it.
inline const std::string kLogBlends =
    "blends log f_z and the second dilatation \xce\xbd = conj(f_zbar)/f_z pointwise in the shape, then integrates them";
inline const std::string kBmBlends =
    "blends the pull-back metric on the boundary only (as ours does) and rebuilds f_z, f_zbar inside by a least-squares "
    "Hilbert transform, then integrates them";

nlohmann::json report_json(const Comparison& c);
std::string report_markdown(const Comparison& c);

}  // namespace hsi::compare
