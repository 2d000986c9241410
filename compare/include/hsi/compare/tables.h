// hsi compare, stage 4: the paper's Tables 1–4 as data (from the runs), then as JSON for
// report.json and as markdown sections for report.md (heading, what was measured, table).
#pragma once

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hsi/compare/runs.h"

namespace hsi::compare {

// Table 4: time per frame at the render mesh against ARAP, FFMP and GE (means over the
// sequence; GE and ours warm-started from the previous frame), with the iterations of GE
// and ours, and both solved cold (the side-by-side interval's middle frame from its first
// keyframe: ours in Table 1, GE here), which is what separates warm from cold iterations.
struct Table4 {
  int mesh_vertices = 0;
  double arap_ms = 0, ffmp_ms = 0, ge_ms = 0, ge_iterations = 0, ccw16_ms = 0;
  int ge_not_converged = 0, ge_frames = 0;
  double ge_cold_iterations = 0, ge_cold_ms = 0, ours_cold_iterations = 0;
  bool ge_cold_converged = true;
  bool boundary_metric = false;  // the boundary-metric variant ran (simply connected); else n/a
  double ccw16_bm_ms = 0;
  int ccw16_bm_mesh_vertices = 0;
  bool ccw16_bm_own_mesh = false;  // on a coarser mesh than the render mesh
  double ours_solve_ms = 0, ours_iterations = 0, ours_eval_cpu_ms = 0;  // f from cached rows on the CPU
  double ours_eval_cuda_ms = std::numeric_limits<double>::quiet_NaN();  // on the GPU; NaN: not our backend
  std::string ours_timing{};  // how ours was timed (OurTiming::describe); empty: means over the sequence
  // f at the vertices on the backend our solve ran on: CUDA where timed, else the CPU.
  double ours_eval_ms() const { return std::isnan(ours_eval_cuda_ms) ? ours_eval_cpu_ms : ours_eval_cuda_ms; }
  double ours_total_ms() const { return ours_solve_ms + ours_eval_ms(); }
  double arap_over_ours_solve() const { return arap_ms / ours_solve_ms; }
  double arap_over_ours_total() const { return arap_ms / ours_total_ms(); }
  double ge_over_ours_solve() const { return ge_ms / ours_solve_ms; }
  double ge_over_ours_total() const { return ge_ms / ours_total_ms(); }
};

// What Table 3's text names: our mean solve time (the solve does not see the mesh), the
// frames timed, and the GPU dense evaluation's device, or why it is not available.
struct Table3Context {
  double ours_solve_ms = 0, ours_iterations = 0;
  size_t timed_frames = 0;
  std::string gpu_device;       // e.g. "llvmpipe (CPU)"
  std::string gpu_unavailable;  // non-empty: no GPU column, this is why
  std::string ours_timing{};    // how ours was timed (OurTiming::describe); empty: means over the sequence
};

nlohmann::json run_json(const OurRun& r);  // one row of Table 1 or 2
nlohmann::json table3_json(const std::vector<Table3Row>& rows, const Table3Context& c);
nlohmann::json table4_json(const Table4& t);

std::string table1_markdown(const std::vector<OurRun>& rows, int table_frames);
std::string table2_markdown(const std::vector<OurRun>& rows, int table_frames);
std::string table3_markdown(const std::vector<Table3Row>& rows, const Table3Context& c);
std::string table4_markdown(const Table4& t, int sequence_frames);

}  // namespace hsi::compare
