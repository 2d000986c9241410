// report.md of hsi compare (hsi/compare/report.h): the figures, the distortion over the
// sequence, Fig. 2 or Fig. 8, Tables 1–4 (tables.h) and the claims (claims.h), with the
// machine heading it.
#include "format.h"
#include "hsi/compare/report.h"
#include "hsi/interpolation.h"

namespace hsi::compare {

std::string report_markdown(const Comparison& c) {
  const PerFrame& p = c.per_frame;
  const int arap_folded = count_positive(p.arap_flipped);
  std::string md;
  auto line = [&md](const std::string& s = "") { md += s + "\n"; };
  line("# hsi compare: " + c.name);
  line();
  line("Scene `" + c.scene_path + "`: " + std::to_string(c.loops) + " loop(s), " + std::to_string(c.holes) +
       " hole(s), " + std::to_string(c.times.size()) + " keyframes at t = " + [&] {
         std::string s;
         for (size_t k = 0; k < c.times.size(); ++k) s += (k ? ", " : "") + fixed(c.times[k], 2);
         return s;
       }() + ". Measured in one run on " + c.date + ".");
  line();
  line("**Machine:** " + c.machine.cpu + ", " + std::to_string(c.machine.cores) + " logical cores; Vulkan device " + c.vulkan_device +
       " (rendering, and the Vulkan column of Table 3). Our Newton core: " + c.core + "." +
       (c.gpu_clocks.empty() ? std::string() : " GPU clocks after our timed block (Tables 3–4): " + c.gpu_clocks + "."));
  line();
  line("**Settings:** |G| = " + std::to_string(c.samples) + " boundary samples, |H| = " + std::to_string(c.hessian_samples) +
       " (r = " + fixed(c.hessian_ratio, 2) + "); ours with " + std::string(to_string(InterpolationOptions{}.projection)) +
       " (the interpolation's default: the plots and Tables 3–4; Table 2 with partproj, Table 1 each projection); " +
       std::to_string(c.frames) + " frames over the keyframes' range " +
       "for the plots, " + std::to_string(c.table_frames) + " for Tables 1–2; baselines on a " + std::to_string(c.mesh_vertices) +
       "-vertex, " + std::to_string(c.mesh_triangles) + "-triangle mesh" +
       (c.bm.own_mesh ? " (CCW16 (boundary metric) on a coarser " + std::to_string(c.bm.mesh_vertices) + "-vertex one: see Fig. 8)"
                    : std::string()) +
       "; keyframes for ARAP, FFMP and GE are our keyframe maps at its vertices, for CCW16 their coefficients.");
  line();
  line(c.bm.applies ? "## Side by side (ours, ARAP, FFMP, GE, CCW16 with log derivatives, CCW16 with the boundary metric)"
                  : "## Side by side (ours, ARAP, FFMP, GE, CCW16 with log derivatives)");
  line();
  line("At t = 0.25, 0.5, 0.75 between keyframes " + std::to_string(c.segment) + " and " + std::to_string(c.segment + 1) +
       ". Texture with the conformal distortion \xce\xba = \xcf\x83\xe2\x82\x81/\xcf\x83\xe2\x82\x82 over it, one colour range [1, " +
       fixed(c.range_hi, 2) + "] for every panel (up to the keyframes' bound, rounded up); larger values and folds saturate to the top colour. "
       "Ours: \xce\xba of the map at the mesh's vertices (the dense evaluation on the Vulkan device). ARAP, FFMP and GE: \xce\xba per triangle, drawn flat; GE's iterations for the frame (warm-started from its sequence's frame before t). "
       "CCW16: \xce\xba from its blended f_z, f_zbar at the vertices, positions integrated along a spanning tree of the mesh; "
       "two variants of it, CCW16 (log derivatives) and CCW16 (boundary metric), differ in what they blend (see " + std::string(c.bm.applies ? "Fig. 8" : "Fig. 2") + " below)." +
       (c.bm.applies ? (c.bm.own_mesh ? " CCW16 (boundary metric) is drawn on its own, coarser " + std::to_string(c.bm.mesh_vertices) +
                                        "-vertex mesh (memory: Fig. 8 below)."
                                  : std::string())
                   : " " + c.bm.why_not + ", so it has no column here."));
  line();
  for (const Snapshot& s : c.snaps) {
    line("![" + c.name + " at t = " + fixed(s.u, 2) + "](" + s.png + ")");
    line();
  }
  line("## Distortion over the sequence (Figs 3–5)");
  line();
  line("Largest distortion per frame. Ours, sampled: the largest value at the certificate's breakpoints on \xe2\x88\x82\xce\xa9 "
       "(observed, not a bound); ours, certified bound: the certificate's upper bound over \xe2\x88\x82\xce\xa9, so over \xce\xa9 "
       "(Theorem 2; the isometric one derived from the \xcf\x83\xe2\x82\x81 upper and \xcf\x83\xe2\x82\x82 lower bounds). "
       "ARAP, FFMP, GE: over the triangles of the mesh. CCW16: over the mesh's vertices. The keyframes' bound: the envelope of the two "
       "neighbouring keyframes' distortion, sampled or certified alike; on the mesh: the same envelope of the keyframes' largest "
       "per-triangle distortion on the render mesh (what the mesh methods are given), and ours on the mesh: our map at its "
       "vertices, per triangle (a control for the mesh methods' numbers).");
  line();
  line("![largest conformal distortion](kappa.png)");
  line();
  line("![largest isometric distortion](isometric.png)");
  line();
  line("| method | max \xce\xba | max isometric | frames | notes |");
  line("|---|---|---|---|---|");
  line("| keyframes' bound (sampled) | " + fixed(max_of(p.bound_kappa), 4) + " | " + fixed(max_of(p.bound_iso), 4) + " | | |");
  line("| keyframes' bound (certified) | " + fixed(max_of(p.bound_kappa_c), 4) + " | " + fixed(max_of(p.bound_iso_c), 4) + " | | |");
  line("| ours (sampled) | " + fixed(max_of(p.our_kappa), 4) + " | " + fixed(max_of(p.our_iso), 4) + " | " + std::to_string(c.ours.frames) + " | " +
       std::to_string(c.ours.certified) + " certified, " + std::to_string(c.ours.not_converged) + " not converged, " +
       std::to_string(c.ours_within_bound) + " within the keyframes' sampled bound (largest excess " + sci(c.ours.max_bound_excess) + ", relative) |");
  line("| ours (certified bound) | " + fixed(max_of(p.our_kappa_c), 4) + " | " + fixed(max_of(p.our_iso_c), 4) + " | " +
       std::to_string(c.ours.certified) + " | " + std::to_string(c.ours.within_certified_bounds) +
       " within the keyframes' certified bound (largest excess " + sci(c.ours.max_certified_bound_excess) + ", relative) |");
  line("| keyframes on the mesh (per triangle) | " + fixed(max_of(p.mesh_bound_kappa), 4) + " | " + fixed(max_of(p.mesh_bound_iso), 4) +
       " | | largest turn between neighbouring keyframes " + fixed(c.keyframes_max_turn * 180 / M_PI, 0) + "\xc2\xb0 |");
  line("| ours on the mesh (per triangle) | " + fixed(max_of(p.ours_mesh_kappa), 4) + " | " + fixed(max_of(p.ours_mesh_iso), 4) + " | " +
       std::to_string(p.size()) + " | a triangle shrunk below both keyframes by up to " + sci(max_of(p.ours_mesh_shrink)) + " (relative) |");
  line("| ARAP | " + fixed(max_of(p.arap_kappa), 4) + " | " + fixed(max_of(p.arap_iso), 4) + " | " + std::to_string(p.size()) + " | " +
       std::to_string(arap_folded) + " frames with flipped triangles; keyframes reproduced to " + sci(c.arap_key_error) + " \xc3\x97 size |");
  line("| FFMP | " + fixed(max_of(p.ffmp_kappa), 4) + " | " + fixed(max_of(p.ffmp_iso), 4) + " | " + std::to_string(p.size()) + " | " +
       std::to_string(count_positive(p.ffmp_flipped)) + " frames with flipped triangles; a triangle shrunk below both keyframes by up to " +
       sci(max_of(p.ffmp_shrink)) + " (relative) |");
  const int ge_unconverged = count_not_converged(p.ge_converged);
  line("| GE | " + fixed(max_of(p.ge_kappa), 4) + " | " + fixed(max_of(p.ge_iso), 4) + " | " + std::to_string(p.size()) + " | " +
       std::to_string(count_positive(p.ge_flipped)) + " frames with flipped triangles, " + std::to_string(ge_unconverged) +
       " not converged; up to " + sci(max_of(p.ge_dist)) + " \xc3\x97 size from ours after rigid alignment |");
  line("| CCW16 (log derivatives) | " + fixed(max_of(p.ccw_kappa), 4) + " | " + fixed(max_of(p.ccw_iso), 4) + " | " + std::to_string(p.size()) + " | " +
       (c.holes ? "not a map: largest hole period " + sci(max_of(p.ccw_period)) + " \xc3\x97 size" : std::string("simply connected: a map")) + " |");
  if (c.bm.applies)
    line("| CCW16 (boundary metric) | " + fixed(max_of(p.bm_kappa), 4) + " | " + fixed(max_of(p.bm_iso), 4) + " | " + std::to_string(p.size()) +
         " | simply connected: a map; blended metric realised at \xe2\x88\x82\xce\xa9 to " + sci(max_of(p.bm_fit)) + " (relative)" +
         (c.bm.own_mesh ? "; on the " + std::to_string(c.bm.mesh_vertices) + "-vertex mesh" : std::string()) + " |");
  else
    line("| CCW16 (boundary metric) | n/a | n/a | 0 | does not apply: " + std::to_string(c.holes) + " hole(s), a multiply-connected domain (paper \xc2\xa7" "1) |");
  line();
  if (c.holes) {
    line("## CCW16 on a shape with holes (Fig. 2)");
    line();
    line("**CCW16 (log derivatives)** " + kLogBlends + ". A frame of it is single-valued only if the integral of its blended "
         "derivatives around every hole (the period P) vanishes. At the keyframes it does; in between it does not, and the integrated mesh tears along a seam by P:");
    line();
    line("| t | hole periods \\|P\\| / size | seam jump / size | max \xce\xba |");
    line("|---|---|---|---|");
    for (const Snapshot& s : c.snaps) {
      std::string periods, jumps;
      for (size_t i = 0; i < s.ccw.hole_period.size(); ++i) periods += (i ? ", " : "") + sci(s.ccw.hole_period[i] / c.size);
      for (size_t i = 0; i < s.ccw.seam_jump.size(); ++i) jumps += (i ? ", " : "") + sci(s.ccw.seam_jump[i] / c.size);
      line("| " + fixed(s.u, 2) + " | " + periods + " | " + jumps + " | " + fixed(s.ccw.max_kappa, 4) + " |");
    }
    line();
    line("**CCW16 (boundary metric)** " + kBmBlends + ". " + c.bm.why_not + ". It is the variant of the paper's Fig. 8 (CCW16 against ours on a simply-connected shape), "
         "which therefore has no counterpart on this scene: run `hsi compare` on a shape without holes (e.g. assets/blob.json) for it.");
  } else {
    line("## CCW16 against ours on a simply-connected shape (Fig. 8)");
    line();
    line("Two variants of CCW16 interpolate the same keyframes. **CCW16 (log derivatives)** " + kLogBlends +
         ". **CCW16 (boundary metric)** " + kBmBlends +
         "; it is the variant the paper's Fig. 8 finds visually the same as ours. Largest distance to our frame over the vertices "
         "of each variant's mesh, relative to the shape's size (bounding-box diagonal), as they are and after the best rigid "
         "alignment (the methods place the frame differently: ours by an interpolated rigid pose, CCW16 from an anchor point "
         "and its mean rotation):");
    line();
    line("| t | log derivatives: max \\|f_ours \xe2\x88\x92 f_CCW16\\| / size | after rigid alignment | boundary metric: max "
         "\\|f_ours \xe2\x88\x92 f_CCW16\\| / size | after rigid alignment | boundary metric: metric fit at \xe2\x88\x82\xce\xa9 | "
         "max \xce\xba ours | max \xce\xba log derivatives | max \xce\xba boundary metric |");
    line("|---|---|---|---|---|---|---|---|---|");
    for (const Snapshot& s : c.snaps)
      line("| " + fixed(s.u, 2) + " | " + sci(s.gap.raw) + " | " + sci(s.gap.rigid) + " | " + sci(s.bm_gap.raw) + " | " +
           sci(s.bm_gap.rigid) + " | " + sci(s.bm.fit_metric) + " | " + fixed(s.ours.distortion.conformal_max, 4) + " | " +
           fixed(s.ccw.max_kappa, 4) + " | " + fixed(s.bm.max_kappa, 4) + " |");
    line();
    line("Over the whole sequence (" + std::to_string(p.size()) + " frames, every keyframe interval), after rigid alignment: CCW16 (log "
         "derivatives) up to " + sci(c.fig8_log.sequence_rigid) + " of the size (at t = " + fixed(c.fig8_log.sequence_t, 3) +
         "), CCW16 (boundary metric) up to " + sci(c.fig8_bm.sequence_rigid) + " (at t = " + fixed(c.fig8_bm.sequence_t, 3) + "). "
         "Between the keyframes only (at a keyframe ours and the log-derivative variant reproduce it exactly, the "
         "boundary-metric variant up to its fit): " + sci(c.fig8_log.between_keyframes_rigid) + " and " +
         sci(c.fig8_bm.between_keyframes_rigid) + ".");
    line();
    line("![CCW16 against ours after rigid alignment](ccw16_distance.png)");
    line();
    line("The relative fit is how well the boundary-metric variant's rebuilt f_z, f_zbar realise the blended metric at the "
         "boundary samples (\xe2\x80\x96M(f) \xe2\x88\x92 M(t)\xe2\x80\x96 / \xe2\x80\x96M(t)\xe2\x80\x96, largest over \xe2\x88\x82\xce\xa9). "
         "Memory: this variant keeps its basis rows at every vertex and quadrature node of its mesh, " +
         fixed(c.bm.render_mesh_mb, 0) + " MB on the " + std::to_string(c.mesh_vertices) + "-vertex render mesh" +
         (c.bm.own_mesh ? "; above the " + fixed(c.ccw16_memory_mb, 0) + " MB allowed (--ccw16-memory) it ran on a coarser " +
                            std::to_string(c.bm.mesh_vertices) + "-vertex mesh of the shape (" + fixed(c.bm.mb, 0) +
                            " MB), and its distances, distortion and time are measured at that mesh's vertices."
                      : " (within the " + fixed(c.ccw16_memory_mb, 0) + " MB allowed, --ccw16-memory)."));
  }
  line();
  md += table1_markdown(c.table1, c.table_frames);
  md += table2_markdown(c.table2, c.table_frames);
  md += table3_markdown(c.table3, c.table3_context);
  md += table4_markdown(c.table4, static_cast<int>(p.size()));
  md += claims_markdown(c.claims);
  line("Raw numbers: [report.json](report.json). Made by `hsi compare` in " + fixed(c.total_s, 1) + " s.");
  return md;
}

}  // namespace hsi::compare
