// hsi compare's figures: side-by-side panels and plots (hsi/compare/figures.h).
#include "hsi/compare/figures.h"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "format.h"
#include "hsi/compute/renderer.h"
#include "hsi/draw/plot.h"

namespace hsi::compare {

draw::Surface compose(const std::string& title, const std::vector<Column>& cols, double lo, double hi) {
  using draw::text;
  const int W = cols.front().image.width, H = cols.front().image.height;
  const double font = std::max(12.0, std::max(W, H) / 30.0);
  const int gap = static_cast<int>(std::ceil(0.6 * font));
  const int title_h = static_cast<int>(std::ceil(2.0 * font)), head_h = static_cast<int>(std::ceil(2.7 * font));
  const int legend_h = static_cast<int>(std::ceil(3.4 * font));
  const int n = static_cast<int>(cols.size());
  const int total_w = n * W + (n + 1) * gap, total_h = title_h + head_h + H + legend_h;
  draw::Surface s = draw::make_surface(total_w, total_h);
  cairo_t* cr = s.cr();
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  text(cr, gap, 1.35 * font, title, 1.05 * font, true, 0.1, 0.1, 0.1, false);
  for (int c = 0; c < n; ++c) {
    const Column& col = cols[static_cast<size_t>(c)];
    const double x = gap + c * (W + gap);
    text(cr, x, title_h + 1.0 * font, col.name, 0.95 * font, true, 0.1, 0.1, 0.1, false);
    // The numbers line, shrunk to the panel's width if it is long.
    double size = 0.78 * font;
    while (size > 8 && draw::text_width(cr, col.stats, size, false) > W) size *= 0.92;
    text(cr, x, title_h + 2.15 * font, col.stats, size, false, col.stats_alarm ? 0.8 : 0.25, col.stats_alarm ? 0.05 : 0.25,
         col.stats_alarm ? 0.05 : 0.25, false);
    const draw::Surface panel = draw::surface_from(col.image);
    cairo_set_source_surface(cr, panel.surf.get(), x, title_h + head_h);
    cairo_paint(cr);
    cairo_rectangle(cr, x - 0.5, title_h + head_h - 0.5, W + 1, H + 1);
    cairo_set_source_rgb(cr, 0.75, 0.75, 0.75);
    cairo_set_line_width(cr, 1);
    cairo_stroke(cr);
  }
  draw::draw_legend(cr, total_w, total_h, legend_h, lo, hi, font);
  return s;
}

namespace {

// CCW16's conformal distortion at the vertices from its f_z, f_zbar (≤ 0: a fold, drawn saturated).
std::vector<double> vertex_kappa(const baselines::Ccw16Frame& f) {
  std::vector<double> kappa(f.positions.size());
  for (size_t v = 0; v < kappa.size(); ++v) {
    const double a = std::abs(f.fz[v]), b = std::abs(f.fzbar[v]);
    kappa[v] = a > b ? (a + b) / (a - b) : -1.0;
  }
  return kappa;
}

void grow(BoundingBox& b, cd p) {
  if (!std::isfinite(p.real()) || !std::isfinite(p.imag())) return;
  b.lo = {std::min(b.lo.real(), p.real()), std::min(b.lo.imag(), p.imag())};
  b.hi = {std::max(b.hi.real(), p.real()), std::max(b.hi.imag(), p.imag())};
}

}  // namespace

double colour_range_hi(const std::vector<Snapshot>& snaps, bool boundary_metric) {
  double hi = 1;
  for (const Snapshot& s : snaps)
    for (double k : {s.ours.distortion.conformal_max, s.arap_d.max_kappa, s.ffmp_d.max_kappa, s.ge_d.max_kappa, s.ccw.max_kappa,
                     boundary_metric ? s.bm.max_kappa : 1.0})
      if (std::isfinite(k)) hi = std::max(hi, std::min(k, s.ours.bound.conformal_max));
  return compute::round_distortion_hi(hi);
}

SideBySide side_by_side(compute::Context& ctx, const Inputs& in, const Baselines& b, std::vector<Snapshot>& snaps, int panel,
                        int segment, Outputs& out) {
  const Cage& cage = in.setup->cage;
  const double size = in.size();
  const int holes = in.holes();
  const bool bm = b.bm.applies;
  const double inf = std::numeric_limits<double>::infinity();
  BoundingBox box{cd(inf, inf), cd(-inf, -inf)};
  for (const Snapshot& s : snaps)
    for (const auto* v : {&s.ours_pos, &s.arap_pos, &s.ffmp_pos, &s.ge_pos, &s.ccw.positions, &s.bm.positions})
      for (const cd& p : *v) grow(box, p);
  SideBySide r;
  r.range_hi = colour_range_hi(snaps, bm);

  // One view for every panel (same scale and place), panels fitted to its aspect.
  const cd ext = box.hi - box.lo;
  const double aspect = std::max(ext.real(), 1e-12) / std::max(ext.imag(), 1e-12);
  const double margin = std::max(8.0, 0.04 * panel);
  int pw = panel, ph = panel;
  if (aspect >= 1)
    ph = std::clamp(static_cast<int>(std::ceil((panel - 2 * margin) / aspect + 2 * margin)), panel / 3, panel);
  else
    pw = std::clamp(static_cast<int>(std::ceil((panel - 2 * margin) * aspect + 2 * margin)), panel / 3, panel);
  pw += pw % 2;
  ph += ph % 2;
  r.panel_width = pw;
  r.panel_height = ph;
  const compute::View view = compute::View::fit(box, pw, ph, margin);
  const SceneTexture& tex = in.texture;
  compute::Renderer welded(ctx, pw, ph), flat(ctx, pw, ph);
  welded.set_mesh(b.mesh);
  welded.set_texture(tex.image, tex.rect, tex.filter);
  const compute::UnweldedMesh unwelded = compute::unweld(b.mesh);
  flat.set_mesh(unwelded.mesh);
  flat.set_texture(tex.image, tex.rect, tex.filter);
  // CCW16 (boundary metric) on its own, coarser mesh when the render mesh's rows were too large.
  std::unique_ptr<compute::Renderer> coarse;
  if (bm && b.bm.own_mesh) {
    coarse = std::make_unique<compute::Renderer>(ctx, pw, ph);
    coarse->set_mesh(b.bm.coarse);
    coarse->set_texture(tex.image, tex.rect, tex.filter);
  }
  compute::RenderStyle style;
  style.overlays = compute::kOverlayDistortion | compute::kOverlayBoundary;  // no handles: the baselines have none
  style.distortion_lo = 1;
  style.distortion_hi = r.range_hi;
  style.distortion_opacity = 0.7f;
  style.boundary_width_px = static_cast<float>(std::max(1.2, panel / 360.0));
  for (Snapshot& s : snaps) {
    std::vector<Column> cols;
    {
      compute::RenderStyle st = style;
      st.uncertified = !s.ours.certified;
      // The title claims only what this frame's certificate proved.
      Column c{s.ours.certified ? "Ours (harmonic, certified locally injective)" : "Ours (harmonic)", "", false,
               welded.render(cage, s.ours.map, view, st)};
      c.stats = "max \xce\xba " + fixed(s.ours.distortion.conformal_max, 3) + " sampled, \xe2\x89\xa4 " +
                fixed(s.ours.distortion_certified.conformal_max, 3) + " certified  (keyframes " + fixed(s.ours.bound.conformal_max, 3) +
                ")  " + std::to_string(s.ours.iterations) + " it";
      if (!s.ours.certified) {
        c.stats = "NOT CERTIFIED: " + s.ours.certificate.reason;
        c.stats_alarm = true;
      }
      cols.push_back(std::move(c));
    }
    // A mesh method: per-triangle distortion, drawn flat (each triangle's three corners get its value).
    auto mesh_column = [&](const char* name, const std::vector<cd>& at, const baselines::MeshDistortion& d, const std::string& more) {
      std::vector<cd> pos(unwelded.source.size());
      std::vector<double> kappa(unwelded.source.size());
      for (size_t v = 0; v < pos.size(); ++v) {
        pos[v] = at[static_cast<size_t>(unwelded.source[v])];
        kappa[v] = d.kappa[v / 3];
      }
      Column c{name, "", d.flipped > 0, flat.render(pos, kappa, view, style)};
      c.stats = "max \xce\xba " + fixed(d.max_kappa, 3) + " per triangle, " + std::to_string(d.flipped) + " flipped" + more;
      cols.push_back(std::move(c));
    };
    mesh_column("ARAP [ACOL00]", s.arap_pos, s.arap_d, "");
    mesh_column("FFMP [KG08]", s.ffmp_pos, s.ffmp_d, "");
    mesh_column("GE [SGK19]", s.ge_pos, s.ge_d,
                ", " + std::to_string(s.ge_iterations) + " it" + (s.ge_converged ? "" : " NOT CONVERGED"));
    if (!s.ge_converged) cols.back().stats_alarm = true;
    {
      const double period = s.ccw.hole_period.empty() ? 0.0 : max_of(s.ccw.hole_period);
      // Any period above rounding makes the frame multivalued; above 0.1% of the size it shows.
      Column c{"CCW16 (log derivatives)", "", period > 1e-3 * size, welded.render(s.ccw.positions, vertex_kappa(s.ccw), view, style)};
      if (holes && period > 1e-9 * size)
        c.stats = "NOT A MAP: hole period " + sci(period / size) + " \xc3\x97 size";
      else if (holes)
        c.stats = "hole period " + sci(period / size) + " \xc3\x97 size (integrable here)";
      else
        c.stats = "max \xce\xba " + fixed(s.ccw.max_kappa, 3) + ", rigid gap to ours " + sci(s.gap.rigid) + " \xc3\x97 size";
      cols.push_back(std::move(c));
    }
    if (bm) {
      compute::Renderer& rr = coarse ? *coarse : welded;
      Column c{"CCW16 (boundary metric)", "", false, rr.render(s.bm.positions, vertex_kappa(s.bm), view, style)};
      c.stats = "max \xce\xba " + fixed(s.bm.max_kappa, 3) + ", rigid gap to ours " + sci(s.bm_gap.rigid) + " \xc3\x97 size";
      if (b.bm.own_mesh) c.stats += ", " + std::to_string(b.bm.coarse.vertex_count()) + "-vertex mesh";
      cols.push_back(std::move(c));
    }
    char title[256];
    std::snprintf(title, sizeof title, "%s   t = %.2f between keyframes %d and %d (time %.3f)", in.scene.name.c_str(), s.u, segment,
                  segment + 1, s.t);
    char name[64];
    std::snprintf(name, sizeof name, "side_by_side_t%.2f.png", s.u);
    s.png = name;
    const draw::Surface fig = compose(title, cols, 1, r.range_hi);
    s.width = cairo_image_surface_get_width(fig.surf.get());
    s.height = cairo_image_surface_get_height(fig.surf.get());
    draw::write_surface(fig, out.add(name));
  }
  return r;
}

int plots(const PerFrame& p, const PlotLabels& l, Outputs& out) {
  using draw::AxisScale;
  using draw::PlotSpec;
  const std::string ccw_name = l.holes ? "CCW16 (log derivatives) at vertices, not a map (hole period \xe2\x89\xa0 0)"
                                       : "CCW16 (log derivatives) at vertices";
  const std::string bm_mesh_note =
      l.boundary_metric_coarse_vertices > 0 ? " (" + std::to_string(l.boundary_metric_coarse_vertices) + "-vertex mesh)" : std::string();
  const std::string bm_name = "CCW16 (boundary metric) at vertices" + bm_mesh_note;
  constexpr double kBmR = 0.6, kBmG = 0.25, kBmB = 0.7;  // the boundary-metric variant's colour in every plot
  constexpr double kFfmpR = 0.85, kFfmpG = 0.15, kFfmpB = 0.45, kGeR = 0.45, kGeG = 0.3, kGeB = 0.1;  // FFMP's and GE's
  // Per method its values: a ours (sampled), b ARAP, m FFMP, g GE, c CCW16 (log derivatives), d CCW16 (boundary metric).
  struct Methods {
    const std::vector<double>&a, &b, &m, &g, &c, &d;
    const std::vector<double>& mesh_bound;  // the keyframes' envelope per triangle on the render mesh
  };
  auto distortion_plot = [&](const std::string& file, const std::string& what, const std::string& symbol, const Methods& v,
                             const std::vector<double>& bound, const std::vector<double>& a_cert, const std::vector<double>& bound_cert) {
    const std::vector<double>&a = v.a, &b = v.b, &c = v.c, &d = v.d;
    PlotSpec s;
    s.title = l.scene_name + ": largest " + what + " per frame, each method vs the keyframes'";
    s.xlabel = "t (keyframes at the dotted lines)";
    s.ylabel = "max " + symbol;
    s.x = p.t;
    s.series = {{"ours: certified bound over \xe2\x88\x82\xce\xa9", a_cert, 0.55, 0.7, 0.95, false, false, 4.0},
                {"keyframes: certified bound", bound_cert, 0.55, 0.55, 0.55, true, true, 2.4},
                {"ours (sampled at breakpoints on \xe2\x88\x82\xce\xa9)", a, 0.12, 0.35, 0.75, false, false, 2.2},
                {"ARAP (per triangle)", b, 0.9, 0.45, 0.05, false, false, 1.6},
                {"FFMP (per triangle)", v.m, kFfmpR, kFfmpG, kFfmpB, false, false, 1.6},
                {"GE (per triangle)", v.g, kGeR, kGeG, kGeB, false, false, 1.6},
                {ccw_name, c, 0.15, 0.6, 0.25, false, false, 1.6},
                {"keyframes (sampled)", bound, 0.1, 0.1, 0.1, true, true, 1.4},
                {"keyframes on the mesh (per triangle)", v.mesh_bound, 0.55, 0.35, 0.2, true, true, 1.2}};
    // Drawn first and wide, so that ours stays visible on top where the two coincide (Fig. 8).
    if (l.boundary_metric) s.series.insert(s.series.begin(), {bm_name, d, kBmR, kBmG, kBmB, false, false, 4.5});
    s.flagged = p.uncertified_t;
    s.unconverged = p.unconverged_t;
    s.x_marks = l.keyframe_times;
    s.y_scale = AxisScale::kAuto;
    auto folds = [](const std::vector<double>& x) { return std::any_of(x.begin(), x.end(), [](double y) { return std::isinf(y); }); };
    if (folds(b) || folds(v.m) || folds(v.g))
      s.note = "\xe2\x96\xb2 at the top: mesh-method frames with flipped triangles (distortion unbounded).  ";
    if (l.boundary_metric) s.note += "CCW16 (boundary metric) drawn wide under the others: it nearly coincides with ours.  ";
    if (!p.uncertified_t.empty()) s.note += "Red lines: frames of ours that could not be certified.  ";
    if (!p.unconverged_t.empty()) s.note += "Orange dashed: frames of ours whose Newton solve did not converge.";
    draw::plot_series(out.add(file), s);
  };
  distortion_plot("kappa.png", "conformal distortion \xce\xba = \xcf\x83\xe2\x82\x81/\xcf\x83\xe2\x82\x82", "\xce\xba",
                  {p.our_kappa, p.arap_kappa, p.ffmp_kappa, p.ge_kappa, p.ccw_kappa, p.bm_kappa, p.mesh_bound_kappa}, p.bound_kappa, p.our_kappa_c,
                  p.bound_kappa_c);
  distortion_plot("isometric.png", "isometric distortion (symmetric Dirichlet)", "E_SD",
                  {p.our_iso, p.arap_iso, p.ffmp_iso, p.ge_iso, p.ccw_iso, p.bm_iso, p.mesh_bound_iso}, p.bound_iso, p.our_iso_c, p.bound_iso_c);
  {
    PlotSpec s;
    s.title = l.scene_name + ": time per frame on this machine (" + std::to_string(l.mesh_vertices) + "-vertex mesh for the baselines)";
    s.xlabel.assign(1, 't');  // not `= "t"`: GCC 12 at -O3 misreads that as an overlapping memcpy (-Wrestrict)
    s.ylabel = "ms per frame";
    s.x = p.t;
    s.series = {{"ours: solve (" + l.core + ")", p.our_ms, 0.12, 0.35, 0.75, false, false, 2.0},
                {"ARAP: one sparse solve", p.arap_ms, 0.9, 0.45, 0.05, false, false, 1.6},
                {"FFMP: two sparse solves (one factorised per frame)", p.ffmp_ms, kFfmpR, kFfmpG, kFfmpB, false, false, 1.6},
                {"GE: Newton on the mesh", p.ge_ms, kGeR, kGeG, kGeB, false, false, 1.6},
                {"CCW16 (log derivatives): blend + integrate", p.ccw_ms, 0.15, 0.6, 0.25, false, false, 1.6}};
    if (l.boundary_metric)
      s.series.push_back({"CCW16 (boundary metric): fit + integrate" + bm_mesh_note, p.bm_ms, kBmR, kBmG, kBmB, false, false, 1.6});
    s.x_marks = l.keyframe_times;
    s.y_scale = AxisScale::kAuto;
    draw::plot_series(out.add("frame_time.png"), s);
  }
  if (!l.boundary_metric) return 3;
  // Fig. 8: how far each CCW16 variant is from our frame over the sequence, up to a rigid motion.
  PlotSpec s;
  s.title = l.scene_name + ": CCW16 against ours after the best rigid alignment (Fig. 8)";
  s.xlabel = "t (keyframes at the dotted lines)";
  s.ylabel = "max |f \xe2\x88\x92 f_ours| / size";
  s.x = p.t;
  // A keyframe reproduced exactly (distance at rounding level) has no place on a log axis.
  auto shown = [](std::vector<double> v) {
    for (double& x : v)
      if (x < 1e-9) x = std::numeric_limits<double>::quiet_NaN();
    return v;
  };
  s.series = {{"CCW16 (log derivatives)", shown(p.ccw_dist), 0.15, 0.6, 0.25, false, false, 1.8},
              {"CCW16 (boundary metric)" + bm_mesh_note, shown(p.bm_dist), kBmR, kBmG, kBmB, false, false, 1.8}};
  s.note = "Max over the mesh vertices; values below 1e-9 of the size (a keyframe reproduced exactly) are left out.";
  s.x_marks = l.keyframe_times;
  s.y_scale = AxisScale::kLog;
  draw::plot_series(out.add("ccw16_distance.png"), s);
  return 4;
}

}  // namespace hsi::compare
