// report.json and report.md of hsi compare (hsi/compare/report.h).
#include "hsi/compare/report.h"

#include "format.h"

namespace hsi::compare {

using nlohmann::json;

namespace {

json over_size(const std::vector<double>& v, double size) {
  json a = json::array();
  for (double p : v) a.push_back(p / size);
  return a;
}

json sequence_json(const Comparison& c) {
  const PerFrame& p = c.per_frame;
  json s = {{"t", p.t},
            {"ours", {{"kappa", nums(p.our_kappa)}, {"isometric", nums(p.our_iso)}, {"kappa_certified_bound", nums(p.our_kappa_c)},
                      {"isometric_certified_bound", nums(p.our_iso_c)}, {"ms", nums(p.our_ms)}, {"iterations", p.our_iters}}},
            {"bound", {{"kappa", nums(p.bound_kappa)}, {"isometric", nums(p.bound_iso)}, {"kappa_certified_bound", nums(p.bound_kappa_c)},
                       {"isometric_certified_bound", nums(p.bound_iso_c)}}},
            {"keyframes_on_mesh", {{"kappa", nums(p.mesh_bound_kappa)}, {"isometric", nums(p.mesh_bound_iso)}}},
            {"ours_on_mesh", {{"kappa", nums(p.ours_mesh_kappa)}, {"isometric", nums(p.ours_mesh_iso)},
                              {"area_shrink", nums(p.ours_mesh_shrink)}}},
            {"arap", {{"kappa", nums(p.arap_kappa)}, {"isometric", nums(p.arap_iso)}, {"flipped", p.arap_flipped}, {"ms", nums(p.arap_ms)},
                      {"area_shrink", nums(p.arap_shrink)}}},
            {"ffmp", {{"kappa", nums(p.ffmp_kappa)}, {"isometric", nums(p.ffmp_iso)}, {"flipped", p.ffmp_flipped}, {"ms", nums(p.ffmp_ms)},
                      {"area_shrink", nums(p.ffmp_shrink)}}},
            {"ge", {{"kappa", nums(p.ge_kappa)}, {"isometric", nums(p.ge_iso)}, {"flipped", p.ge_flipped}, {"ms", nums(p.ge_ms)},
                    {"iterations", p.ge_iters}, {"converged", p.ge_converged}, {"area_shrink", nums(p.ge_shrink)},
                    {"distance_to_ours_after_rigid_alignment_over_size", nums(p.ge_dist)}}},
            {"ccw16", {{"kappa", nums(p.ccw_kappa)}, {"isometric", nums(p.ccw_iso)}, {"ms", nums(p.ccw_ms)},
                       {"max_hole_period_over_size", nums(p.ccw_period)}}}};
  if (c.bm.applies) {
    s["ccw16"]["distance_to_ours_after_rigid_alignment_over_size"] = nums(p.ccw_dist);
    s["ccw16_boundary_metric"] = {{"kappa", nums(p.bm_kappa)},
                                  {"isometric", nums(p.bm_iso)},
                                  {"ms", nums(p.bm_ms)},
                                  {"fit_metric", nums(p.bm_fit)},
                                  {"distance_to_ours_after_rigid_alignment_over_size", nums(p.bm_dist)}};
  }
  return s;
}

json summary_json(const Comparison& c) {
  const PerFrame& p = c.per_frame;
  const SequenceSummary& o = c.ours;
  const int arap_folded = count_positive(p.arap_flipped);
  json s = {
      {"ours", {{"frames", o.frames}, {"certified", o.certified}, {"not_converged", o.not_converged},
                {"frames_within_bound", c.ours_within_bound}, {"max_bound_excess", o.max_bound_excess},
                {"frames_within_certified_bound", o.within_certified_bounds},
                {"max_certified_bound_excess", o.max_certified_bound_excess},
                {"max_kappa_certified_bound", num(max_of(p.our_kappa_c))}, {"max_isometric_certified_bound", num(max_of(p.our_iso_c))},
                {"max_kappa", num(max_of(p.our_kappa))},
                {"max_isometric", num(max_of(p.our_iso))}, {"mean_iterations", o.mean_iterations}, {"mean_ms", o.mean_ms}}},
      {"bound", {{"max_kappa", num(max_of(p.bound_kappa))}, {"max_isometric", num(max_of(p.bound_iso))},
                 {"max_kappa_certified_bound", num(max_of(p.bound_kappa_c))}, {"max_isometric_certified_bound", num(max_of(p.bound_iso_c))}}},
      {"keyframes_on_mesh", {{"max_kappa", num(max_of(p.mesh_bound_kappa))}, {"max_isometric", num(max_of(p.mesh_bound_iso))},
                             {"max_turn_degrees", c.keyframes_max_turn * 180 / M_PI}}},
      {"ours_on_mesh", {{"max_kappa", num(max_of(p.ours_mesh_kappa))}, {"max_isometric", num(max_of(p.ours_mesh_iso))},
                        {"max_area_shrink", num(max_of(p.ours_mesh_shrink))}}},
      {"arap", {{"max_kappa", num(max_of(p.arap_kappa))}, {"max_isometric", num(max_of(p.arap_iso))}, {"frames_with_flips", arap_folded},
                {"keyframe_error_over_size", c.arap_key_error}, {"setup_ms", c.arap_setup_ms}, {"mean_ms", mean_of(p.arap_ms)},
                {"max_area_shrink", num(max_of(p.arap_shrink))}}},
      {"ffmp", {{"max_kappa", num(max_of(p.ffmp_kappa))}, {"max_isometric", num(max_of(p.ffmp_iso))},
                {"frames_with_flips", count_positive(p.ffmp_flipped)}, {"setup_ms", c.ffmp_setup_ms}, {"mean_ms", mean_of(p.ffmp_ms)},
                {"max_area_shrink", num(max_of(p.ffmp_shrink))}}},
      {"ge", {{"max_kappa", num(max_of(p.ge_kappa))}, {"max_isometric", num(max_of(p.ge_iso))}, {"frames_with_flips", count_positive(p.ge_flipped)},
              {"not_converged", count_not_converged(p.ge_converged)},
              {"setup_ms", c.ge_setup_ms}, {"mean_ms", mean_of(p.ge_ms)}, {"max_area_shrink", num(max_of(p.ge_shrink))},
              {"max_distance_to_ours_after_rigid_alignment_over_size", num(max_of(p.ge_dist))}}},
      {"ccw16", {{"max_kappa", num(max_of(p.ccw_kappa))}, {"max_isometric", num(max_of(p.ccw_iso))},
                 {"max_hole_period_over_size", num(max_of(p.ccw_period))}, {"setup_ms", c.ccw_setup_ms}, {"mean_ms", mean_of(p.ccw_ms)}}}};
  s["ccw16_boundary_metric"] =
      c.bm.applies ? json{{"applies", true}, {"max_kappa", num(max_of(p.bm_kappa))}, {"max_isometric", num(max_of(p.bm_iso))},
                          {"max_fit_metric", num(max_of(p.bm_fit))}, {"setup_ms", c.bm.setup_ms}, {"mean_ms", mean_of(p.bm_ms)}}
                   : json{{"applies", false}, {"reason", c.bm.why_not}};
  return s;
}

json side_by_side_json(const Comparison& c) {
  json sbs = json::array();
  for (const Snapshot& s : c.snaps) {
    sbs.push_back({{"u", s.u},
                   {"t", s.t},
                   {"png", s.png},
                   {"image_size", {s.width, s.height}},
                   {"ours", {{"certified", s.ours.certified}, {"iterations", s.ours.iterations}, {"kappa_max", s.ours.distortion.conformal_max},
                             {"isometric_max", s.ours.distortion.isometric_max}, {"bound_kappa", s.ours.bound.conformal_max},
                             {"kappa_max_certified_bound", num(s.ours.distortion_certified.conformal_max)},
                             {"bound_kappa_certified", num(s.ours.certified_bound.conformal_max)}}},
                   {"arap", {{"kappa_max", num(s.arap_d.max_kappa)}, {"isometric_max", num(s.arap_d.max_isometric)}, {"flipped", s.arap_d.flipped}}},
                   {"ffmp", {{"kappa_max", num(s.ffmp_d.max_kappa)}, {"isometric_max", num(s.ffmp_d.max_isometric)}, {"flipped", s.ffmp_d.flipped}}},
                   {"ge", {{"kappa_max", num(s.ge_d.max_kappa)}, {"isometric_max", num(s.ge_d.max_isometric)}, {"flipped", s.ge_d.flipped},
                           {"iterations", s.ge_iterations}, {"converged", s.ge_converged},
                           {"max_distance_to_ours_after_rigid_alignment_over_size", s.ge_gap.rigid}}},
                   {"ccw16", {{"kappa_max", num(s.ccw.max_kappa)}, {"isometric_max", num(s.ccw.max_isometric)},
                              {"hole_period_over_size", over_size(s.ccw.hole_period, c.size)},
                              {"seam_jump_over_size", over_size(s.ccw.seam_jump, c.size)},
                              {"max_distance_to_ours_over_size", s.gap.raw},
                              {"max_distance_to_ours_after_rigid_alignment_over_size", s.gap.rigid}}}});
    if (c.bm.applies)
      sbs.back()["ccw16_boundary_metric"] = {{"kappa_max", num(s.bm.max_kappa)},
                                             {"isometric_max", num(s.bm.max_isometric)},
                                             {"fit_log_modulus", s.bm.fit_log_modulus},
                                             {"fit_fzbar", s.bm.fit_fzbar},
                                             {"fit_metric", s.bm.fit_metric},
                                             {"max_distance_to_ours_over_size", s.bm_gap.raw},
                                             {"max_distance_to_ours_after_rigid_alignment_over_size", s.bm_gap.rigid}};
  }
  return sbs;
}

json fig8_json(const Fig8& g, const std::string& name, const std::string& blends, int vertices) {
  return json{{"name", name},
              {"blends", blends},
              {"mesh_vertices", vertices},
              {"max_distance_to_ours_over_size", g.raw},
              {"max_distance_to_ours_after_rigid_alignment_over_size", g.rigid},
              {"sequence_max_distance_after_rigid_alignment_over_size", num(g.sequence_rigid)},
              {"sequence_max_at_t", num(g.sequence_t)},
              {"between_keyframes_max_distance_after_rigid_alignment_over_size", num(g.between_keyframes_rigid)}};
}

}  // namespace

json report_json(const Comparison& c) {
  json rep;
  rep["scene"] = c.scene_path;
  rep["name"] = c.name;
  rep["holes"] = c.holes;
  rep["date"] = c.date;
  rep["machine"] = {{"cpu", c.machine.cpu}, {"logical_cores", c.machine.cores}, {"vulkan_device", c.vulkan_device},
                    {"gpu_clocks", c.gpu_clocks}};
  rep["settings"] = {{"frames", c.frames},
                     {"table_frames", c.table_frames},
                     {"mesh_vertices", c.mesh_vertices},
                     {"mesh_triangles", c.mesh_triangles},
                     {"samples", c.samples},
                     {"hessian_samples", c.hessian_samples},
                     {"hessian_ratio", c.hessian_ratio},
                     {"segment", c.segment},
                     {"timing_frames", c.timing_frames},
                     {"ccw16_memory_mb", c.ccw16_memory_mb},
                     {"newton_core", c.core},
                     {"panel_size", {c.panel_width, c.panel_height}}};
  json kf = json::array();
  for (const KeyframeDistortion& k : c.keyframes)
    kf.push_back({{"time", k.time},
                  {"conformal_max", k.sampled.conformal_max},
                  {"isometric_max", k.sampled.isometric_max},
                  {"conformal_max_certified_bound", k.certified.conformal_max},
                  {"isometric_max_certified_bound", k.certified.isometric_max}});
  rep["keyframes"] = kf;
  rep["distortion_kinds"] = {
      {"sampled", "ours' kappa / isometric and the keyframes' bound: sampled at the certificate's breakpoints on the boundary"},
      {"per_triangle", "arap, ffmp, ge, keyframes_on_mesh, ours_on_mesh: per triangle of the piecewise-linear frame on the render "
                       "mesh (ours_on_mesh: our map at its vertices); area_shrink: how far a triangle's area ratio falls below "
                       "both neighbouring keyframes' on it, min(det_k, det_k+1) / det - 1 (0: none smaller than both)"},
      {"certified", "*_certified_bound: the certificate's bounds over the boundary, so over the shape (Theorem 2); isometric from "
                    "the sigma bounds; \"nan\" where a frame is not certified"}};
  rep["sequence"] = sequence_json(c);
  json bm = {{"name", "CCW16 (boundary metric)"}, {"variant", to_string(baselines::Ccw16Variant::BoundaryMetric)},
             {"blends", kBmBlends}, {"applies", c.bm.applies}};
  if (c.bm.applies) {
    bm["mesh_vertices"] = c.bm.mesh_vertices;
    bm["mesh_triangles"] = c.bm.mesh_triangles;
    bm["coarser_than_render_mesh"] = c.bm.own_mesh;
    bm["basis_rows_mb"] = c.bm.mb;
    bm["render_mesh_basis_rows_mb"] = c.bm.render_mesh_mb;
    bm["memory_budget_mb"] = c.ccw16_memory_mb;
  } else {
    bm["reason"] = c.bm.why_not;
  }
  rep["ccw16_variants"] = {{"log_derivatives", {{"name", "CCW16 (log derivatives)"},
                                                {"variant", to_string(baselines::Ccw16Variant::LogDerivatives)},
                                                {"blends", kLogBlends},
                                                {"applies", true},
                                                {"mesh_vertices", c.mesh_vertices}}},
                           {"boundary_metric", bm}};
  rep["summary"] = summary_json(c);
  rep["side_by_side"] = side_by_side_json(c);
  // Fig. 8 (simply connected): each variant's distance to our frames, as is and after the best
  // rigid alignment, the largest over the three side-by-side times and over the whole sequence.
  if (c.bm.applies) {
    json times = json::array();
    for (const Snapshot& s : c.snaps) times.push_back(s.t);
    rep["fig8"] = {{"applies", true},
                   {"times", times},
                   {"log_derivatives", fig8_json(c.fig8_log, "CCW16 (log derivatives)", kLogBlends, c.mesh_vertices)},
                   {"boundary_metric", fig8_json(c.fig8_bm, "CCW16 (boundary metric)", kBmBlends, c.bm.mesh_vertices)}};
  } else {
    rep["fig8"] = {{"applies", false},
                   {"reason", "CCW16 (log derivatives) is not a map on this shape (its hole periods: Fig. 2); " + c.bm.why_not}};
  }
  rep["colour_range"] = {1.0, c.range_hi};
  json t1 = json::array(), t2 = json::array();
  for (const OurRun& r : c.table1) t1.push_back(run_json(r));
  for (const OurRun& r : c.table2) t2.push_back(run_json(r));
  rep["table1_projection"] = t1;
  rep["table2_ratio"] = t2;
  rep["table3_resolution"] = table3_json(c.table3, c.table3_context);
  rep["table4_per_frame"] = table4_json(c.table4);
  rep["claims"] = claims_json(c.claims);
  rep["total_s"] = c.total_s;
  return rep;
}

}  // namespace hsi::compare
