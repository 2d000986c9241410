// Tables 1–4 as JSON and markdown (hsi/compare/tables.h).
#include "hsi/compare/tables.h"

#include "format.h"

namespace hsi::compare {

using nlohmann::json;

namespace {
// Markdown lines, each ended by a newline.
struct Lines {
  std::string md;
  void operator()(const std::string& s = "") { md += s + "\n"; }
};
}  // namespace

json run_json(const OurRun& r) {
  json j = {{"label", r.label},
            {"newton_core", r.core},
            {"hessian_ratio", r.ratio},
            {"hessian_samples", r.hessian_samples},
            {"cold_iterations", r.cold.iterations},
            {"cold_ms", r.cold.ms},
            {"cold_certified", r.cold.certified},
            {"max_iterations", r.max_iterations}};
  // The sequence's summary with the fields and names of hsi interpolate's report (scene_sequence.h).
  for (const SummaryField& f : summary_fields(r.summary))
    j[f.name] = f.integer ? json(static_cast<long long>(f.value)) : json(f.value);
  return j;
}

json table3_json(const std::vector<Table3Row>& rows, const Table3Context& c) {
  const double ours_solve_ms = c.ours_solve_ms;
  json a = json::array();
  for (const Table3Row& r : rows)
    a.push_back({{"vertices", r.vertices},
                 {"triangles", r.triangles},
                 {"mesh_s", r.mesh_s},
                 {"arap_factorisation_ms", r.arap_factor_ms},
                 {"arap_ms", r.arap_ms},
                 {"ours_solve_ms", ours_solve_ms},
                 {"ours_eval_cpu_ms", r.ours_eval_cpu_ms},
                 {"ours_eval_cpu_setup_ms", r.ours_eval_setup_ms},
                 {"ours_eval_cuda_ms", num(r.ours_eval_cuda_ms)},
                 {"ours_eval_vulkan_ms", num(r.ours_eval_gpu_ms)},
                 {"ours_total_cpu_ms", ours_solve_ms + r.ours_eval_cpu_ms},
                 {"ours_total_ms", ours_solve_ms + r.ours_eval_ms()},
                 {"arap_over_ours_total", r.arap_ms / (ours_solve_ms + r.ours_eval_ms())},
                 {"ours_iterations", c.ours_iterations},
                 {"ge_run", r.ge_not_run.empty()},
                 {"ge_ms", r.ge_not_run.empty() ? num(r.ge_ms) : json(nullptr)},
                 {"ge_iterations", r.ge_not_run.empty() ? num(r.ge_iterations) : json(nullptr)},
                 {"ge_not_converged", r.ge_not_converged},
                 {"ge_not_run", r.ge_not_run.empty() ? json(nullptr) : json(r.ge_not_run)},
                 {"ge_over_ours_solve", r.ge_not_run.empty() ? num(r.ge_ms / ours_solve_ms) : json(nullptr)}});
  return a;
}

json table4_json(const Table4& t) {
  return {{"mesh_vertices", t.mesh_vertices},
          {"arap_ms", t.arap_ms},
          {"ffmp_ms", num(t.ffmp_ms)},
          {"ge_ms", num(t.ge_ms)},
          {"ge_iterations", num(t.ge_iterations)},
          {"ge_frames", t.ge_frames},
          {"ge_not_converged", t.ge_not_converged},
          {"ge_cold_iterations", t.ge_cold_iterations},
          {"ge_cold_ms", t.ge_cold_ms},
          {"ge_cold_converged", t.ge_cold_converged},
          {"ours_cold_iterations", t.ours_cold_iterations},
          {"ge_over_ours_solve", num(t.ge_over_ours_solve())},
          {"ge_over_ours_total", num(t.ge_over_ours_total())},
          {"ccw16_ms", t.ccw16_ms},
          {"ccw16_boundary_metric_ms", t.boundary_metric ? num(t.ccw16_bm_ms) : json(nullptr)},
          {"ccw16_boundary_metric_mesh_vertices", t.boundary_metric ? json(t.ccw16_bm_mesh_vertices) : json(nullptr)},
          {"ours_solve_ms", t.ours_solve_ms},
          {"ours_iterations", t.ours_iterations},
          {"ours_eval_cpu_ms", t.ours_eval_cpu_ms},
          {"ours_eval_cuda_ms", num(t.ours_eval_cuda_ms)},
          {"ours_total_cpu_ms", t.ours_solve_ms + t.ours_eval_cpu_ms},
          {"ours_total_ms", t.ours_total_ms()},
          {"ours_timing", t.ours_timing},
          {"arap_over_ours_solve", t.arap_over_ours_solve()},
          {"arap_over_ours_total", t.arap_over_ours_total()}};
}

std::string table1_markdown(const std::vector<OurRun>& rows, int table_frames) {
  Lines line;
  line("## Table 1: Hessian PSD projection");
  line();
  line("Delete: H = H\xe2\x82\x82 only; FullProj: eigen-decomposition of H\xe2\x82\x81 + H\xe2\x82\x82 per sample; PartProj: the "
       "analytic projection of H\xe2\x82\x81 (ours). \"Cold\": the frame at the middle of the keyframe interval solved from the "
       "interval's first keyframe (the paper's setting); \"sequence\": " + std::to_string(table_frames) +
       " frames, each warm-started from the previous one.");
  line();
  line("| projection | Newton core | cold: #iter | cold: ms | sequence: mean #iter | max #iter | mean ms per frame | certified |");
  line("|---|---|---|---|---|---|---|---|");
  for (const OurRun& r : rows)
    line("| " + r.label + " | " + r.core + " | " + std::to_string(r.cold.iterations) + " | " + fixed(r.cold.ms, 1) + " | " +
         fixed(r.summary.mean_iterations, 2) + " | " + std::to_string(r.max_iterations) + " | " + fixed(r.summary.mean_ms, 1) + " | " +
         std::to_string(r.summary.certified) + "/" + std::to_string(r.summary.frames) + " |");
  line();
  return line.md;
}

std::string table2_markdown(const std::vector<OurRun>& rows, int table_frames) {
  Lines line;
  line("## Table 2: Hessian sample ratio r");
  line();
  line("|H| = r |G|, PartProj, " + std::to_string(table_frames) + " warm-started frames.");
  line();
  line("| r | \\|H\\| | mean #iter | max #iter | mean ms per frame | certified |");
  line("|---|---|---|---|---|---|");
  for (const OurRun& r : rows)
    line("| " + sci(r.ratio) + " | " + std::to_string(r.hessian_samples) + " | " + fixed(r.summary.mean_iterations, 2) + " | " +
         std::to_string(r.max_iterations) + " | " + fixed(r.summary.mean_ms, 1) + " | " + std::to_string(r.summary.certified) + "/" +
         std::to_string(r.summary.frames) + " |");
  line();
  return line.md;
}

std::string table3_markdown(const std::vector<Table3Row>& rows, const Table3Context& c) {
  Lines line;
  line("## Table 3: time per frame against the render mesh's resolution");
  line();
  const std::string gpu = c.gpu_unavailable.empty()
                              ? "; the Vulkan column: the basis evaluated at every vertex per frame with the Vulkan dense evaluation on " +
                                    c.gpu_device
                              : "; the Vulkan column (the basis evaluated at every vertex per frame): the Vulkan dense evaluation is "
                                "not available (" + c.gpu_unavailable + ")";
  line("Ours: the solve works on boundary samples and does not see the mesh (" +
       (c.ours_timing.empty() ? std::string("mean of the sequence") : c.ours_timing) +
       "); drawing a frame at the mesh adds f at its vertices: from basis rows cached once per mesh, then one matrix-vector "
       "product per frame, on the CPU and, where our solve ran on CUDA, on the GPU (the total uses the backend of the solve)" + gpu +
       ". ARAP: one sparse solve per frame after a factorisation made once per mesh. GE: Newton on the mesh (one sparse "
       "Cholesky per iteration), each timed frame warm-started from GE's own frame at the sequence's previous time (that one "
       "solved untimed from our frame there), as the paper's Table 3 (GE and ours: time and iterations per frame). Ours' "
       "iterations: the mean of the block, the same at every resolution. Times are means over " +
       std::to_string(c.timed_frames) + " frames. The cached evaluators' first evaluation is not timed.");
  line();
  line("| vertices | triangles | GE ms per frame | GE #iter | ours solve ms | ours #iter | GE / ours solve | ARAP factorisation ms | ARAP ms per frame | ours f at vertices, CPU ms | ours f at vertices, CUDA ms | ours f at vertices, Vulkan ms | ours total ms | ARAP / ours solve | ARAP / ours total |");
  line("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
  for (const Table3Row& r : rows) {
    const bool ge = r.ge_not_run.empty();
    line("| " + std::to_string(r.vertices) + " | " + std::to_string(r.triangles) + " | " +
         (ge ? fixed(r.ge_ms, 1) + (r.ge_not_converged ? " (" + std::to_string(r.ge_not_converged) + " not converged)" : std::string())
             : r.ge_not_run) +
         " | " + (ge ? fixed(r.ge_iterations, 1) : std::string("n/a")) + " | " + fixed(c.ours_solve_ms, 1) + " | " +
         fixed(c.ours_iterations, 2) + " | " + (ge ? sci(r.ge_ms / c.ours_solve_ms) : std::string("n/a")) + " | " +
         fixed(r.arap_factor_ms, 0) + " | " + fixed(r.arap_ms, 1) + " | " + fixed(r.ours_eval_cpu_ms, 3) + " | " +
         fixed(r.ours_eval_cuda_ms, 3) + " | " + fixed(r.ours_eval_gpu_ms, 1) + " | " + fixed(c.ours_solve_ms + r.ours_eval_ms(), 2) +
         " | " + sci(r.arap_ms / c.ours_solve_ms) + " | " + sci(r.arap_ms / (c.ours_solve_ms + r.ours_eval_ms())) + " |");
  }
  if (rows.empty()) line("| (no resolutions requested) | | | | | | | | | | | | | | |");
  line();
  return line.md;
}

std::string table4_markdown(const Table4& t, int sequence_frames) {
  Lines line;
  line("## Table 4: time per frame against ARAP, FFMP and GE");
  line();
  line("At the " + std::to_string(t.mesh_vertices) + "-vertex mesh, means over the " + std::to_string(sequence_frames) +
       " frames of the sequence" +
       (t.ccw16_bm_own_mesh ? " (CCW16 (boundary metric): at its " + std::to_string(t.ccw16_bm_mesh_vertices) + "-vertex mesh)"
                            : std::string()) +
       (t.boundary_metric ? "." : "; CCW16 (boundary metric) does not apply to a shape with holes.") +
       " GE and ours warm-start each frame from the previous one (keyframes' own frames not timed)." +
       (t.ours_timing.empty() ? std::string()
                              : " Ours: " + t.ours_timing + (std::isnan(t.ours_eval_cuda_ms) ? "" : " (f at the vertices on the CPU instead: " +
                                                                                                       fixed(t.ours_eval_cpu_ms, 3) + " ms)") +
                                    "."));
  line();
  line("![time per frame](frame_time.png)");
  line();
  line("| ARAP ms | FFMP ms | GE ms | GE #iter | ours solve ms | ours #iter | ours solve + f at vertices ms | CCW16 (log derivatives) ms | CCW16 (boundary metric) ms | ARAP / ours solve | ARAP / ours solve + f | GE / ours solve | GE / ours solve + f |");
  line("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
  line("| " + fixed(t.arap_ms, 2) + " | " + fixed(t.ffmp_ms, 2) + " | " + fixed(t.ge_ms, 2) + " | " + fixed(t.ge_iterations, 2) + " | " +
       fixed(t.ours_solve_ms, 2) + " | " + fixed(t.ours_iterations, 2) + " | " + fixed(t.ours_total_ms(), 2) + " | " + fixed(t.ccw16_ms, 2) +
       " | " + (t.boundary_metric ? fixed(t.ccw16_bm_ms, 2) : std::string("n/a")) + " | " + sci(t.arap_over_ours_solve()) + " | " +
       sci(t.arap_over_ours_total()) + " | " + sci(t.ge_over_ours_solve()) + " | " + sci(t.ge_over_ours_total()) + " |");
  line();
  line("GE: " + std::to_string(t.ge_not_converged) + " of " + std::to_string(t.ge_frames) +
       " frames not converged. Solved cold (the side-by-side interval's middle frame from its first keyframe, no warm start): GE " +
       fixed(t.ge_cold_iterations, 0) + " iterations in " + fixed(t.ge_cold_ms, 0) + " ms" + (t.ge_cold_converged ? "" : " (NOT CONVERGED)") +
       ", ours " + fixed(t.ours_cold_iterations, 0) + " (Table 1, PartProj). The paper reports GE at 35–165 iterations per frame "
       "and ours at 2–4.");
  line();
  return line.md;
}

}  // namespace hsi::compare
