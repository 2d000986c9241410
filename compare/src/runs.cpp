// hsi compare's runs: ours, ARAP, FFMP, GE, CCW16 and the timings (hsi/compare/runs.h).
#include "hsi/compare/runs.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_set>

#include "format.h"
#include "hsi/keyframes.h"

namespace hsi::compare {

void check_options(const Options& o) {
  if (o.panel < 96 || o.panel > 4096)
    throw InputError("--size: '" + std::to_string(o.panel) + "' is not a panel size between 96 and 4096 pixels");
  for (double r : o.ratios)
    if (!(r > 0 && r <= 1)) throw InputError("--ratios: " + std::to_string(r) + " is not a Hessian sample ratio in (0, 1]");
  for (int v : o.table3_vertices)
    if (v < 100 || v > 5'000'000) throw InputError("--table3-vertices: " + std::to_string(v) + " is outside 100..5000000");
  if (o.frames < 2) throw InputError("--frames: " + std::to_string(o.frames) + " is fewer than 2");
  if (o.table_frames < 2) throw InputError("--table-frames: " + std::to_string(o.table_frames) + " is fewer than 2");
  if (o.timing_frames < 1) throw InputError("--timing-frames: " + std::to_string(o.timing_frames) + " is fewer than 1");
  if (o.mesh_vertices < 100) throw InputError("--mesh-vertices: " + std::to_string(o.mesh_vertices) + " is fewer than 100");
  if (!(o.ccw16_memory_mb >= 1)) throw InputError("--ccw16-memory: " + std::to_string(o.ccw16_memory_mb) + " MB is below 1 MB");
}

Inputs prepare_inputs(const Options& o) {
  Inputs in;
  in.scene = load_scene(o.scene);
  in.scene_path = o.scene;
  if (in.scene.keyframes.size() < 2) throw InputError(o.scene + ": comparing needs at least two keyframes");
  const int segments = static_cast<int>(in.scene.keyframes.size()) - 1;
  if (o.segment < 0 || o.segment >= segments)
    throw InputError("--segment " + std::to_string(o.segment) + ": the scene has " + std::to_string(segments) +
                     " keyframe interval(s), 0.." + std::to_string(segments - 1));
  check_options(o);
  in.texture = scene_texture(in.scene, o.scene);
  for (int v : o.table3_vertices)
    if (!(o.no_800k && v >= 800'000)) in.table3.push_back(v);
  in.setup = scene_setup(in.scene, o.samples, 0);
  solve_scene_keyframes(in.scene, *in.setup);
  for (const Keyframe& k : in.scene.keyframes) {
    in.times.push_back(k.time);
    in.keys.push_back(*k.coefficients);
  }
  in.seg_t0 = in.times[static_cast<size_t>(o.segment)];
  in.seg_t1 = in.times[static_cast<size_t>(o.segment) + 1];
  in.t_mid = 0.5 * (in.seg_t0 + in.seg_t1);
  return in;
}

std::unique_ptr<NewtonCore> make_core(const Backends& b, const ShapeSetup& setup) {
  std::unique_ptr<NewtonCore> core = b.newton_core ? b.newton_core(setup) : nullptr;
  return core ? std::move(core) : make_cpu_newton_core(setup.D_G, setup.H);
}

OurSequence run_our_sequence(const Inputs& in, const Options& o) {
  OurSequence s;
  std::unique_ptr<NewtonCore> core = make_core(o.backends, *in.setup);
  s.core = core->name();
  s.interp = std::make_unique<Interpolator>(*in.setup, in.times, in.keys, InterpolationOptions{}, std::move(core));
  say(o.progress, false, "ours (%s): %d frames over the keyframes' range", s.core.c_str(), o.frames);
  const auto t0 = Clock::now();
  s.frames = s.interp->sequence(o.frames, [&](const FrameResult& f, int i, int n) {
    say(o.progress, true, "ours: frame %d/%d  t = %.4f  %d it  %.1f ms", i + 1, n, f.t, f.iterations, f.ms);
  });
  s.summary = summarize(s.frames, s_since(t0));
  for (const FrameResult& f : s.frames) s.within_bound += f.certified && f.bound_excess <= 1e-9;  // sampled against sampled
  say(o.progress, false, "ours (%s): %d frames, %d certified, %.2f iterations and %.1f ms per frame", s.core.c_str(),
      s.summary.frames, s.summary.certified, s.summary.mean_iterations, s.summary.mean_ms);
  return s;
}

OurRun run_ours(const std::string& label, const ShapeSetup& setup, const Inputs& in, HessianProjection projection,
                std::unique_ptr<NewtonCore> core, int frames, double ratio) {
  OurRun r;
  r.label = label;
  r.core = core->name();
  r.hessian_samples = static_cast<int>(setup.H.size());
  r.ratio = ratio;
  InterpolationOptions io;
  io.projection = projection;
  Interpolator interp(setup, in.times, in.keys, io, std::move(core));
  r.cold = interp.frame(in.t_mid);
  const auto t0 = Clock::now();
  const std::vector<FrameResult> seq = interp.sequence(frames);
  r.summary = summarize(seq, s_since(t0));
  for (const FrameResult& f : seq)
    if (!f.keyframe) r.max_iterations = std::max(r.max_iterations, f.iterations);
  return r;
}

std::vector<OurRun> run_table1(const Inputs& in, const Options& o, const std::string& main_core) {
  std::vector<OurRun> t;
  const ShapeSetup& setup = *in.setup;
  for (const HessianProjection proj : {HessianProjection::Delete, HessianProjection::FullProj, HessianProjection::PartProj}) {
    say(o.progress, false, "table 1: %s, %d frames ...", to_string(proj), o.table_frames);
    t.push_back(run_ours(to_string(proj), setup, in, proj, make_cpu_newton_core(setup.D_G, setup.H), o.table_frames,
                         in.scene.hessian_ratio));
    say(o.progress, false, "table 1: %s: %.2f iterations per frame", to_string(proj), t.back().summary.mean_iterations);
  }
  if (main_core != t.back().core) {
    const std::string label = std::string(to_string(HessianProjection::PartProj)) + " (" + main_core + ")";
    say(o.progress, false, "table 1: %s, %d frames ...", label.c_str(), o.table_frames);
    t.push_back(run_ours(label, setup, in, HessianProjection::PartProj, make_core(o.backends, setup), o.table_frames,
                         in.scene.hessian_ratio));
  }
  return t;
}

std::vector<OurRun> run_table2(Inputs& in, const Options& o) {
  std::vector<OurRun> t;
  for (const double r : o.ratios) {
    const std::shared_ptr<const ShapeSetup> sr = scene_setup(in.scene, o.samples, r);
    char label[32];
    std::snprintf(label, sizeof label, "r = %g", r);
    say(o.progress, false, "table 2: %s (|H| = %zu), %d frames ...", label, sr->H.size(), o.table_frames);
    t.push_back(run_ours(label, *sr, in, HessianProjection::PartProj, make_core(o.backends, *sr), o.table_frames, r));
    say(o.progress, false, "table 2: %s (|H| = %zu): %.2f iterations, %.1f ms per frame", label, sr->H.size(),
        t.back().summary.mean_iterations, t.back().summary.mean_ms);
  }
  return t;
}

std::vector<cd> map_points_chunked(const Cage& cage, const HarmonicMap& map, std::span<const cd> points) {
  constexpr size_t kChunk = 8192;  // 800k points × n columns would not fit in memory at once
  std::vector<cd> out;
  out.reserve(points.size());
  for (size_t i = 0; i < points.size(); i += kChunk) {
    const std::vector<cd> part = map_points(cage, map, points.subspan(i, std::min(kChunk, points.size() - i)));
    out.insert(out.end(), part.begin(), part.end());
  }
  return out;
}

TriMesh mesh_with(const Shape& shape, int vertices) {
  TriangulateOptions o;
  o.max_edge = edge_for_vertex_count(shape, vertices);
  return triangulate(shape, o);
}

// The C and D basis rows (2 × 16 bytes × m columns) at every vertex and at every Gauss node
// of every edge (`quadrature` nodes per piece of at most max_piece × size; ccw16.h), counted
// as it places them. ~300 MB at 10,000 vertices for a 32-vertex cage: hsi compare caps it.
double metric_rows_bytes(const TriMesh& mesh, int columns, const baselines::Ccw16Options& co, double size) {
  std::unordered_set<std::uint64_t> edges;
  const double h = co.max_piece * size;
  double points = mesh.vertex_count() + 1.0 + co.quadrature;  // + the anchor and its piece to the base vertex
  for (const auto& tri : mesh.triangles)
    for (int c = 0; c < 3; ++c) {
      const int u = tri[static_cast<size_t>(c)], v = tri[static_cast<size_t>((c + 1) % 3)];
      const auto key = (static_cast<std::uint64_t>(std::min(u, v)) << 32) | static_cast<std::uint32_t>(std::max(u, v));
      if (!edges.insert(key).second) continue;
      const double len = std::abs(mesh.vertices[static_cast<size_t>(u)] - mesh.vertices[static_cast<size_t>(v)]);
      points += co.quadrature * std::max(1.0, std::ceil(len / h));
    }
  return points * columns * 2.0 * sizeof(cd);
}

TriangleShape triangle_shape(const TriMesh& rest, std::span<const cd> positions) {
  TriangleShape s;
  s.det.assign(rest.triangles.size(), 0.0);
  s.turn.assign(rest.triangles.size(), 0.0);
  for (size_t t = 0; t < rest.triangles.size(); ++t) {
    const auto& v = rest.triangles[t];
    const cd z0 = rest.vertices[static_cast<size_t>(v[0])], w0 = positions[static_cast<size_t>(v[0])];
    const cd e1 = rest.vertices[static_cast<size_t>(v[1])] - z0, e2 = rest.vertices[static_cast<size_t>(v[2])] - z0;
    const cd d1 = positions[static_cast<size_t>(v[1])] - w0, d2 = positions[static_cast<size_t>(v[2])] - w0;
    // The affine map z ↦ f_z z + f_zbar z̄ taking the rest edges e1, e2 to d1, d2.
    const cd den = e1 * std::conj(e2) - e2 * std::conj(e1);
    if (std::abs(den) == 0) continue;
    const cd fz = (d1 * std::conj(e2) - d2 * std::conj(e1)) / den, fzbar = (e1 * d2 - e2 * d1) / den;
    s.det[t] = std::norm(fz) - std::norm(fzbar);
    s.turn[t] = std::arg(fz);
  }
  return s;
}

MeshKeyframes mesh_keyframes(const TriMesh& mesh, const std::vector<baselines::MeshKeyframe>& keys) {
  MeshKeyframes m;
  for (const auto& k : keys) {
    m.times.push_back(k.time);
    m.distortion.push_back(baselines::mesh_distortion(mesh, k.positions));
    m.shape.push_back(triangle_shape(mesh, k.positions));
  }
  for (size_t k = 0; k + 1 < m.shape.size(); ++k)
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
      m.max_turn = std::max(m.max_turn, std::abs(std::remainder(m.shape[k + 1].turn[t] - m.shape[k].turn[t], 2 * M_PI)));
  return m;
}

std::pair<size_t, size_t> MeshKeyframes::around(double t) const {
  size_t k = 0;
  while (k + 2 < times.size() && t > times[k + 1]) ++k;
  return {k, k + 1};
}
double MeshKeyframes::kappa_bound(double t) const {
  const auto [a, b] = around(t);
  return std::max(distortion[a].max_kappa, distortion[b].max_kappa);
}
double MeshKeyframes::iso_bound(double t) const {
  const auto [a, b] = around(t);
  return std::max(distortion[a].max_isometric, distortion[b].max_isometric);
}
double MeshKeyframes::area_shrink(double t, const TriangleShape& frame) const {
  const auto [a, b] = around(t);
  double worst = 0;
  for (size_t i = 0; i < frame.det.size(); ++i) {
    const double d = frame.det[i];
    if (!(d > 0)) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, std::min(shape[a].det[i], shape[b].det[i]) / d - 1);
  }
  return worst;
}

Baselines set_up_baselines(const Inputs& in, const Options& o) {
  Baselines b;
  const Cage& cage = in.setup->cage;
  const Shape& shape = in.scene.shape;
  say(o.progress, false, "baselines: meshing the shape (about %d vertices), setting up ARAP, FFMP, GE and CCW16 ...", o.mesh_vertices);
  b.mesh = mesh_with(shape, o.mesh_vertices);
  for (size_t k = 0; k < in.keys.size(); ++k)
    b.arap_keys.push_back({in.times[k], map_points_chunked(cage, in.keys[k], b.mesh.vertices)});
  b.keys_on_mesh = mesh_keyframes(b.mesh, b.arap_keys);
  // A baseline that refuses the keyframes (e.g. a keyframe that flips a triangle of
  // the mesh) stops the comparison with its reason and what to try.
  auto baseline = [&](const char* name, auto make) {
    try {
      return make();
    } catch (const InputError& e) {
      throw InputError(o.scene + ": the " + name + " baseline refuses this scene's keyframes on the " +
                       std::to_string(b.mesh.vertex_count()) + "-vertex mesh: " + e.what() +
                       (std::string(name) != "CCW16" ? " (a finer mesh, --mesh-vertices, may resolve a flipped triangle)" : ""));
    }
  };
  auto t0 = Clock::now();
  b.arap.emplace(baseline("ARAP", [&] { return baselines::ArapInterpolation(b.mesh, b.arap_keys); }));
  b.arap_setup_ms = ms_since(t0);
  t0 = Clock::now();
  b.ffmp.emplace(baseline("FFMP", [&] { return baselines::FfmpInterpolation(b.mesh, b.arap_keys); }));
  b.ffmp_setup_ms = ms_since(t0);
  t0 = Clock::now();
  b.ge.emplace(baseline("GE", [&] { return baselines::GeInterpolation(b.mesh, b.arap_keys); }));
  b.ge_setup_ms = ms_since(t0);
  std::vector<baselines::Ccw16Keyframe> ccw_keys;
  for (size_t k = 0; k < in.keys.size(); ++k) ccw_keys.push_back({in.times[k], in.keys[k]});
  t0 = Clock::now();
  b.ccw.emplace(baseline("CCW16", [&] { return baselines::Ccw16Interpolation(shape, cage, ccw_keys); }));
  b.ccw_mesh.emplace(b.ccw->prepare(b.mesh));
  b.ccw_setup_ms = ms_since(t0);
  say(o.progress, false,
      "render mesh %d vertices, %d triangles; set up in ms: ARAP %.0f, FFMP %.0f, GE %.0f, CCW16 (log derivatives) %.0f",
      b.mesh.vertex_count(), b.mesh.triangle_count(), b.arap_setup_ms, b.ffmp_setup_ms, b.ge_setup_ms, b.ccw_setup_ms);

  // CCW16's boundary-metric variant (the one the paper's Fig. 8 compares with): the metric
  // blended on the boundary, f_z and f_zbar rebuilt by a least-squares Hilbert transform.
  MetricVariant& bm = b.bm;
  const int holes = in.holes();
  if (holes > 0) {
    bm.why_not = "CCW16 (boundary metric) does not apply to multiply-connected domains (paper \xc2\xa7" "1): its Hilbert "
                 "transform recovers a single-valued log f_z from its real part only on a simply-connected domain, and this "
                 "shape has " + std::to_string(holes) + (holes == 1 ? " hole" : " holes");
    say(o.progress, false, "%s; only CCW16 (log derivatives) is compared", bm.why_not.c_str());
  } else {
    bm.applies = true;
    baselines::Ccw16Options bco;
    bco.variant = baselines::Ccw16Variant::BoundaryMetric;
    const double budget = o.ccw16_memory_mb * 1024.0 * 1024.0;
    double bytes = metric_rows_bytes(b.mesh, cage.vertex_count(), bco, in.size());
    bm.render_mesh_mb = bytes / (1024.0 * 1024.0);
    // Coarser meshes until the rows fit (the mesher's vertex count is only roughly the one asked for).
    int target = b.mesh.vertex_count();
    for (int tries = 0; bytes > budget && tries < 8 && target > 100; ++tries) {
      target = std::max(100, static_cast<int>(0.92 * target * budget / bytes));
      bm.coarse = mesh_with(shape, target);
      bm.own_mesh = true;
      bytes = metric_rows_bytes(bm.coarse, cage.vertex_count(), bco, in.size());
    }
    bm.mb = bytes / (1024.0 * 1024.0);
    say(o.progress, false, "CCW16 (boundary metric): setting up on a %d-vertex mesh ...", b.bm_mesh().vertex_count());
    t0 = Clock::now();
    bm.interp.emplace(baseline("CCW16 (boundary metric)", [&] { return baselines::Ccw16Interpolation(shape, cage, ccw_keys, bco); }));
    bm.prepared.emplace(bm.interp->prepare(b.bm_mesh()));
    bm.setup_ms = ms_since(t0);
    say(o.progress, false,
        "CCW16 (boundary metric) on %s%d-vertex mesh (%.0f MB of basis rows; %.0f MB on the render mesh, --ccw16-memory %.0f MB), set up in %.0f ms",
        bm.own_mesh ? "a coarser " : "the ", b.bm_mesh().vertex_count(), bm.mb, bm.render_mesh_mb, o.ccw16_memory_mb, bm.setup_ms);
  }

  // ARAP reproduces its keyframes (a check of the baseline as we run it).
  for (const auto& k : b.arap_keys) {
    const std::vector<cd> p = b.arap->positions(k.time);
    for (size_t i = 0; i < p.size(); ++i) b.arap_key_error = std::max(b.arap_key_error, std::abs(p[i] - k.positions[i]) / in.size());
  }
  return b;
}

std::vector<baselines::GeFrame> run_ge_sequence(const std::vector<FrameResult>& ours, const Baselines& b, const Progress& progress) {
  std::vector<double> ts;
  for (const FrameResult& f : ours) ts.push_back(f.t);
  say(progress, false, "GE over the sequence: %zu frames on the %d-vertex mesh, each warm-started from the previous one ...", ts.size(),
      b.mesh.vertex_count());
  std::vector<baselines::GeFrame> ge = b.ge->sequence(ts, [&](const baselines::GeFrame& f, int i, int n) {
    say(progress, true, "GE: frame %d/%d  t = %.4f  %d it  %.0f ms%s", i + 1, n, f.time, f.iterations, f.ms,
        f.converged ? "" : "  NOT CONVERGED");
  });
  double ms = 0, it = 0;
  int not_converged = 0;
  for (const baselines::GeFrame& f : ge) ms += f.ms, it += f.iterations, not_converged += !f.converged;
  say(progress, false, "GE over the sequence: %.2f iterations and %.0f ms per frame, %d frame(s) not converged",
      it / static_cast<double>(ge.size()), ms / static_cast<double>(ge.size()), not_converged);
  return ge;
}

PerFrame measure_sequence(const Inputs& in, const std::vector<FrameResult>& ours, const Baselines& b,
                          const std::vector<baselines::GeFrame>& ge, const Progress& progress) {
  const size_t F = ours.size();
  if (ge.size() != F) throw std::logic_error("measure_sequence: GE has " + std::to_string(ge.size()) + " frames, ours " + std::to_string(F));
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const Cage& cage = in.setup->cage;
  const double size = in.size();
  const MeshKeyframes& keys = b.keys_on_mesh;
  PerFrame p;
  for (auto* v : {&p.t, &p.our_kappa, &p.our_iso, &p.bound_kappa, &p.bound_iso, &p.our_ms, &p.our_iters, &p.our_kappa_c,
                  &p.our_iso_c, &p.bound_kappa_c, &p.bound_iso_c, &p.mesh_bound_kappa, &p.mesh_bound_iso, &p.ours_mesh_kappa,
                  &p.ours_mesh_iso, &p.ours_mesh_shrink, &p.arap_kappa, &p.arap_iso, &p.arap_ms, &p.arap_flipped, &p.arap_shrink,
                  &p.ffmp_kappa, &p.ffmp_iso, &p.ffmp_ms, &p.ffmp_flipped, &p.ffmp_shrink, &p.ge_kappa, &p.ge_iso, &p.ge_ms,
                  &p.ge_iters, &p.ge_flipped, &p.ge_shrink, &p.ge_converged, &p.ge_dist, &p.ccw_kappa, &p.ccw_iso, &p.ccw_ms,
                  &p.ccw_period})
    v->resize(F);
  for (auto* v : {&p.bm_kappa, &p.bm_iso, &p.bm_ms, &p.bm_fit, &p.ccw_dist, &p.bm_dist}) v->assign(F, nan);
  p.keyframe.resize(F);
  say(progress, false, "baselines over the sequence: ARAP, FFMP and CCW16 at %zu frames ...", F);
  // A mesh method's frame: its largest per-triangle distortion, flips and shrinking.
  struct MeshFrame {
    double kappa, iso, flipped, area;
  };
  auto on_mesh = [&](double t, const std::vector<cd>& pos) {
    const baselines::MeshDistortion d = baselines::mesh_distortion(b.mesh, pos);
    return MeshFrame{d.max_kappa, d.max_isometric, static_cast<double>(d.flipped), keys.area_shrink(t, triangle_shape(b.mesh, pos))};
  };
  for (size_t i = 0; i < F; ++i) {
    const FrameResult& f = ours[i];
    p.t[i] = f.t;
    p.keyframe[i] = f.keyframe;
    p.our_kappa[i] = f.certified ? f.distortion.conformal_max : inf;
    p.our_iso[i] = f.certified ? f.distortion.isometric_max : inf;
    p.bound_kappa[i] = f.bound.conformal_max;
    p.bound_iso[i] = f.bound.isometric_max;
    p.our_kappa_c[i] = f.distortion_certified.conformal_max;
    p.our_iso_c[i] = f.distortion_certified.isometric_max;
    p.bound_kappa_c[i] = f.certified_bound.conformal_max;
    p.bound_iso_c[i] = f.certified_bound.isometric_max;
    p.our_ms[i] = f.keyframe ? nan : f.ms;
    p.our_iters[i] = f.iterations;
    if (!f.certified) p.uncertified_t.push_back(f.t);
    if (!f.converged) p.unconverged_t.push_back(f.t);
    p.mesh_bound_kappa[i] = keys.kappa_bound(f.t);
    p.mesh_bound_iso[i] = keys.iso_bound(f.t);
    const std::vector<cd> ours_at = map_points_chunked(cage, f.map, b.mesh.vertices);
    const MeshFrame om = on_mesh(f.t, ours_at);
    p.ours_mesh_kappa[i] = om.kappa;
    p.ours_mesh_iso[i] = om.iso;
    p.ours_mesh_shrink[i] = om.area;

    auto t0 = Clock::now();
    const std::vector<cd> pos = b.arap->positions(f.t);
    p.arap_ms[i] = ms_since(t0);
    const MeshFrame a = on_mesh(f.t, pos);
    p.arap_kappa[i] = a.kappa, p.arap_iso[i] = a.iso, p.arap_flipped[i] = a.flipped, p.arap_shrink[i] = a.area;
    t0 = Clock::now();
    const std::vector<cd> fp = b.ffmp->positions(f.t);
    p.ffmp_ms[i] = ms_since(t0);
    const MeshFrame m = on_mesh(f.t, fp);
    p.ffmp_kappa[i] = m.kappa, p.ffmp_iso[i] = m.iso, p.ffmp_flipped[i] = m.flipped, p.ffmp_shrink[i] = m.area;
    const MeshFrame g = on_mesh(f.t, ge[i].positions);
    p.ge_kappa[i] = g.kappa, p.ge_iso[i] = g.iso, p.ge_flipped[i] = g.flipped, p.ge_shrink[i] = g.area;
    p.ge_ms[i] = f.keyframe ? nan : ge[i].ms;  // at a keyframe ours is the keyframe itself, unsolved: neither is timed there
    p.ge_iters[i] = ge[i].iterations;
    p.ge_converged[i] = ge[i].converged;
    p.ge_dist[i] = point_gap(ge[i].positions, ours_at, size).rigid;

    t0 = Clock::now();
    const baselines::Ccw16Frame c = b.ccw->frame(f.t, *b.ccw_mesh);
    p.ccw_ms[i] = ms_since(t0);
    p.ccw_kappa[i] = c.max_kappa;
    p.ccw_iso[i] = c.max_isometric;
    p.ccw_period[i] = c.hole_period.empty() ? 0.0 : max_of(c.hole_period) / size;
    if (b.bm.applies) {
      t0 = Clock::now();
      const baselines::Ccw16Frame bmf = b.bm.interp->frame(f.t, *b.bm.prepared);
      p.bm_ms[i] = ms_since(t0);
      p.bm_kappa[i] = bmf.max_kappa;
      p.bm_iso[i] = bmf.max_isometric;
      p.bm_fit[i] = bmf.fit_metric;
      p.ccw_dist[i] = point_gap(c.positions, ours_at, size).rigid;
      p.bm_dist[i] = point_gap(bmf.positions, b.bm.own_mesh ? map_points_chunked(cage, f.map, b.bm.coarse.vertices) : ours_at, size).rigid;
    }
    say(progress, true, "baselines: frame %zu/%zu", i + 1, F);
  }
  say(progress, false,
      "baselines over the sequence, ms per frame (frames with folds): ARAP %.1f (%d), FFMP %.1f (%d), GE %.1f (%d); CCW16 (log derivatives) %.1f",
      mean_of(p.arap_ms), count_positive(p.arap_flipped), mean_of(p.ffmp_ms), count_positive(p.ffmp_flipped), mean_of(p.ge_ms), count_positive(p.ge_flipped),
      mean_of(p.ccw_ms));
  if (b.bm.applies)
    say(progress, false, "CCW16 (boundary metric): %.1f ms per frame; after rigid alignment within %.2e of the size of ours (log derivatives: %.2e)",
        mean_of(p.bm_ms), max_of(p.bm_dist), max_of(p.ccw_dist));
  return p;
}

std::vector<Snapshot> snapshots(const Inputs& in, const OurSequence& ours, const Baselines& b, const std::vector<baselines::GeFrame>& ge) {
  const Cage& cage = in.setup->cage;
  const std::vector<FrameResult>& seq = ours.frames;
  std::vector<Snapshot> snaps;
  for (const double u : {0.25, 0.5, 0.75}) {
    Snapshot s;
    s.u = u;
    s.t = in.seg_t0 + u * (in.seg_t1 - in.seg_t0);
    // Warm-started from the sequence's frame just before t, as playback would be.
    size_t j = 0;
    for (size_t i = 0; i < seq.size(); ++i)
      if (seq[i].t <= s.t) j = i;
    s.ours = ours.interp->frame(s.t, seq[j].x, &seq[j].certificate);
    s.ours_pos = map_points_chunked(cage, s.ours.map, b.mesh.vertices);
    s.arap_pos = b.arap->positions(s.t);
    s.arap_d = baselines::mesh_distortion(b.mesh, s.arap_pos);
    s.ffmp_pos = b.ffmp->positions(s.t);
    s.ffmp_d = baselines::mesh_distortion(b.mesh, s.ffmp_pos);
    const baselines::GeFrame g = b.ge->frame(s.t, ge[j].positions);
    s.ge_pos = g.positions;
    s.ge_iterations = g.iterations;
    s.ge_converged = g.converged;
    s.ge_d = baselines::mesh_distortion(b.mesh, s.ge_pos);
    s.ge_gap = point_gap(s.ge_pos, s.ours_pos, in.size());
    s.ccw = b.ccw->frame(s.t, *b.ccw_mesh);
    s.gap = point_gap(s.ccw.positions, s.ours_pos, in.size());
    if (b.bm.applies) {
      s.bm = b.bm.interp->frame(s.t, *b.bm.prepared);
      s.bm_gap = point_gap(s.bm.positions, b.bm.own_mesh ? map_points_chunked(cage, s.ours.map, b.bm.coarse.vertices) : s.ours_pos,
                           in.size());
    }
    snaps.push_back(std::move(s));
  }
  return snaps;
}

std::unique_ptr<MeshEvaluator> make_mesh_evaluator(const Backends& b, const Cage& cage, std::span<const cd> points) {
  std::unique_ptr<MeshEvaluator> e = b.mesh_evaluator ? b.mesh_evaluator(cage, points) : nullptr;
  return e ? std::move(e) : make_cpu_mesh_evaluator(cage, points);
}

std::string OurTiming::describe() const {
  char buf[640];
  std::snprintf(buf, sizeof buf,
                "timed in one block: %d warm-up frames (not timed), then the sequence's %d solved frames back to back, each "
                "solve followed by f at the render mesh's vertices from cached basis rows on %s (the rows evaluated once per "
                "mesh, %.0f ms), nothing else in between",
                warmup, frames, evaluator == "cpu" ? "the CPU" : evaluator == "cuda" ? "the GPU (CUDA)" : evaluator.c_str(),
                eval_setup_ms);
  std::string s = buf;
  if (!clocks_after.empty()) s += "; GPU clocks before the warm-up: " + clocks_before + "; after the block: " + clocks_after;
  return s;
}

OurTiming time_ours(const Inputs& in, const OurSequence& ours, const TriMesh& mesh, const Options& o) {
  constexpr int kWarmup = 10;
  OurTiming r;
  const Cage& cage = in.setup->cage;
  Interpolator& interp = *ours.interp;
  auto t0 = Clock::now();
  const std::unique_ptr<MeshEvaluator> ev = make_mesh_evaluator(o.backends, cage, mesh.vertices);
  r.eval_setup_ms = ms_since(t0);
  r.evaluator = ev->name();
  auto clocks = [&] { return o.backends.gpu_clocks ? o.backends.gpu_clocks() : std::string(); };
  r.clocks_before = clocks();
  say(o.progress, false, "ours timed for Tables 3-4: %d warm-up frames, then %d frames in one block (solve + f at %d vertices on %s)",
      std::min(kWarmup, o.frames), o.frames, mesh.vertex_count(), r.evaluator.c_str());
  MapValues v;
  // Warm-up: the sequence's first frames, solved and evaluated as in the block, not timed.
  std::vector<double> warm;
  for (int i = 0; i < std::min(kWarmup, o.frames); ++i)
    warm.push_back(interp.t_begin() + (interp.t_end() - interp.t_begin()) * i / (o.frames - 1));
  for (const FrameResult& f : interp.sequence(warm, [&](const FrameResult& g, int, int) { ev->evaluate(g.map, v); }))
    r.warmup += !f.keyframe;
  // The block: no progress lines, nothing but our frames.
  std::vector<double> eval(static_cast<size_t>(o.frames), 0.0);
  const std::vector<FrameResult> frames = interp.sequence(o.frames, [&](const FrameResult& f, int i, int) {
    const auto te = Clock::now();
    ev->evaluate(f.map, v);
    eval[static_cast<size_t>(i)] = ms_since(te);
  });
  r.clocks_after = clocks();
  std::vector<const HarmonicMap*> solved;
  for (size_t i = 0; i < frames.size(); ++i) {
    if (frames[i].keyframe) continue;
    solved.push_back(&frames[i].map);
    r.solve_ms += frames[i].ms;
    r.eval_ms += eval[i];
    r.iterations += frames[i].iterations;
  }
  r.frames = static_cast<int>(solved.size());
  const double n = std::max(1.0, static_cast<double>(r.frames));
  r.solve_ms /= n;
  r.eval_ms /= n;
  r.iterations /= n;
  r.eval_cpu_ms = r.eval_ms;
  if (r.evaluator != "cpu" && !solved.empty()) {  // the CPU evaluator at the same maps, after the block
    const std::unique_ptr<MeshEvaluator> cpu = make_cpu_mesh_evaluator(cage, mesh.vertices);
    cpu->evaluate(*solved.front(), v);
    r.eval_cpu_ms = 0;
    for (const HarmonicMap* m : solved) {
      t0 = Clock::now();
      cpu->evaluate(*m, v);
      r.eval_cpu_ms += ms_since(t0) / n;
    }
  }
  say(o.progress, false, "ours in one block: solve %.2f ms + f at the vertices %.3f ms (%s) per frame, %.2f iterations%s%s",
      r.solve_ms, r.eval_ms, r.evaluator.c_str(), r.iterations, r.clocks_after.empty() ? "" : "; GPU ", r.clocks_after.c_str());
  return r;
}
namespace {
// The keyframe nearest time t.
size_t nearest_keyframe(const std::vector<baselines::MeshKeyframe>& keys, double t) {
  size_t k = 0;
  for (size_t j = 1; j < keys.size(); ++j)
    if (std::abs(keys[j].time - t) < std::abs(keys[k].time - t)) k = j;
  return k;
}
}  // namespace

std::vector<size_t> timed_frames(size_t frames, int timing_frames) {
  std::vector<size_t> timed;
  for (int k = 0; k < timing_frames; ++k)
    timed.push_back(static_cast<size_t>(k + 1) * (frames - 1) / static_cast<size_t>(timing_frames + 1));
  return timed;
}

std::string ge_not_run_note(int vertices, int max_vertices, const std::vector<Table3Row>& rows) {
  // GE's cost per frame grows about linearly with the mesh (one sparse Cholesky of 2n
  // unknowns per iteration, same iterations): the estimate scales the largest row it ran at.
  const Table3Row* ran = nullptr;
  for (const Table3Row& r : rows)
    if (r.ge_not_run.empty() && std::isfinite(r.ge_ms) && (!ran || r.vertices > ran->vertices)) ran = &r;
  std::string note = "not run: above " + std::to_string(max_vertices) + " vertices (--ge-max-vertices)";
  if (ran) {
    char b[160];
    std::snprintf(b, sizeof b, "; est. %.0f s/frame (%d-vertex row \xc3\x97 %.1f)", ran->ge_ms / 1000.0 * vertices / ran->vertices,
                  ran->vertices, static_cast<double>(vertices) / ran->vertices);
    note += b;
  }
  return note;
}

baselines::GeFrame ge_cold_frame(const Inputs& in, const Baselines& b, int segment) {
  return b.ge->frame(in.t_mid, b.arap_keys[static_cast<size_t>(segment)].positions);
}

// Ours: the solve does not see the mesh; a frame at the mesh costs the solve plus f at
// its vertices. ARAP: one sparse solve per frame on the mesh, after a factorisation. GE:
// Newton on the mesh, warm-started (below).
std::vector<Table3Row> run_table3(const Inputs& in, const std::vector<FrameResult>& ours, const std::vector<size_t>& timed,
                                  const Options& o) {
  const Backends& backends = o.backends;
  const Progress& progress = o.progress;
  const Cage& cage = in.setup->cage;
  std::vector<Table3Row> rows;
  for (int v : in.table3) {
    Table3Row row{};
    say(progress, false, "table 3: meshing the shape at about %d vertices ...", v);
    auto t0 = Clock::now();
    const TriMesh m = mesh_with(in.scene.shape, v);
    row.mesh_s = s_since(t0);
    row.vertices = m.vertex_count();
    row.triangles = m.triangle_count();
    say(progress, false, "table 3: ARAP at %d vertices: factorising, then %zu frame(s) ...", row.vertices, timed.size());
    std::vector<baselines::ArapKeyframe> ak;
    for (size_t k = 0; k < in.keys.size(); ++k) ak.push_back({in.times[k], map_points_chunked(cage, in.keys[k], m.vertices)});
    t0 = Clock::now();
    const baselines::ArapInterpolation a(m, ak);
    row.arap_factor_ms = ms_since(t0);
    // Ours: f at the vertices from rows cached once per mesh, on the CPU and on the
    // backend's evaluator where that is not the CPU; one untimed evaluation each first.
    t0 = Clock::now();
    const std::unique_ptr<MeshEvaluator> cpu_eval = make_cpu_mesh_evaluator(cage, m.vertices);
    row.ours_eval_setup_ms = ms_since(t0);
    std::unique_ptr<MeshEvaluator> backend_eval = backends.mesh_evaluator ? backends.mesh_evaluator(cage, m.vertices) : nullptr;
    if (backend_eval && std::string(backend_eval->name()) == "cpu") backend_eval.reset();
    MapValues values;
    cpu_eval->evaluate(ours[timed.front()].map, values);
    if (backend_eval) backend_eval->evaluate(ours[timed.front()].map, values);
    double arap_sum = 0, cpu_sum = 0, gpu_sum = 0, cuda_sum = 0;
    for (size_t i : timed) {
      t0 = Clock::now();
      const std::vector<cd> p = a.positions(ours[i].t);
      arap_sum += ms_since(t0);
      t0 = Clock::now();
      cpu_eval->evaluate(ours[i].map, values);
      cpu_sum += ms_since(t0);
      if (p.size() != static_cast<size_t>(values.f.size())) throw std::logic_error("table 3: sizes disagree");
      if (backend_eval) {
        t0 = Clock::now();
        backend_eval->evaluate(ours[i].map, values);
        cuda_sum += ms_since(t0);
      }
      if (backends.dense_eval) {
        t0 = Clock::now();
        const size_t n = backends.dense_eval(cage, ours[i].map, m.vertices);
        gpu_sum += ms_since(t0);
        if (n != p.size()) throw std::logic_error("table 3: sizes disagree");
      }
    }
    const double n = static_cast<double>(timed.size());
    row.arap_ms = arap_sum / n;
    row.ours_eval_cpu_ms = cpu_sum / n;
    if (backend_eval) row.ours_eval_cuda_ms = cuda_sum / n;
    row.ours_eval_gpu_ms = backends.dense_eval ? gpu_sum / n : std::numeric_limits<double>::quiet_NaN();
    say(progress, false,
        "table 3: %d vertices: ARAP factorisation %.0f ms, %.1f ms per frame; ours f at the vertices from cached rows %.3f ms (CPU), "
        "%.3f ms (CUDA); basis per frame %.1f ms (Vulkan)",
        row.vertices, row.arap_factor_ms, row.arap_ms, row.ours_eval_cpu_ms, row.ours_eval_cuda_ms, row.ours_eval_gpu_ms);
    if (row.vertices > o.ge_max_vertices) {
      row.ge_not_run = ge_not_run_note(row.vertices, o.ge_max_vertices, rows);
      say(progress, false, "table 3: GE at %d vertices %s", row.vertices, row.ge_not_run.c_str());
    } else {
      // Each timed frame warm-started from GE's own frame at the sequence's previous time,
      // which is solved (untimed) from our frame there: as in a played sequence, without
      // solving the whole sequence at every resolution.
      say(progress, false, "table 3: GE at %d vertices, %zu frame(s) ...", row.vertices, timed.size());
      const baselines::GeInterpolation ge(m, ak);
      double ms = 0, it = 0;
      for (size_t i : timed) {
        const size_t prev = i > 0 ? i - 1 : i;
        std::vector<cd> start = map_points_chunked(cage, ours[prev].map, m.vertices);
        if (baselines::mesh_distortion(m, start).flipped > 0) start = ak[nearest_keyframe(ak, ours[prev].t)].positions;
        const baselines::GeFrame primed = ge.frame(ours[prev].t, start);
        const baselines::GeFrame g = ge.frame(ours[i].t, primed.positions);
        ms += g.ms;
        it += g.iterations;
        row.ge_not_converged += !g.converged;
      }
      row.ge_ms = ms / n;
      row.ge_iterations = it / n;
      say(progress, false, "table 3: GE at %d vertices: %.0f ms and %.1f iterations per frame%s", row.vertices, row.ge_ms,
          row.ge_iterations, row.ge_not_converged ? ", NOT CONVERGED in some frames" : "");
    }
    rows.push_back(row);
  }
  return rows;
}

}  // namespace hsi::compare
