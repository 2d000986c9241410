// The hsi compare pipeline (hsi/compare/compare.h): runs → alignment → figures → tables →
// claims → report, each stage in its own file; this one orders them and says how far it got.
#include "hsi/compare/compare.h"

#include <ctime>

#include "format.h"
#include "hsi/compare/figures.h"
#include "hsi/compare/outputs.h"
#include "hsi/compare/report.h"
#include "hsi/compute/vulkan_context.h"

namespace hsi::compare {

std::filesystem::path run(const Options& o) {
  const auto t_start = Clock::now();
  if (!o.backends.vulkan) throw std::invalid_argument("hsi::compare::run: no Vulkan context (Backends::vulkan) to render with");
  Inputs in = prepare_inputs(o);  // everything that can be refused is refused before any work
  compute::Context& ctx = *o.backends.vulkan;
  Comparison c;
  c.machine = this_machine();
  c.vulkan_device = ctx.info().name + " (" + ctx.info().type_name() + ")";
  const Cage& cage = in.setup->cage;
  say(o.progress, false, "scene %s: %d loop(s), %d hole(s), %zu keyframes; cage m = %d, |G| = %zu, |H| = %zu; %s, %d cores; Vulkan: %s",
      in.scene.name.c_str(), in.scene.shape.loop_count(), in.holes(), in.scene.keyframes.size(), cage.vertex_count(),
      in.setup->G.size(), in.setup->H.size(), c.machine.cpu.c_str(), c.machine.cores, c.vulkan_device.c_str());

  Outputs out(o.out);
  out.open();

  // Runs: ours, the baselines over the sequence, every method at the side-by-side times.
  const OurSequence ours = run_our_sequence(in, o);
  const Baselines b = set_up_baselines(in, o);
  const std::vector<baselines::GeFrame> ge = run_ge_sequence(ours.frames, b, o.progress);
  c.per_frame = measure_sequence(in, ours.frames, b, ge, o.progress);
  c.snaps = snapshots(in, ours, b, ge);
  say(o.progress, false, "GE cold: the middle of keyframe interval %d from its first keyframe ...", o.segment);
  const baselines::GeFrame ge_cold = ge_cold_frame(in, b, o.segment);
  say(o.progress, false, "GE cold: %d iterations, %.0f ms%s", ge_cold.iterations, ge_cold.ms, ge_cold.converged ? "" : ", NOT CONVERGED");

  // Figures.
  say(o.progress, false, "side by side: rendering %zu methods at t = 0.25, 0.5, 0.75 of keyframe interval %d ...",
      b.bm.applies ? size_t{6} : size_t{5}, o.segment);
  const SideBySide sbs = side_by_side(ctx, in, b, c.snaps, o.panel, o.segment, out);
  say(o.progress, false, "side by side: %zu figures at %d x %d per panel", c.snaps.size(), sbs.panel_width, sbs.panel_height);
  PlotLabels labels;
  labels.scene_name = in.scene.name;
  labels.keyframe_times = in.times;
  labels.holes = in.holes() > 0;
  labels.boundary_metric = b.bm.applies;
  labels.boundary_metric_coarse_vertices = b.bm.own_mesh ? b.bm.coarse.vertex_count() : 0;
  labels.mesh_vertices = b.mesh.vertex_count();
  labels.core = ours.core;
  const int plotted = plots(c.per_frame, labels, out);
  say(o.progress, false, "plots: %d written", plotted);

  // Tables 1–2: our sequences at other settings; 3–4: timings.
  c.table1 = run_table1(in, o, ours.core);
  c.table2 = run_table2(in, o);
  // Ours for Tables 3–4: solve + f at the render mesh's vertices, timed in one block.
  const OurTiming timing = time_ours(in, ours, b.mesh, o);
  c.gpu_clocks = timing.clocks_after;
  const std::vector<size_t> timed = timed_frames(ours.frames.size(), o.timing_frames);
  c.table3 = run_table3(in, ours.frames, timed, o);

  if (ctx.validation_enabled() && ctx.validation_log()->count())
    throw std::runtime_error("Vulkan validation reported problems:\n" + ctx.validation_log()->summary(10));

  // Fig. 8 (simply connected): each CCW16 variant against ours after rigid alignment.
  if (b.bm.applies) {
    std::vector<Gap> log_gaps, bm_gaps;
    for (const Snapshot& s : c.snaps) log_gaps.push_back(s.gap), bm_gaps.push_back(s.bm_gap);
    c.fig8_log = fig8(log_gaps, c.per_frame.ccw_dist, c.per_frame.t, c.per_frame.keyframe);
    c.fig8_bm = fig8(bm_gaps, c.per_frame.bm_dist, c.per_frame.t, c.per_frame.keyframe);
  }

  // The report: what ran where, the settings, every stage's numbers.
  c.scene_path = o.scene;
  c.name = in.scene.name;
  c.loops = in.scene.shape.loop_count();
  c.holes = in.holes();
  c.size = in.size();
  c.times = in.times;
  for (size_t k = 0; k < in.times.size(); ++k)
    c.keyframes.push_back({in.times[k], ours.interp->keyframe_distortion(static_cast<int>(k)),
                           ours.interp->keyframe_certified_distortion(static_cast<int>(k))});
  char date[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S %Z", std::localtime(&now));
  c.date = date;
  c.frames = o.frames;
  c.table_frames = o.table_frames;
  c.samples = static_cast<int>(in.setup->G.size());
  c.hessian_samples = static_cast<int>(in.setup->H.size());
  c.hessian_ratio = in.scene.hessian_ratio;
  c.segment = o.segment;
  c.timing_frames = o.timing_frames;
  c.mesh_vertices = b.mesh.vertex_count();
  c.mesh_triangles = b.mesh.triangle_count();
  c.ccw16_memory_mb = o.ccw16_memory_mb;
  c.core = ours.core;
  c.panel_width = sbs.panel_width;
  c.panel_height = sbs.panel_height;
  c.range_hi = sbs.range_hi;
  c.ours = ours.summary;
  c.ours_within_bound = ours.within_bound;
  c.arap_setup_ms = b.arap_setup_ms;
  c.ffmp_setup_ms = b.ffmp_setup_ms;
  c.ge_setup_ms = b.ge_setup_ms;
  c.keyframes_max_turn = b.keys_on_mesh.max_turn;
  c.ccw_setup_ms = b.ccw_setup_ms;
  c.arap_key_error = b.arap_key_error;
  c.bm = {b.bm.applies, b.bm.why_not, b.bm_mesh().vertex_count(), b.bm_mesh().triangle_count(), b.bm.own_mesh, b.bm.mb,
          b.bm.render_mesh_mb, b.bm.setup_ms};
  c.table3_context = {timing.solve_ms, timing.iterations, timed.size(), c.vulkan_device,
                      o.backends.dense_eval ? std::string() : o.backends.dense_eval_unavailable, timing.describe()};
  Table4& t4 = c.table4;
  t4.mesh_vertices = b.mesh.vertex_count();
  t4.arap_ms = mean_of(c.per_frame.arap_ms);
  t4.ffmp_ms = mean_of(c.per_frame.ffmp_ms);
  t4.ge_ms = mean_of(c.per_frame.ge_ms);
  for (size_t i = 0; i < ge.size(); ++i) {
    if (c.per_frame.keyframe[i]) continue;  // as ours: the keyframes' own frames are not counted
    t4.ge_iterations += ge[i].iterations;
    ++t4.ge_frames;
  }
  t4.ge_iterations = t4.ge_frames ? t4.ge_iterations / t4.ge_frames : std::numeric_limits<double>::quiet_NaN();
  for (const baselines::GeFrame& g : ge) t4.ge_not_converged += !g.converged;
  t4.ge_cold_iterations = ge_cold.iterations;
  t4.ge_cold_ms = ge_cold.ms;
  t4.ge_cold_converged = ge_cold.converged;
  for (const OurRun& r : c.table1)
    if (r.label == to_string(HessianProjection::PartProj)) t4.ours_cold_iterations = r.cold.iterations;
  t4.ccw16_ms = mean_of(c.per_frame.ccw_ms);
  t4.boundary_metric = b.bm.applies;
  t4.ccw16_bm_ms = mean_of(c.per_frame.bm_ms);
  t4.ccw16_bm_mesh_vertices = b.bm_mesh().vertex_count();
  t4.ccw16_bm_own_mesh = b.bm.own_mesh;
  t4.ours_solve_ms = timing.solve_ms;
  t4.ours_iterations = timing.iterations;
  t4.ours_eval_cpu_ms = timing.eval_cpu_ms;
  if (timing.evaluator != "cpu") t4.ours_eval_cuda_ms = timing.eval_ms;
  t4.ours_timing = timing.describe();
  c.claims = decide_claims(c);
  c.total_s = s_since(t_start);
  write_file_atomic(out.add("report.json"), report_json(c).dump(1) + "\n");
  c.total_s = s_since(t_start);
  const std::filesystem::path md = out.add("report.md");
  write_file_atomic(md, report_markdown(c));  // last: a report in the folder is a finished one
  out.commit();
  say(o.progress, false, "wrote %s with 3 side-by-side figures, %d plots, Tables 1-4 and %zu claims (report.json: raw numbers)",
      md.string().c_str(), plotted, c.claims.size());
  return md;
}

}  // namespace hsi::compare
