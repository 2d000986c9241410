// hsi compare SCENE -o DIR/: the paper's claims reproduced on one scene against the
// baselines (issue #11), measured in one run on this machine. Our method (certified
// harmonic interpolation), ARAP [ACOL00] on the render mesh and CCW16 (derivative
// blending + integration) in its two variants: log derivatives (log f_z and ν blended
// pointwise; breaks on shapes with holes: the paper's Fig. 2) and, on simply-connected
// shapes only (paper §1), boundary metric (the metric blended on ∂Ω, f_z and f_zbar by a
// least-squares Hilbert transform: the paper's Fig. 8). Side by side with the distortion
// colour map at t = 0.25, 0.5, 0.75 of a keyframe interval; each method's largest
// conformal and isometric distortion over the whole sequence against the keyframes'
// bounds (Figs 3–5); Tables 1–4 (Hessian projections, the Hessian sample ratio r, time
// against the render mesh's resolution, per-frame time against ARAP); CCW16's hole
// periods (Fig. 2) or both variants' distance to ours (Fig. 8).
// Writes PNGs, report.json with the raw numbers, and report.md last.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>
#include <unordered_set>

#include "commands.h"
#include "hsi/machine.h"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/scene_io.h"
#include "hsi/scene_sequence.h"
#include "hsi/triangulate.h"
#include "hsi/draw/plot.h"
#ifdef HSI_WITH_CUDA
#include "hsi/cuda/newton_core.h"
#endif

#if defined(HSI_WITH_VULKAN) && defined(HSI_WITH_BASELINES)
#define HSI_COMPARE 1
#include <cairo.h>

#include "hsi/baselines/arap.h"
#include "hsi/baselines/ccw16.h"
#include "hsi/compute/dense_eval.h"
#include "hsi/compute/renderer.h"
#include "hsi/draw/raster.h"
#endif

namespace hsi::cli {

#ifdef HSI_COMPARE
namespace {

using namespace hsi::draw;

using Clock = std::chrono::steady_clock;
using nlohmann::json;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
double s_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct Opts {
  std::string scene, out;
  int frames = 100, table_frames = 40, mesh_vertices = 10000, samples = 0, timing_frames = 3, segment = 0;
  double ccw16_memory_mb = 128;  // most the CCW16 boundary-metric variant may hold in basis rows
  std::string size = "420";
  std::vector<double> ratios = {1.0, 0.5, 0.2, 0.1, 0.05};
  std::vector<int> table3_vertices = {8000, 80000, 800000};
  bool no_800k = false, validation = false;
  std::string backend = "auto", device;
};

// Progress on stderr, one line per step (a full run takes minutes on a laptop CPU).
__attribute__((format(printf, 2, 3))) void stage(Clock::time_point t0, const char* f, ...) {
  va_list ap;
  va_start(ap, f);
  std::fprintf(stderr, "[compare %6.1f s] ", s_since(t0));
  std::vfprintf(stderr, f, ap);
  std::fprintf(stderr, "\n");
  std::fflush(stderr);
  va_end(ap);
}


std::string fixed(double v, int digits) {
  if (std::isnan(v)) return "n/a";
  if (std::isinf(v)) return v > 0 ? "∞" : "−∞";
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}
std::string sci(double v) {
  if (std::isnan(v)) return "n/a";
  if (std::isinf(v)) return v > 0 ? "∞" : "−∞";
  char b[64];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}
// JSON has no infinity: +inf (a folded frame) is written as the string "inf".
json num(double v) { return std::isfinite(v) ? json(v) : json(std::isnan(v) ? "nan" : v > 0 ? "inf" : "-inf"); }
json nums(const std::vector<double>& v) {
  json a = json::array();
  for (double x : v) a.push_back(num(x));
  return a;
}
double max_of(const std::vector<double>& v) {
  double m = -std::numeric_limits<double>::infinity();
  for (double x : v)
    if (!std::isnan(x)) m = std::max(m, x);
  return m;
}
double mean_of(const std::vector<double>& v) {
  double s = 0;
  int n = 0;
  for (double x : v)
    if (std::isfinite(x)) s += x, ++n;
  return n ? s / n : std::numeric_limits<double>::quiet_NaN();
}

// f of a map at many points, in chunks so that the basis rows stay small (800k
// points × n columns would not fit in memory at once).
std::vector<cd> map_points_chunked(const Cage& cage, const HarmonicMap& map, std::span<const cd> points) {
  constexpr size_t kChunk = 8192;
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

// Bytes that CCW16's boundary-metric variant holds once prepare()d on a mesh: the C and D
// basis rows (2 × 16 bytes × m columns) at every vertex and at every Gauss node of every
// edge (`quadrature` nodes per piece of at most max_piece × size; ccw16.h), counted as it
// places them. ~300 MB at 10,000 vertices for a 32-vertex cage: hsi compare caps it.
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

void grow(BoundingBox& b, cd p) {
  if (!std::isfinite(p.real()) || !std::isfinite(p.imag())) return;
  b.lo = {std::min(b.lo.real(), p.real()), std::min(b.lo.imag(), p.imag())};
  b.hi = {std::max(b.hi.real(), p.real()), std::max(b.hi.imag(), p.imag())};
}

// max |a_i − b_i| as given, and after the best rigid motion of a onto b (2D
// Procrustes: b ≈ r a + c, |r| = 1), both relative to `size`.
struct Gap {
  double raw = 0, rigid = 0;
};
Gap point_gap(std::span<const cd> a, std::span<const cd> b, double size) {
  Gap g;
  cd ma = 0, mb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    g.raw = std::max(g.raw, std::abs(a[i] - b[i]));
    ma += a[i];
    mb += b[i];
  }
  ma /= static_cast<double>(a.size());
  mb /= static_cast<double>(b.size());
  cd s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += (b[i] - mb) * std::conj(a[i] - ma);
  const cd r = std::abs(s) > 0 ? s / std::abs(s) : cd(1, 0);
  for (size_t i = 0; i < a.size(); ++i) g.rigid = std::max(g.rigid, std::abs(r * (a[i] - ma) - (b[i] - mb)));
  g.raw /= size;
  g.rigid /= size;
  return g;
}

// Fig. 8: one CCW16 variant's distance to our frames (relative to the size): the largest over
// the side-by-side times as is and after rigid alignment, and over the whole sequence.
struct Fig8 {
  double raw = 0, rigid = 0;
  double sequence_rigid = std::numeric_limits<double>::quiet_NaN(), sequence_t = std::numeric_limits<double>::quiet_NaN();
  double between_keyframes_rigid = std::numeric_limits<double>::quiet_NaN();  // the same without the keyframes' frames
};

// One of our sequences (a projection, a Hessian ratio) with what the tables report.
struct OurRun {
  std::string label;
  std::string core;
  int hessian_samples = 0;
  double ratio = 0;
  std::vector<FrameResult> frames;
  FrameResult cold;  // the segment's middle frame solved from its first keyframe (the paper's Table 1 setting)
  SequenceSummary summary;
  int max_iterations = 0;
};

// Files this run wrote, removed again if it fails, so that nothing is left that looks
// like a finished report (report.md is written last in any case).
class Outputs {
 public:
  explicit Outputs(std::filesystem::path dir) : dir_(std::move(dir)) {}
  ~Outputs() {
    if (committed_) return;
    for (const auto& p : written_) {
      std::error_code ec;
      std::filesystem::remove(p, ec);
    }
    if (created_) {
      std::error_code ec;
      std::filesystem::remove(dir_, ec);  // only if empty
    }
  }
  void open() {
    if (std::filesystem::exists(dir_) && !std::filesystem::is_directory(dir_))
      throw InputError("-o " + dir_.string() + ": exists and is not a folder");
    created_ = std::filesystem::create_directories(dir_);
    // A report from an earlier run must not pass for this one's if this one fails.
    // Nor may an earlier run's Fig. 8 plot stay next to a report of a shape with holes.
    for (const char* stale : {"report.md", "report.json", "ccw16_distance.png"}) std::filesystem::remove(dir_ / stale);
  }
  std::filesystem::path add(const std::string& name) {
    written_.push_back(dir_ / name);
    return dir_ / name;
  }
  void commit() { committed_ = true; }
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  std::vector<std::filesystem::path> written_;
  bool created_ = false, committed_ = false;
};

// The Newton core for our solves: the CUDA twin where asked for (or, with auto, where a
// device is present), else the CPU reference.
std::unique_ptr<NewtonCore> make_core(const ShapeSetup& setup, const std::string& backend) {
  std::unique_ptr<NewtonCore> core;
  std::string why = "this hsi was built without CUDA";
#ifdef HSI_WITH_CUDA
  if (backend != "cpu" && hsi::cuda::device_available(&why)) core = hsi::cuda::make_newton_core(setup);
#endif
  if (!core && backend == "cuda") throw std::runtime_error("--backend cuda: no CUDA device (" + why + ")");
  if (!core) core = make_cpu_newton_core(setup.D_G, setup.H);
  return core;
}

OurRun run_ours(const std::string& label, const ShapeSetup& setup, const std::vector<double>& times,
                const std::vector<HarmonicMap>& keys, HessianProjection projection, std::unique_ptr<NewtonCore> core,
                int frames, double t_mid, double ratio) {
  OurRun r;
  r.label = label;
  r.core = core->name();
  r.hessian_samples = static_cast<int>(setup.H.size());
  r.ratio = ratio;
  InterpolationOptions io;
  io.projection = projection;
  Interpolator interp(setup, times, keys, io, std::move(core));
  r.cold = interp.frame(t_mid);
  const auto t0 = Clock::now();
  r.frames = interp.sequence(frames);
  r.summary = summarize(r.frames, s_since(t0));
  for (const FrameResult& f : r.frames)
    if (!f.keyframe) r.max_iterations = std::max(r.max_iterations, f.iterations);
  return r;
}

json run_json(const OurRun& r) {
  return {{"label", r.label},
          {"newton_core", r.core},
          {"hessian_ratio", r.ratio},
          {"hessian_samples", r.hessian_samples},
          {"cold_iterations", r.cold.iterations},
          {"cold_ms", r.cold.ms},
          {"cold_certified", r.cold.certified},
          {"frames", r.summary.frames},
          {"certified", r.summary.certified},
          {"mean_iterations", r.summary.mean_iterations},
          {"max_iterations", r.max_iterations},
          {"mean_ms", r.summary.mean_ms},
          {"max_ms", r.summary.max_ms},
          {"total_s", r.summary.total_s}};
}

// A side-by-side column: a rendered panel with its caption.
struct Column {
  std::string name, stats;
  bool stats_alarm = false;  // stats in red (a broken or folded result)
  vk::RgbaImage image;
};

// The side-by-side figure: title, per column a name and a line of numbers, the
// panels, and one colour bar for all of them.
Surface compose(const std::string& title, const std::vector<Column>& cols, double lo, double hi) {
  const int W = cols.front().image.width, H = cols.front().image.height;
  const double font = std::max(12.0, std::max(W, H) / 30.0);
  const int gap = static_cast<int>(std::ceil(0.6 * font));
  const int title_h = static_cast<int>(std::ceil(2.0 * font)), head_h = static_cast<int>(std::ceil(2.7 * font));
  const int legend_h = static_cast<int>(std::ceil(3.4 * font));
  const int n = static_cast<int>(cols.size());
  const int total_w = n * W + (n + 1) * gap, total_h = title_h + head_h + H + legend_h;
  Surface s = make_surface(total_w, total_h);
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
    while (size > 8 && text_width(cr, col.stats, size, false) > W) size *= 0.92;
    text(cr, x, title_h + 2.15 * font, col.stats, size, false, col.stats_alarm ? 0.8 : 0.25, col.stats_alarm ? 0.05 : 0.25,
         col.stats_alarm ? 0.05 : 0.25, false);
    const Surface panel = surface_from(col.image);
    cairo_set_source_surface(cr, panel.surf.get(), x, title_h + head_h);
    cairo_paint(cr);
    cairo_rectangle(cr, x - 0.5, title_h + head_h - 0.5, W + 1, H + 1);
    cairo_set_source_rgb(cr, 0.75, 0.75, 0.75);
    cairo_set_line_width(cr, 1);
    cairo_stroke(cr);
  }
  draw_legend(cr, total_w, total_h, legend_h, lo, hi, font);
  return s;
}

// CCW16's conformal distortion at the vertices from its f_z, f_zbar (≤ 0: a fold, drawn saturated).
std::vector<double> vertex_kappa(const baselines::Ccw16Frame& f) {
  std::vector<double> kappa(f.positions.size());
  for (size_t v = 0; v < kappa.size(); ++v) {
    const double a = std::abs(f.fz[v]), b = std::abs(f.fzbar[v]);
    kappa[v] = a > b ? (a + b) / (a - b) : -1.0;
  }
  return kappa;
}

int parse_size(const std::string& s) {
  int v = 0;
  try {
    size_t used = 0;
    v = std::stoi(s, &used);
    if (used != s.size()) v = 0;
  } catch (const std::exception&) {
    v = 0;
  }
  if (v < 96 || v > 4096) throw InputError("--size: '" + s + "' is not a panel size between 96 and 4096 pixels");
  return v;
}

void run_compare(const Opts& o) {
  const auto t_start = Clock::now();
  // --- inputs: everything that can be refused is refused before any work ---------------------
  Scene scene = load_scene(o.scene);
  if (scene.keyframes.size() < 2) throw InputError(o.scene + ": comparing needs at least two keyframes");
  const int segments = static_cast<int>(scene.keyframes.size()) - 1;
  if (o.segment < 0 || o.segment >= segments)
    throw InputError("--segment " + std::to_string(o.segment) + ": the scene has " + std::to_string(segments) +
                     " keyframe interval(s), 0.." + std::to_string(segments - 1));
  const int panel = parse_size(o.size);
  for (double r : o.ratios)
    if (!(r > 0 && r <= 1)) throw InputError("--ratios: " + std::to_string(r) + " is not a Hessian sample ratio in (0, 1]");
  std::vector<int> table3;
  for (int v : o.table3_vertices) {
    if (v < 100 || v > 5'000'000) throw InputError("--table3-vertices: " + std::to_string(v) + " is outside 100..5000000");
    if (!(o.no_800k && v >= 800'000)) table3.push_back(v);
  }
  const Machine machine = this_machine();

  vk::ContextOptions co;
  co.validation = o.validation;
  co.device_name = o.device;
  std::unique_ptr<vk::Context> ctx;
  try {
    ctx = std::make_unique<vk::Context>(co);
  } catch (const vk::VulkanUnavailable& e) {
    throw std::runtime_error(std::string("hsi compare renders with Vulkan and needs a device (a GPU, or lavapipe on the CPU): ") +
                             e.what());
  }
  const std::string vulkan_device = ctx->info().name + " (" + ctx->info().type_name() + ")";

  // Texture: the scene's, or a checkerboard.
  const vk::SceneTexture scene_tex = vk::scene_texture(scene, o.scene);
  const vk::RgbaImage& texture = scene_tex.image;
  const std::array<double, 4>& rect = scene_tex.rect;

  Outputs out(o.out);
  out.open();

  // --- keyframes, our main sequence ---------------------------------------------------------
  const std::shared_ptr<const ShapeSetup> setup = scene_setup(scene, o.samples, 0);
  const Cage& cage = setup->cage;
  const double size = setup->size;
  const int holes = cage.hole_count();
  stage(t_start, "scene %s: %d loop(s), %d hole(s), %zu keyframes; cage m = %d, |G| = %zu, |H| = %zu; %s, %d cores; Vulkan: %s",
        scene.name.c_str(), scene.shape.loop_count(), holes, scene.keyframes.size(), cage.vertex_count(), setup->G.size(),
        setup->H.size(), machine.cpu.c_str(), machine.cores, vulkan_device.c_str());
  solve_scene_keyframes(scene, *setup);
  std::vector<double> times;
  std::vector<HarmonicMap> keys;
  for (const Keyframe& k : scene.keyframes) {
    times.push_back(k.time);
    keys.push_back(*k.coefficients);
  }
  const double seg_t0 = times[static_cast<size_t>(o.segment)], seg_t1 = times[static_cast<size_t>(o.segment) + 1];
  const double t_mid = 0.5 * (seg_t0 + seg_t1);

  std::unique_ptr<NewtonCore> main_core = make_core(*setup, o.backend);
  const std::string core_name = main_core->name();
  Interpolator interp(*setup, times, keys, {}, std::move(main_core));
  const bool tty = isatty(fileno(stderr));
  const auto t_seq = Clock::now();
  std::vector<FrameResult> ours = interp.sequence(o.frames, [&](const FrameResult& f, int i, int n) {
    if (tty) std::fprintf(stderr, "\r[compare] ours: frame %d/%d  t = %.4f  %d it  %.1f ms   ", i + 1, n, f.t, f.iterations, f.ms);
    if (tty && i + 1 == n) std::fprintf(stderr, "\n");
  });
  const SequenceSummary ours_sum = summarize(ours, s_since(t_seq));
  stage(t_start, "ours (%s): %d frames, %d certified, %.2f iterations and %.1f ms per frame", core_name.c_str(), ours_sum.frames,
        ours_sum.certified, ours_sum.mean_iterations, ours_sum.mean_ms);

  // --- baselines on the render mesh ----------------------------------------------------------
  const TriMesh mesh = mesh_with(scene.shape, o.mesh_vertices);
  std::vector<baselines::ArapKeyframe> arap_keys;
  for (size_t k = 0; k < keys.size(); ++k) arap_keys.push_back({times[k], map_points_chunked(cage, keys[k], mesh.vertices)});
  // A baseline that refuses the keyframes (e.g. a keyframe that flips a triangle of
  // the mesh) stops the comparison with its reason and what to try.
  auto baseline = [&](const char* name, auto make) {
    try {
      return make();
    } catch (const InputError& e) {
      throw InputError(o.scene + ": the " + name + " baseline refuses this scene's keyframes on the " +
                       std::to_string(mesh.vertex_count()) + "-vertex mesh: " + e.what() +
                       (std::string(name) == "ARAP" ? " (a finer mesh, --mesh-vertices, may resolve a flipped triangle)" : ""));
    }
  };
  auto t0 = Clock::now();
  const baselines::ArapInterpolation arap = baseline("ARAP", [&] { return baselines::ArapInterpolation(mesh, arap_keys); });
  const double arap_setup_ms = ms_since(t0);
  std::vector<baselines::Ccw16Keyframe> ccw_keys;
  for (size_t k = 0; k < keys.size(); ++k) ccw_keys.push_back({times[k], keys[k]});
  t0 = Clock::now();
  const baselines::Ccw16Interpolation ccw =
      baseline("CCW16", [&] { return baselines::Ccw16Interpolation(scene.shape, cage, ccw_keys); });
  const baselines::Ccw16Mesh ccw_mesh = ccw.prepare(mesh);
  const double ccw_setup_ms = ms_since(t0);
  stage(t_start, "render mesh %d vertices, %d triangles; ARAP set up in %.0f ms, CCW16 (log derivatives) in %.0f ms",
        mesh.vertex_count(), mesh.triangle_count(), arap_setup_ms, ccw_setup_ms);

  // CCW16's boundary-metric variant (the one the paper's Fig. 8 compares with): the metric
  // blended on the boundary, f_z and f_zbar rebuilt by a least-squares Hilbert transform.
  // Only on a simply-connected shape (paper §1): with holes it is reported as not
  // applicable, not skipped. Its prepared mesh holds basis rows at every vertex and Gauss
  // node; above --ccw16-memory it runs on a coarser mesh of the shape, and says so.
  struct MetricVariant {
    bool applies = false;
    std::string why_not;
    const TriMesh* mesh = nullptr;  // the render mesh, or `coarse`
    TriMesh coarse;
    double render_mesh_mb = 0, mb = 0, setup_ms = 0;
    std::optional<baselines::Ccw16Interpolation> interp;
    std::optional<baselines::Ccw16Mesh> prepared;
    bool own_mesh = false;  // true: on `coarse`
  } bm;
  if (holes > 0) {
    bm.why_not = "CCW16 (boundary metric) does not apply to multiply-connected domains (paper \xc2\xa7" "1): its Hilbert "
                 "transform recovers a single-valued log f_z from its real part only on a simply-connected domain, and this "
                 "shape has " + std::to_string(holes) + (holes == 1 ? " hole" : " holes");
    stage(t_start, "%s; only CCW16 (log derivatives) is compared", bm.why_not.c_str());
  } else {
    bm.applies = true;
    baselines::Ccw16Options bco;
    bco.variant = baselines::Ccw16Variant::BoundaryMetric;
    const double budget = o.ccw16_memory_mb * 1024.0 * 1024.0;
    double bytes = metric_rows_bytes(mesh, cage.vertex_count(), bco, size);
    bm.render_mesh_mb = bytes / (1024.0 * 1024.0);
    bm.mesh = &mesh;
    // Coarser meshes until the rows fit (the mesher's vertex count is only roughly the one asked for).
    int target = mesh.vertex_count();
    for (int tries = 0; bytes > budget && tries < 8 && target > 100; ++tries) {
      target = std::max(100, static_cast<int>(0.92 * target * budget / bytes));
      bm.coarse = mesh_with(scene.shape, target);
      bm.mesh = &bm.coarse;
      bm.own_mesh = true;
      bytes = metric_rows_bytes(bm.coarse, cage.vertex_count(), bco, size);
    }
    bm.mb = bytes / (1024.0 * 1024.0);
    t0 = Clock::now();
    bm.interp.emplace(baseline("CCW16 (boundary metric)", [&] { return baselines::Ccw16Interpolation(scene.shape, cage, ccw_keys, bco); }));
    bm.prepared.emplace(bm.interp->prepare(*bm.mesh));
    bm.setup_ms = ms_since(t0);
    stage(t_start, "CCW16 (boundary metric) on %s%d-vertex mesh (%.0f MB of basis rows; %.0f MB on the render mesh, --ccw16-memory %.0f MB), set up in %.0f ms",
          bm.own_mesh ? "a coarser " : "the ", bm.mesh->vertex_count(), bm.mb, bm.render_mesh_mb, o.ccw16_memory_mb, bm.setup_ms);
  }

  // ARAP reproduces its keyframes (a check of the baseline as we run it).
  double arap_key_error = 0;
  for (const auto& k : arap_keys) {
    const std::vector<cd> p = arap.positions(k.time);
    for (size_t i = 0; i < p.size(); ++i) arap_key_error = std::max(arap_key_error, std::abs(p[i] - k.positions[i]) / size);
  }

  // Per frame of the sequence: each method's largest distortion and its time.
  const size_t F = ours.size();
  std::vector<double> ts(F), our_kappa(F), our_iso(F), bound_kappa(F), bound_iso(F), our_ms(F), our_iters(F);
  // Ours: our_kappa / our_iso are sampled at the certificate's breakpoints (as are the
  // keyframes' bound_*); the certificate's bounds over ∂Ω (NaN where not certified):
  std::vector<double> our_kappa_c(F), our_iso_c(F), bound_kappa_c(F), bound_iso_c(F);
  std::vector<double> arap_kappa(F), arap_iso(F), arap_ms(F), arap_flipped(F);
  std::vector<double> ccw_kappa(F), ccw_iso(F), ccw_ms(F), ccw_period(F);
  // Simply connected: CCW16's boundary-metric variant per frame, and each variant's distance
  // to our frame after the best rigid alignment (Fig. 8), at the vertices of its mesh.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> bm_kappa(F, nan), bm_iso(F, nan), bm_ms(F, nan), bm_fit(F, nan), ccw_dist(F, nan), bm_dist(F, nan);
  std::vector<double> uncertified_t, unconverged_t;
  for (size_t i = 0; i < F; ++i) {
    const FrameResult& f = ours[i];
    ts[i] = f.t;
    our_kappa[i] = f.certified ? f.distortion.conformal_max : std::numeric_limits<double>::infinity();
    our_iso[i] = f.certified ? f.distortion.isometric_max : std::numeric_limits<double>::infinity();
    bound_kappa[i] = f.bound.conformal_max;
    bound_iso[i] = f.bound.isometric_max;
    our_kappa_c[i] = f.distortion_certified.conformal_max;
    our_iso_c[i] = f.distortion_certified.isometric_max;
    bound_kappa_c[i] = f.certified_bound.conformal_max;
    bound_iso_c[i] = f.certified_bound.isometric_max;
    our_ms[i] = f.keyframe ? std::numeric_limits<double>::quiet_NaN() : f.ms;
    our_iters[i] = f.iterations;
    if (!f.certified) uncertified_t.push_back(f.t);
    if (!f.converged) unconverged_t.push_back(f.t);
    t0 = Clock::now();
    const std::vector<cd> p = arap.positions(f.t);
    arap_ms[i] = ms_since(t0);
    const baselines::MeshDistortion d = baselines::mesh_distortion(mesh, p);
    arap_kappa[i] = d.max_kappa;
    arap_iso[i] = d.max_isometric;
    arap_flipped[i] = d.flipped;
    t0 = Clock::now();
    const baselines::Ccw16Frame c = ccw.frame(f.t, ccw_mesh);
    ccw_ms[i] = ms_since(t0);
    ccw_kappa[i] = c.max_kappa;
    ccw_iso[i] = c.max_isometric;
    ccw_period[i] = c.hole_period.empty() ? 0.0 : max_of(c.hole_period) / size;
    if (bm.applies) {
      t0 = Clock::now();
      const baselines::Ccw16Frame b = bm.interp->frame(f.t, *bm.prepared);
      bm_ms[i] = ms_since(t0);
      bm_kappa[i] = b.max_kappa;
      bm_iso[i] = b.max_isometric;
      bm_fit[i] = b.fit_metric;
      const std::vector<cd> ours_at = map_points_chunked(cage, f.map, mesh.vertices);
      ccw_dist[i] = point_gap(c.positions, ours_at, size).rigid;
      bm_dist[i] = point_gap(b.positions, bm.own_mesh ? map_points_chunked(cage, f.map, bm.mesh->vertices) : ours_at, size).rigid;
    }
    if (tty) std::fprintf(stderr, "\r[compare] baselines: frame %zu/%zu   ", i + 1, F);
  }
  if (tty) std::fprintf(stderr, "\n");
  stage(t_start, "baselines over the sequence: ARAP %.1f ms per frame (%d frames with folds), CCW16 (log derivatives) %.1f ms per frame",
        mean_of(arap_ms), static_cast<int>(std::count_if(arap_flipped.begin(), arap_flipped.end(), [](double v) { return v > 0; })),
        mean_of(ccw_ms));
  if (bm.applies)
    stage(t_start, "CCW16 (boundary metric): %.1f ms per frame; after rigid alignment within %.2e of the size of ours (log derivatives: %.2e)",
          mean_of(bm_ms), max_of(bm_dist), max_of(ccw_dist));

  // --- side by side at t = 0.25, 0.5, 0.75 of the segment -----------------------------------
  struct Snapshot {
    double u = 0, t = 0;
    FrameResult ours;
    std::vector<cd> ours_pos, arap_pos;
    baselines::MeshDistortion arap_d;
    baselines::Ccw16Frame ccw, bm;  // CCW16: log derivatives; boundary metric (simply connected only)
    Gap gap, bm_gap;                // ours vs each CCW16 variant
    std::string png;
    int width = 0, height = 0;  // of the figure
  };
  std::vector<Snapshot> snaps;
  BoundingBox box{cd(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()),
                  cd(-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity())};
  double range_hi = 1;
  for (const double u : {0.25, 0.5, 0.75}) {
    Snapshot s;
    s.u = u;
    s.t = seg_t0 + u * (seg_t1 - seg_t0);
    // Warm-started from the sequence's frame just before t, as playback would be.
    size_t j = 0;
    for (size_t i = 0; i < F; ++i)
      if (ours[i].t <= s.t) j = i;
    s.ours = interp.frame(s.t, ours[j].x, &ours[j].certificate);
    s.ours_pos = map_points_chunked(cage, s.ours.map, mesh.vertices);
    s.arap_pos = arap.positions(s.t);
    s.arap_d = baselines::mesh_distortion(mesh, s.arap_pos);
    s.ccw = ccw.frame(s.t, ccw_mesh);
    s.gap = point_gap(s.ccw.positions, s.ours_pos, size);
    if (bm.applies) {
      s.bm = bm.interp->frame(s.t, *bm.prepared);
      s.bm_gap = point_gap(s.bm.positions, bm.own_mesh ? map_points_chunked(cage, s.ours.map, bm.mesh->vertices) : s.ours_pos, size);
    }
    for (const auto* v : {&s.ours_pos, &s.arap_pos, &s.ccw.positions, &s.bm.positions})
      for (const cd& p : *v) grow(box, p);
    // The colour range: up to the largest κ any panel shows, but no further than the
    // keyframes' bound (beyond it, values saturate: the eye sees where a method leaves it).
    for (double k : {s.ours.distortion.conformal_max, s.arap_d.max_kappa, s.ccw.max_kappa, bm.applies ? s.bm.max_kappa : 1.0})
      if (std::isfinite(k)) range_hi = std::max(range_hi, std::min(k, s.ours.bound.conformal_max));
    snaps.push_back(std::move(s));
  }
  range_hi = vk::round_distortion_hi(range_hi);

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
  const vk::View view = vk::View::fit(box, pw, ph, margin);
  vk::Renderer welded(*ctx, pw, ph), flat(*ctx, pw, ph);
  welded.set_mesh(mesh);
  welded.set_texture(texture, rect);
  const vk::UnweldedMesh unwelded = vk::unweld(mesh);
  flat.set_mesh(unwelded.mesh);
  flat.set_texture(texture, rect);
  // CCW16 (boundary metric) on its own, coarser mesh when the render mesh's rows were too large.
  std::unique_ptr<vk::Renderer> coarse;
  if (bm.applies && bm.own_mesh) {
    coarse = std::make_unique<vk::Renderer>(*ctx, pw, ph);
    coarse->set_mesh(*bm.mesh);
    coarse->set_texture(texture, rect);
  }
  vk::RenderStyle style;
  style.overlays = vk::kOverlayDistortion | vk::kOverlayBoundary;  // no handles: the baselines have none
  style.distortion_lo = 1;
  style.distortion_hi = range_hi;
  style.distortion_opacity = 0.7f;
  style.boundary_width_px = static_cast<float>(std::max(1.2, panel / 360.0));
  for (Snapshot& s : snaps) {
    std::vector<Column> cols;
    {
      vk::RenderStyle st = style;
      st.uncertified = !s.ours.certified;
      Column c{"Ours (harmonic, certified)", "", false, welded.render(cage, s.ours.map, view, st)};
      c.stats = "max \xce\xba " + fixed(s.ours.distortion.conformal_max, 3) + " sampled, \xe2\x89\xa4 " +
                fixed(s.ours.distortion_certified.conformal_max, 3) + " certified  (keyframes " + fixed(s.ours.bound.conformal_max, 3) +
                ")  " + std::to_string(s.ours.iterations) + " it";
      if (!s.ours.certified) {
        c.stats = "NOT CERTIFIED: " + s.ours.certificate.reason;
        c.stats_alarm = true;
      }
      cols.push_back(std::move(c));
    }
    {
      // Per-triangle distortion, drawn flat (each triangle's three corners get its value).
      std::vector<cd> pos(unwelded.source.size());
      std::vector<double> kappa(unwelded.source.size());
      for (size_t v = 0; v < pos.size(); ++v) {
        pos[v] = s.arap_pos[static_cast<size_t>(unwelded.source[v])];
        kappa[v] = s.arap_d.kappa[v / 3];
      }
      Column c{"ARAP [ACOL00]", "", s.arap_d.flipped > 0, flat.render(pos, kappa, view, style)};
      c.stats = "max \xce\xba " + fixed(s.arap_d.max_kappa, 3) + " per triangle, " + std::to_string(s.arap_d.flipped) +
                " flipped";
      cols.push_back(std::move(c));
    }
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
    if (bm.applies) {
      vk::Renderer& r = coarse ? *coarse : welded;
      Column c{"CCW16 (boundary metric)", "", false, r.render(s.bm.positions, vertex_kappa(s.bm), view, style)};
      c.stats = "max \xce\xba " + fixed(s.bm.max_kappa, 3) + ", rigid gap to ours " + sci(s.bm_gap.rigid) + " \xc3\x97 size";
      if (bm.own_mesh) c.stats += ", " + std::to_string(bm.mesh->vertex_count()) + "-vertex mesh";
      cols.push_back(std::move(c));
    }
    char title[256];
    std::snprintf(title, sizeof title, "%s   t = %.2f between keyframes %d and %d (time %.3f)", scene.name.c_str(), s.u,
                  o.segment, o.segment + 1, s.t);
    char name[64];
    std::snprintf(name, sizeof name, "side_by_side_t%.2f.png", s.u);
    s.png = name;
    const Surface fig = compose(title, cols, 1, range_hi);
    s.width = cairo_image_surface_get_width(fig.surf.get());
    s.height = cairo_image_surface_get_height(fig.surf.get());
    write_surface(fig, out.add(name));
  }
  stage(t_start, "side by side: %zu figures at %d x %d per panel", snaps.size(), pw, ph);

  // --- plots -----------------------------------------------------------------------------------
  const std::string ccw_name = holes ? "CCW16 (log derivatives) at vertices, not a map (hole period \xe2\x89\xa0 0)"
                                     : "CCW16 (log derivatives) at vertices";
  const std::string bm_mesh_note = bm.own_mesh ? " (" + std::to_string(bm.mesh->vertex_count()) + "-vertex mesh)" : std::string();
  const std::string bm_name = "CCW16 (boundary metric) at vertices" + bm_mesh_note;
  constexpr double kBmR = 0.6, kBmG = 0.25, kBmB = 0.7;  // the boundary-metric variant's colour in every plot
  auto distortion_plot = [&](const std::string& file, const std::string& what, const std::string& symbol,
                             const std::vector<double>& a, const std::vector<double>& b, const std::vector<double>& c,
                             const std::vector<double>& d, const std::vector<double>& bound, const std::vector<double>& a_cert,
                             const std::vector<double>& bound_cert) {
    PlotSpec p;
    p.title = scene.name + ": largest " + what + " per frame, each method vs the keyframes'";
    p.xlabel = "t (keyframes at the dotted lines)";
    p.ylabel = "max " + symbol;
    p.x = ts;
    p.series = {{"ours: certified bound over \xe2\x88\x82\xce\xa9", a_cert, 0.55, 0.7, 0.95, false, false, 4.0},
                {"keyframes: certified bound", bound_cert, 0.55, 0.55, 0.55, true, true, 2.4},
                {"ours (sampled at breakpoints on \xe2\x88\x82\xce\xa9)", a, 0.12, 0.35, 0.75, false, false, 2.2},
                {"ARAP (per triangle)", b, 0.9, 0.45, 0.05, false, false, 1.6},
                {ccw_name, c, 0.15, 0.6, 0.25, false, false, 1.6},
                {"keyframes (sampled)", bound, 0.1, 0.1, 0.1, true, true, 1.4}};
    // Drawn first and wide, so that ours stays visible on top where the two coincide (Fig. 8).
    if (bm.applies) p.series.insert(p.series.begin(), {bm_name, d, kBmR, kBmG, kBmB, false, false, 4.5});
    p.flagged = uncertified_t;
    p.unconverged = unconverged_t;
    p.x_marks = times;
    p.y_scale = AxisScale::kAuto;
    if (std::any_of(b.begin(), b.end(), [](double v) { return std::isinf(v); }))
      p.note = "\xe2\x96\xb2 at the top: ARAP frames with flipped triangles (distortion unbounded).  ";
    if (bm.applies) p.note += "CCW16 (boundary metric) drawn wide under the others: it nearly coincides with ours.  ";
    if (!uncertified_t.empty()) p.note += "Red lines: frames of ours that could not be certified.  ";
    if (!unconverged_t.empty()) p.note += "Orange dashed: frames of ours whose Newton solve did not converge.";
    plot_series(out.add(file), p);
  };
  distortion_plot("kappa.png", "conformal distortion \xce\xba = \xcf\x83\xe2\x82\x81/\xcf\x83\xe2\x82\x82", "\xce\xba",
                  our_kappa, arap_kappa, ccw_kappa, bm_kappa, bound_kappa, our_kappa_c, bound_kappa_c);
  distortion_plot("isometric.png", "isometric distortion (symmetric Dirichlet)", "E_SD", our_iso, arap_iso, ccw_iso, bm_iso,
                  bound_iso, our_iso_c, bound_iso_c);
  {
    PlotSpec p;
    p.title = scene.name + ": time per frame on this machine (" + std::to_string(mesh.vertex_count()) + "-vertex mesh for the baselines)";
    p.xlabel = "t";
    p.ylabel = "ms per frame";
    p.x = ts;
    p.series = {{"ours: solve (" + core_name + ")", our_ms, 0.12, 0.35, 0.75, false, false, 2.0},
                {"ARAP: one sparse solve", arap_ms, 0.9, 0.45, 0.05, false, false, 1.6},
                {"CCW16 (log derivatives): blend + integrate", ccw_ms, 0.15, 0.6, 0.25, false, false, 1.6}};
    if (bm.applies)
      p.series.push_back({"CCW16 (boundary metric): fit + integrate" + bm_mesh_note, bm_ms, kBmR, kBmG, kBmB, false, false, 1.6});
    p.x_marks = times;
    p.y_scale = AxisScale::kAuto;
    plot_series(out.add("frame_time.png"), p);
  }
  if (bm.applies) {
    // Fig. 8: how far each CCW16 variant is from our frame over the sequence, up to a rigid motion.
    PlotSpec p;
    p.title = scene.name + ": CCW16 against ours after the best rigid alignment (Fig. 8)";
    p.xlabel = "t (keyframes at the dotted lines)";
    p.ylabel = "max |f \xe2\x88\x92 f_ours| / size";
    p.x = ts;
    // A keyframe reproduced exactly (distance at rounding level) has no place on a log axis.
    auto shown = [](std::vector<double> v) {
      for (double& x : v)
        if (x < 1e-9) x = std::numeric_limits<double>::quiet_NaN();
      return v;
    };
    p.series = {{"CCW16 (log derivatives)", shown(ccw_dist), 0.15, 0.6, 0.25, false, false, 1.8},
                {"CCW16 (boundary metric)" + bm_mesh_note, shown(bm_dist), kBmR, kBmG, kBmB, false, false, 1.8}};
    p.note = "Max over the mesh vertices; values below 1e-9 of the size (a keyframe reproduced exactly) are left out.";
    p.x_marks = times;
    p.y_scale = AxisScale::kLog;
    plot_series(out.add("ccw16_distance.png"), p);
  }

  // --- Table 1: Hessian projections; Table 2: Hessian sample ratio ---------------------------
  std::vector<OurRun> table1, table2;
  for (const HessianProjection proj : {HessianProjection::Delete, HessianProjection::FullProj, HessianProjection::PartProj}) {
    table1.push_back(run_ours(to_string(proj), *setup, times, keys, proj, make_cpu_newton_core(setup->D_G, setup->H),
                              o.table_frames, t_mid, scene.hessian_ratio));
    stage(t_start, "table 1: %s: %.2f iterations per frame", to_string(proj), table1.back().summary.mean_iterations);
  }
  if (core_name != table1.back().core)
    table1.push_back(run_ours(std::string(to_string(HessianProjection::PartProj)) + " (" + core_name + ")", *setup, times, keys,
                              HessianProjection::PartProj, make_core(*setup, o.backend), o.table_frames, t_mid,
                              scene.hessian_ratio));
  for (const double r : o.ratios) {
    const std::shared_ptr<const ShapeSetup> sr = scene_setup(scene, o.samples, r);
    char label[32];
    std::snprintf(label, sizeof label, "r = %g", r);
    table2.push_back(run_ours(label, *sr, times, keys, HessianProjection::PartProj, make_core(*sr, o.backend), o.table_frames,
                              t_mid, r));
    stage(t_start, "table 2: %s (|H| = %zu): %.2f iterations, %.1f ms per frame", label, sr->H.size(),
          table2.back().summary.mean_iterations, table2.back().summary.mean_ms);
  }

  // --- Table 3: time against the render mesh's resolution ------------------------------------
  // Ours: the solve does not see the mesh; a frame at the mesh costs the solve plus f at
  // its vertices. ARAP: one sparse solve per frame on the mesh, after a factorisation.
  std::vector<size_t> timed;  // frames of the sequence whose maps and times are used
  for (int k = 0; k < o.timing_frames; ++k) timed.push_back(static_cast<size_t>(k + 1) * (F - 1) / static_cast<size_t>(o.timing_frames + 1));
  vk::DenseEvaluator dense(*ctx);
  json table3_json = json::array();
  struct T3 {
    int vertices, triangles;
    double mesh_s, arap_factor_ms, arap_ms, ours_eval_cpu_ms, ours_eval_vk_ms;
  };
  std::vector<T3> t3;
  for (int v : table3) {
    T3 row{};
    t0 = Clock::now();
    const TriMesh m = mesh_with(scene.shape, v);
    row.mesh_s = s_since(t0);
    row.vertices = m.vertex_count();
    row.triangles = m.triangle_count();
    std::vector<baselines::ArapKeyframe> ak;
    for (size_t k = 0; k < keys.size(); ++k) ak.push_back({times[k], map_points_chunked(cage, keys[k], m.vertices)});
    t0 = Clock::now();
    const baselines::ArapInterpolation a(m, std::move(ak));
    row.arap_factor_ms = ms_since(t0);
    double arap_sum = 0, cpu_sum = 0, vk_sum = 0;
    for (size_t i : timed) {
      t0 = Clock::now();
      const std::vector<cd> p = a.positions(ours[i].t);
      arap_sum += ms_since(t0);
      t0 = Clock::now();
      const std::vector<cd> f = map_points_chunked(cage, ours[i].map, m.vertices);
      cpu_sum += ms_since(t0);
      t0 = Clock::now();
      const vk::DenseField d = dense.evaluate_points(cage, ours[i].map, m.vertices);
      vk_sum += ms_since(t0);
      if (p.size() != f.size() || d.size() != f.size()) throw std::logic_error("table 3: sizes disagree");
    }
    const double n = static_cast<double>(timed.size());
    row.arap_ms = arap_sum / n;
    row.ours_eval_cpu_ms = cpu_sum / n;
    row.ours_eval_vk_ms = vk_sum / n;
    t3.push_back(row);
    stage(t_start, "table 3: %d vertices: ARAP factorisation %.0f ms, %.1f ms per frame; ours f at the vertices %.1f ms (CPU), %.1f ms (Vulkan)",
          row.vertices, row.arap_factor_ms, row.arap_ms, row.ours_eval_cpu_ms, row.ours_eval_vk_ms);
  }
  // Ours at the default mesh, for Table 4: f at its vertices on the CPU.
  double ours_eval_default_ms = 0;
  for (size_t i : timed) {
    t0 = Clock::now();
    const std::vector<cd> f = map_points_chunked(cage, ours[i].map, mesh.vertices);
    ours_eval_default_ms += ms_since(t0) / static_cast<double>(timed.size());
  }

  if (ctx->validation_enabled() && ctx->validation_log()->count())
    throw std::runtime_error("Vulkan validation reported problems:\n" + ctx->validation_log()->summary(10));

  // --- report.json ----------------------------------------------------------------------------
  const double arap_frame_ms = mean_of(arap_ms), ccw_frame_ms = mean_of(ccw_ms);
  int ours_within = 0;
  for (const FrameResult& f : ours) ours_within += f.certified && f.bound_excess <= 1e-9;  // sampled against sampled
  int arap_folded = 0;
  for (double v : arap_flipped) arap_folded += v > 0;
  json rep;
  rep["scene"] = o.scene;
  rep["name"] = scene.name;
  rep["holes"] = holes;
  char date[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S %Z", std::localtime(&now));
  rep["date"] = date;
  rep["machine"] = {{"cpu", machine.cpu}, {"logical_cores", machine.cores}, {"vulkan_device", vulkan_device}};
  rep["settings"] = {{"frames", o.frames},
                     {"table_frames", o.table_frames},
                     {"mesh_vertices", mesh.vertex_count()},
                     {"mesh_triangles", mesh.triangle_count()},
                     {"samples", setup->G.size()},
                     {"hessian_samples", setup->H.size()},
                     {"hessian_ratio", scene.hessian_ratio},
                     {"segment", o.segment},
                     {"timing_frames", o.timing_frames},
                     {"ccw16_memory_mb", o.ccw16_memory_mb},
                     {"newton_core", core_name},
                     {"panel_size", {pw, ph}}};
  json kf = json::array();
  for (size_t k = 0; k < times.size(); ++k)
    kf.push_back({{"time", times[k]},
                  {"conformal_max", interp.keyframe_distortion(static_cast<int>(k)).conformal_max},
                  {"isometric_max", interp.keyframe_distortion(static_cast<int>(k)).isometric_max},
                  {"conformal_max_certified_bound", interp.keyframe_certified_distortion(static_cast<int>(k)).conformal_max},
                  {"isometric_max_certified_bound", interp.keyframe_certified_distortion(static_cast<int>(k)).isometric_max}});
  rep["keyframes"] = kf;
  rep["distortion_kinds"] = {
      {"sampled", "ours' kappa / isometric and the keyframes' bound: sampled at the certificate's breakpoints on the boundary"},
      {"certified", "*_certified_bound: the certificate's bounds over the boundary, so over the shape (Theorem 2); isometric from "
                    "the sigma bounds; \"nan\" where a frame is not certified"}};
  rep["sequence"] = {{"t", ts},
                     {"ours", {{"kappa", nums(our_kappa)}, {"isometric", nums(our_iso)}, {"kappa_certified_bound", nums(our_kappa_c)},
                               {"isometric_certified_bound", nums(our_iso_c)}, {"ms", nums(our_ms)}, {"iterations", our_iters}}},
                     {"bound", {{"kappa", nums(bound_kappa)}, {"isometric", nums(bound_iso)}, {"kappa_certified_bound", nums(bound_kappa_c)},
                                {"isometric_certified_bound", nums(bound_iso_c)}}},
                     {"arap", {{"kappa", nums(arap_kappa)}, {"isometric", nums(arap_iso)}, {"flipped", arap_flipped}, {"ms", nums(arap_ms)}}},
                     {"ccw16", {{"kappa", nums(ccw_kappa)}, {"isometric", nums(ccw_iso)}, {"ms", nums(ccw_ms)},
                                {"max_hole_period_over_size", nums(ccw_period)}}}};
  if (bm.applies) {
    rep["sequence"]["ccw16"]["distance_to_ours_after_rigid_alignment_over_size"] = nums(ccw_dist);
    rep["sequence"]["ccw16_boundary_metric"] = {{"kappa", nums(bm_kappa)},
                                                {"isometric", nums(bm_iso)},
                                                {"ms", nums(bm_ms)},
                                                {"fit_metric", nums(bm_fit)},
                                                {"distance_to_ours_after_rigid_alignment_over_size", nums(bm_dist)}};
  }
  // The two CCW16 variants: what each blends, where it ran, and why one may not apply.
  const std::string log_blends =
      "blends log f_z and the second dilatation \xce\xbd = conj(f_zbar)/f_z pointwise in the shape, then integrates them";
  const std::string bm_blends =
      "blends the pull-back metric on the boundary only (as ours does) and rebuilds f_z, f_zbar inside by a least-squares "
      "Hilbert transform, then integrates them";
  json bm_json = {{"name", "CCW16 (boundary metric)"}, {"variant", to_string(baselines::Ccw16Variant::BoundaryMetric)},
                  {"blends", bm_blends}, {"applies", bm.applies}};
  if (bm.applies) {
    bm_json["mesh_vertices"] = bm.mesh->vertex_count();
    bm_json["mesh_triangles"] = bm.mesh->triangle_count();
    bm_json["coarser_than_render_mesh"] = bm.own_mesh;
    bm_json["basis_rows_mb"] = bm.mb;
    bm_json["render_mesh_basis_rows_mb"] = bm.render_mesh_mb;
    bm_json["memory_budget_mb"] = o.ccw16_memory_mb;
  } else {
    bm_json["reason"] = bm.why_not;
  }
  rep["ccw16_variants"] = {{"log_derivatives", {{"name", "CCW16 (log derivatives)"},
                                                {"variant", to_string(baselines::Ccw16Variant::LogDerivatives)},
                                                {"blends", log_blends},
                                                {"applies", true},
                                                {"mesh_vertices", mesh.vertex_count()}}},
                           {"boundary_metric", bm_json}};
  rep["summary"] = {
      {"ours", {{"frames", ours_sum.frames}, {"certified", ours_sum.certified}, {"not_converged", ours_sum.not_converged},
                {"frames_within_bound", ours_within}, {"max_bound_excess", ours_sum.max_bound_excess},
                {"frames_within_certified_bound", ours_sum.within_certified_bounds},
                {"max_certified_bound_excess", ours_sum.max_certified_bound_excess},
                {"max_kappa_certified_bound", num(max_of(our_kappa_c))}, {"max_isometric_certified_bound", num(max_of(our_iso_c))},
                {"max_kappa", num(max_of(our_kappa))},
                {"max_isometric", num(max_of(our_iso))}, {"mean_iterations", ours_sum.mean_iterations}, {"mean_ms", ours_sum.mean_ms}}},
      {"bound", {{"max_kappa", num(max_of(bound_kappa))}, {"max_isometric", num(max_of(bound_iso))},
                 {"max_kappa_certified_bound", num(max_of(bound_kappa_c))}, {"max_isometric_certified_bound", num(max_of(bound_iso_c))}}},
      {"arap", {{"max_kappa", num(max_of(arap_kappa))}, {"max_isometric", num(max_of(arap_iso))}, {"frames_with_flips", arap_folded},
                {"keyframe_error_over_size", arap_key_error}, {"setup_ms", arap_setup_ms}, {"mean_ms", arap_frame_ms}}},
      {"ccw16", {{"max_kappa", num(max_of(ccw_kappa))}, {"max_isometric", num(max_of(ccw_iso))},
                 {"max_hole_period_over_size", num(max_of(ccw_period))}, {"setup_ms", ccw_setup_ms}, {"mean_ms", ccw_frame_ms}}}};
  rep["summary"]["ccw16_boundary_metric"] =
      bm.applies ? json{{"applies", true}, {"max_kappa", num(max_of(bm_kappa))}, {"max_isometric", num(max_of(bm_iso))},
                        {"max_fit_metric", num(max_of(bm_fit))}, {"setup_ms", bm.setup_ms}, {"mean_ms", mean_of(bm_ms)}}
                 : json{{"applies", false}, {"reason", bm.why_not}};
  json sbs = json::array();
  for (const Snapshot& s : snaps) {
    sbs.push_back({{"u", s.u},
                   {"t", s.t},
                   {"png", s.png},
                   {"image_size", {s.width, s.height}},
                   {"ours", {{"certified", s.ours.certified}, {"iterations", s.ours.iterations}, {"kappa_max", s.ours.distortion.conformal_max},
                             {"isometric_max", s.ours.distortion.isometric_max}, {"bound_kappa", s.ours.bound.conformal_max},
                             {"kappa_max_certified_bound", num(s.ours.distortion_certified.conformal_max)},
                             {"bound_kappa_certified", num(s.ours.certified_bound.conformal_max)}}},
                   {"arap", {{"kappa_max", num(s.arap_d.max_kappa)}, {"isometric_max", num(s.arap_d.max_isometric)}, {"flipped", s.arap_d.flipped}}},
                   {"ccw16", {{"kappa_max", num(s.ccw.max_kappa)}, {"isometric_max", num(s.ccw.max_isometric)},
                              {"hole_period_over_size", [&] {
                                 json a = json::array();
                                 for (double p : s.ccw.hole_period) a.push_back(p / size);
                                 return a;
                               }()},
                              {"seam_jump_over_size", [&] {
                                 json a = json::array();
                                 for (double p : s.ccw.seam_jump) a.push_back(p / size);
                                 return a;
                               }()},
                              {"max_distance_to_ours_over_size", s.gap.raw},
                              {"max_distance_to_ours_after_rigid_alignment_over_size", s.gap.rigid}}}});
  }
  if (bm.applies)
    for (size_t i = 0; i < snaps.size(); ++i) {
      const Snapshot& s = snaps[i];
      sbs[i]["ccw16_boundary_metric"] = {{"kappa_max", num(s.bm.max_kappa)},
                                         {"isometric_max", num(s.bm.max_isometric)},
                                         {"fit_log_modulus", s.bm.fit_log_modulus},
                                         {"fit_fzbar", s.bm.fit_fzbar},
                                         {"fit_metric", s.bm.fit_metric},
                                         {"max_distance_to_ours_over_size", s.bm_gap.raw},
                                         {"max_distance_to_ours_after_rigid_alignment_over_size", s.bm_gap.rigid}};
    }
  rep["side_by_side"] = sbs;
  // Fig. 8 (simply connected): each variant's distance to our frames, as is and after the best
  // rigid alignment, the largest over the three side-by-side times and over the whole sequence.
  Fig8 fig8_log, fig8_bm;
  if (bm.applies) {
    for (const Snapshot& s : snaps) {
      fig8_log.raw = std::max(fig8_log.raw, s.gap.raw);
      fig8_log.rigid = std::max(fig8_log.rigid, s.gap.rigid);
      fig8_bm.raw = std::max(fig8_bm.raw, s.bm_gap.raw);
      fig8_bm.rigid = std::max(fig8_bm.rigid, s.bm_gap.rigid);
    }
    fig8_log.sequence_rigid = max_of(ccw_dist);
    fig8_bm.sequence_rigid = max_of(bm_dist);
    fig8_log.sequence_t = ts[static_cast<size_t>(std::max_element(ccw_dist.begin(), ccw_dist.end()) - ccw_dist.begin())];
    fig8_bm.sequence_t = ts[static_cast<size_t>(std::max_element(bm_dist.begin(), bm_dist.end()) - bm_dist.begin())];
    // At a keyframe ours and CCW16 (log derivatives) reproduce it exactly, CCW16 (boundary
    // metric) up to its fit: the interpolation itself is what lies between the keyframes.
    std::vector<double> log_between, bm_between;
    for (size_t i = 0; i < F; ++i)
      if (!ours[i].keyframe) log_between.push_back(ccw_dist[i]), bm_between.push_back(bm_dist[i]);
    if (!log_between.empty()) {
      fig8_log.between_keyframes_rigid = max_of(log_between);
      fig8_bm.between_keyframes_rigid = max_of(bm_between);
    }
    auto fig8_json = [&](const Fig8& g, const std::string& name, const std::string& blends, int vertices) {
      return json{{"name", name},
                  {"blends", blends},
                  {"mesh_vertices", vertices},
                  {"max_distance_to_ours_over_size", g.raw},
                  {"max_distance_to_ours_after_rigid_alignment_over_size", g.rigid},
                  {"sequence_max_distance_after_rigid_alignment_over_size", num(g.sequence_rigid)},
                  {"sequence_max_at_t", num(g.sequence_t)},
                  {"between_keyframes_max_distance_after_rigid_alignment_over_size", num(g.between_keyframes_rigid)}};
    };
    rep["fig8"] = {{"applies", true},
                   {"times", {snaps[0].t, snaps[1].t, snaps[2].t}},
                   {"log_derivatives", fig8_json(fig8_log, "CCW16 (log derivatives)", log_blends, mesh.vertex_count())},
                   {"boundary_metric", fig8_json(fig8_bm, "CCW16 (boundary metric)", bm_blends, bm.mesh->vertex_count())}};
  } else {
    rep["fig8"] = {{"applies", false},
                   {"reason", "CCW16 (log derivatives) is not a map on this shape (its hole periods: Fig. 2); " + bm.why_not}};
  }
  rep["colour_range"] = {1.0, range_hi};
  json t1 = json::array(), t2 = json::array();
  for (const OurRun& r : table1) t1.push_back(run_json(r));
  for (const OurRun& r : table2) t2.push_back(run_json(r));
  rep["table1_projection"] = t1;
  rep["table2_ratio"] = t2;
  for (const T3& r : t3)
    table3_json.push_back({{"vertices", r.vertices},
                           {"triangles", r.triangles},
                           {"mesh_s", r.mesh_s},
                           {"arap_factorisation_ms", r.arap_factor_ms},
                           {"arap_ms", r.arap_ms},
                           {"ours_solve_ms", ours_sum.mean_ms},
                           {"ours_eval_cpu_ms", r.ours_eval_cpu_ms},
                           {"ours_eval_vulkan_ms", r.ours_eval_vk_ms},
                           {"ours_total_cpu_ms", ours_sum.mean_ms + r.ours_eval_cpu_ms}});
  rep["table3_resolution"] = table3_json;
  rep["table4_per_frame"] = {{"mesh_vertices", mesh.vertex_count()},
                             {"arap_ms", arap_frame_ms},
                             {"ccw16_ms", ccw_frame_ms},
                             {"ccw16_boundary_metric_ms", bm.applies ? num(mean_of(bm_ms)) : json(nullptr)},
                             {"ccw16_boundary_metric_mesh_vertices", bm.applies ? json(bm.mesh->vertex_count()) : json(nullptr)},
                             {"ours_solve_ms", ours_sum.mean_ms},
                             {"ours_iterations", ours_sum.mean_iterations},
                             {"ours_eval_cpu_ms", ours_eval_default_ms},
                             {"ours_total_cpu_ms", ours_sum.mean_ms + ours_eval_default_ms},
                             {"arap_over_ours_solve", arap_frame_ms / ours_sum.mean_ms},
                             {"arap_over_ours_total", arap_frame_ms / (ours_sum.mean_ms + ours_eval_default_ms)}};
  rep["total_s"] = s_since(t_start);
  write_file_atomic(out.add("report.json"), rep.dump(1) + "\n");

  // --- report.md (last) ---------------------------------------------------------------------
  std::string md;
  auto line = [&md](const std::string& s = "") { md += s + "\n"; };
  line("# hsi compare: " + scene.name);
  line();
  line("Scene `" + o.scene + "`: " + std::to_string(scene.shape.loop_count()) + " loop(s), " + std::to_string(holes) +
       " hole(s), " + std::to_string(times.size()) + " keyframes at t = " + [&] {
         std::string s;
         for (size_t k = 0; k < times.size(); ++k) s += (k ? ", " : "") + fixed(times[k], 2);
         return s;
       }() + ". Measured in one run on " + date + ".");
  line();
  line("**Machine:** " + machine.cpu + ", " + std::to_string(machine.cores) + " logical cores; Vulkan device " + vulkan_device +
       " (rendering, and the Vulkan column of Table 3). Our Newton core: " + core_name + ".");
  line();
  line("**Settings:** |G| = " + std::to_string(setup->G.size()) + " boundary samples, |H| = " + std::to_string(setup->H.size()) +
       " (r = " + fixed(scene.hessian_ratio, 2) + "), PartProj; " + std::to_string(o.frames) + " frames over the keyframes' range " +
       "for the plots, " + std::to_string(o.table_frames) + " for Tables 1–2; baselines on a " + std::to_string(mesh.vertex_count()) +
       "-vertex, " + std::to_string(mesh.triangle_count()) + "-triangle mesh" +
       (bm.own_mesh ? " (CCW16 (boundary metric) on a coarser " + std::to_string(bm.mesh->vertex_count()) + "-vertex one: see Fig. 8)"
                    : std::string()) +
       "; keyframes for ARAP are our keyframe maps at its vertices, for CCW16 their coefficients.");
  line();
  line(bm.applies ? "## Side by side (ours, ARAP, CCW16 with log derivatives, CCW16 with the boundary metric)"
                  : "## Side by side (ours, ARAP, CCW16 with log derivatives)");
  line();
  line("At t = 0.25, 0.5, 0.75 between keyframes " + std::to_string(o.segment) + " and " + std::to_string(o.segment + 1) +
       ". Texture with the conformal distortion \xce\xba = \xcf\x83\xe2\x82\x81/\xcf\x83\xe2\x82\x82 over it, one colour range [1, " +
       fixed(range_hi, 2) + "] for every panel (up to the keyframes' bound, rounded up); larger values and folds saturate to the top colour. "
       "Ours: \xce\xba of the map at the mesh's vertices (the dense evaluation on the Vulkan device). ARAP: \xce\xba per triangle, drawn flat. "
       "CCW16: \xce\xba from its blended f_z, f_zbar at the vertices, positions integrated along a spanning tree of the mesh; "
       "two variants of it, CCW16 (log derivatives) and CCW16 (boundary metric), differ in what they blend (see " + std::string(bm.applies ? "Fig. 8" : "Fig. 2") + " below)." +
       (bm.applies ? (bm.own_mesh ? " CCW16 (boundary metric) is drawn on its own, coarser " + std::to_string(bm.mesh->vertex_count()) +
                                        "-vertex mesh (memory: Fig. 8 below)."
                                  : std::string())
                   : " " + bm.why_not + ", so it has no column here."));
  line();
  for (const Snapshot& s : snaps) {
    line("![" + scene.name + " at t = " + fixed(s.u, 2) + "](" + s.png + ")");
    line();
  }
  line("## Distortion over the sequence (Figs 3–5)");
  line();
  line("Largest distortion per frame. Ours, sampled: the largest value at the certificate's breakpoints on \xe2\x88\x82\xce\xa9 "
       "(observed, not a bound); ours, certified bound: the certificate's upper bound over \xe2\x88\x82\xce\xa9, so over \xce\xa9 "
       "(Theorem 2; the isometric one derived from the \xcf\x83\xe2\x82\x81 upper and \xcf\x83\xe2\x82\x82 lower bounds). "
       "ARAP: over the triangles of the mesh. CCW16: over the mesh's vertices. The keyframes' bound: the envelope of the two "
       "neighbouring keyframes' distortion, sampled or certified alike.");
  line();
  line("![largest conformal distortion](kappa.png)");
  line();
  line("![largest isometric distortion](isometric.png)");
  line();
  line("| method | max \xce\xba | max isometric | frames | notes |");
  line("|---|---|---|---|---|");
  line("| keyframes' bound (sampled) | " + fixed(max_of(bound_kappa), 4) + " | " + fixed(max_of(bound_iso), 4) + " | | |");
  line("| keyframes' bound (certified) | " + fixed(max_of(bound_kappa_c), 4) + " | " + fixed(max_of(bound_iso_c), 4) + " | | |");
  line("| ours (sampled) | " + fixed(max_of(our_kappa), 4) + " | " + fixed(max_of(our_iso), 4) + " | " + std::to_string(ours_sum.frames) + " | " +
       std::to_string(ours_sum.certified) + " certified, " + std::to_string(ours_sum.not_converged) + " not converged, " +
       std::to_string(ours_within) + " within the keyframes' sampled bound (largest excess " + sci(ours_sum.max_bound_excess) + ", relative) |");
  line("| ours (certified bound) | " + fixed(max_of(our_kappa_c), 4) + " | " + fixed(max_of(our_iso_c), 4) + " | " +
       std::to_string(ours_sum.certified) + " | " + std::to_string(ours_sum.within_certified_bounds) +
       " within the keyframes' certified bound (largest excess " + sci(ours_sum.max_certified_bound_excess) + ", relative) |");
  line("| ARAP | " + fixed(max_of(arap_kappa), 4) + " | " + fixed(max_of(arap_iso), 4) + " | " + std::to_string(F) + " | " +
       std::to_string(arap_folded) + " frames with flipped triangles; keyframes reproduced to " + sci(arap_key_error) + " \xc3\x97 size |");
  line("| CCW16 (log derivatives) | " + fixed(max_of(ccw_kappa), 4) + " | " + fixed(max_of(ccw_iso), 4) + " | " + std::to_string(F) + " | " +
       (holes ? "not a map: largest hole period " + sci(max_of(ccw_period)) + " \xc3\x97 size" : std::string("simply connected: a map")) + " |");
  if (bm.applies)
    line("| CCW16 (boundary metric) | " + fixed(max_of(bm_kappa), 4) + " | " + fixed(max_of(bm_iso), 4) + " | " + std::to_string(F) +
         " | simply connected: a map; blended metric realised at \xe2\x88\x82\xce\xa9 to " + sci(max_of(bm_fit)) + " (relative)" +
         (bm.own_mesh ? "; on the " + std::to_string(bm.mesh->vertex_count()) + "-vertex mesh" : std::string()) + " |");
  else
    line("| CCW16 (boundary metric) | n/a | n/a | 0 | does not apply: " + std::to_string(holes) + " hole(s), a multiply-connected domain (paper \xc2\xa7" "1) |");
  line();
  if (holes) {
    line("## CCW16 on a shape with holes (Fig. 2)");
    line();
    line("**CCW16 (log derivatives)** " + log_blends + ". A frame of it is single-valued only if the integral of its blended "
         "derivatives around every hole (the period P) vanishes. At the keyframes it does; in between it does not, and the integrated mesh tears along a seam by P:");
    line();
    line("| t | hole periods \\|P\\| / size | seam jump / size | max \xce\xba |");
    line("|---|---|---|---|");
    for (const Snapshot& s : snaps) {
      std::string p, j;
      for (size_t i = 0; i < s.ccw.hole_period.size(); ++i) p += (i ? ", " : "") + sci(s.ccw.hole_period[i] / size);
      for (size_t i = 0; i < s.ccw.seam_jump.size(); ++i) j += (i ? ", " : "") + sci(s.ccw.seam_jump[i] / size);
      line("| " + fixed(s.u, 2) + " | " + p + " | " + j + " | " + fixed(s.ccw.max_kappa, 4) + " |");
    }
    line();
    line("**CCW16 (boundary metric)** " + bm_blends + ". " + bm.why_not + ". It is the variant of the paper's Fig. 8 (CCW16 against ours on a simply-connected shape), "
         "which therefore has no counterpart on this scene: run `hsi compare` on a shape without holes (e.g. assets/blob.json) for it.");
  } else {
    line("## CCW16 against ours on a simply-connected shape (Fig. 8)");
    line();
    line("Two variants of CCW16 interpolate the same keyframes. **CCW16 (log derivatives)** " + log_blends +
         ". **CCW16 (boundary metric)** " + bm_blends +
         "; it is the variant the paper's Fig. 8 finds visually the same as ours. Largest distance to our frame over the vertices "
         "of each variant's mesh, relative to the shape's size (bounding-box diagonal), as they are and after the best rigid "
         "alignment (the methods place the frame differently: ours by an interpolated rigid pose, CCW16 from an anchor point "
         "and its mean rotation):");
    line();
    line("| t | log derivatives: max \\|f_ours \xe2\x88\x92 f_CCW16\\| / size | after rigid alignment | boundary metric: max "
         "\\|f_ours \xe2\x88\x92 f_CCW16\\| / size | after rigid alignment | boundary metric: metric fit at \xe2\x88\x82\xce\xa9 | "
         "max \xce\xba ours | max \xce\xba log derivatives | max \xce\xba boundary metric |");
    line("|---|---|---|---|---|---|---|---|---|");
    for (const Snapshot& s : snaps)
      line("| " + fixed(s.u, 2) + " | " + sci(s.gap.raw) + " | " + sci(s.gap.rigid) + " | " + sci(s.bm_gap.raw) + " | " +
           sci(s.bm_gap.rigid) + " | " + sci(s.bm.fit_metric) + " | " + fixed(s.ours.distortion.conformal_max, 4) + " | " +
           fixed(s.ccw.max_kappa, 4) + " | " + fixed(s.bm.max_kappa, 4) + " |");
    line();
    line("Over the whole sequence (" + std::to_string(F) + " frames, every keyframe interval), after rigid alignment: CCW16 (log "
         "derivatives) up to " + sci(fig8_log.sequence_rigid) + " of the size (at t = " + fixed(fig8_log.sequence_t, 3) +
         "), CCW16 (boundary metric) up to " + sci(fig8_bm.sequence_rigid) + " (at t = " + fixed(fig8_bm.sequence_t, 3) + "). "
         "Between the keyframes only (at a keyframe ours and the log-derivative variant reproduce it exactly, the "
         "boundary-metric variant up to its fit): " + sci(fig8_log.between_keyframes_rigid) + " and " +
         sci(fig8_bm.between_keyframes_rigid) + ".");
    line();
    line("![CCW16 against ours after rigid alignment](ccw16_distance.png)");
    line();
    line("The relative fit is how well the boundary-metric variant's rebuilt f_z, f_zbar realise the blended metric at the "
         "boundary samples (\xe2\x80\x96M(f) \xe2\x88\x92 M(t)\xe2\x80\x96 / \xe2\x80\x96M(t)\xe2\x80\x96, largest over \xe2\x88\x82\xce\xa9). "
         "Memory: this variant keeps its basis rows at every vertex and quadrature node of its mesh, " +
         fixed(bm.render_mesh_mb, 0) + " MB on the " + std::to_string(mesh.vertex_count()) + "-vertex render mesh" +
         (bm.own_mesh ? "; above the " + fixed(o.ccw16_memory_mb, 0) + " MB allowed (--ccw16-memory) it ran on a coarser " +
                            std::to_string(bm.mesh->vertex_count()) + "-vertex mesh of the shape (" + fixed(bm.mb, 0) +
                            " MB), and its distances, distortion and time are measured at that mesh's vertices."
                      : " (within the " + fixed(o.ccw16_memory_mb, 0) + " MB allowed, --ccw16-memory)."));
  }
  line();
  line("## Table 1: Hessian PSD projection");
  line();
  line("Delete: H = H\xe2\x82\x82 only; FullProj: eigen-decomposition of H\xe2\x82\x81 + H\xe2\x82\x82 per sample; PartProj: the "
       "analytic projection of H\xe2\x82\x81 (ours). \"Cold\": the frame at the middle of the keyframe interval solved from the "
       "interval's first keyframe (the paper's setting); \"sequence\": " + std::to_string(o.table_frames) +
       " frames, each warm-started from the previous one.");
  line();
  line("| projection | Newton core | cold: #iter | cold: ms | sequence: mean #iter | max #iter | mean ms per frame | certified |");
  line("|---|---|---|---|---|---|---|---|");
  for (const OurRun& r : table1)
    line("| " + r.label + " | " + r.core + " | " + std::to_string(r.cold.iterations) + " | " + fixed(r.cold.ms, 1) + " | " +
         fixed(r.summary.mean_iterations, 2) + " | " + std::to_string(r.max_iterations) + " | " + fixed(r.summary.mean_ms, 1) + " | " +
         std::to_string(r.summary.certified) + "/" + std::to_string(r.summary.frames) + " |");
  line();
  line("## Table 2: Hessian sample ratio r");
  line();
  line("|H| = r |G|, PartProj, " + std::to_string(o.table_frames) + " warm-started frames.");
  line();
  line("| r | \\|H\\| | mean #iter | max #iter | mean ms per frame | certified |");
  line("|---|---|---|---|---|---|");
  for (const OurRun& r : table2)
    line("| " + sci(r.ratio) + " | " + std::to_string(r.hessian_samples) + " | " + fixed(r.summary.mean_iterations, 2) + " | " +
         std::to_string(r.max_iterations) + " | " + fixed(r.summary.mean_ms, 1) + " | " + std::to_string(r.summary.certified) + "/" +
         std::to_string(r.summary.frames) + " |");
  line();
  line("## Table 3: time per frame against the render mesh's resolution");
  line();
  line("Ours: the solve works on boundary samples and does not see the mesh (mean of the sequence); drawing a frame at the mesh "
       "adds f at its vertices, on the CPU (basis rows evaluated per frame, no caching) or with the Vulkan dense evaluation on " +
       vulkan_device + ". ARAP: one sparse solve per frame after a factorisation made once per mesh. Times are means over " +
       std::to_string(timed.size()) + " frames.");
  line();
  line("| vertices | triangles | ARAP factorisation ms | ARAP ms per frame | ours solve ms | ours f at vertices, CPU ms | ours f at vertices, Vulkan ms | ours total (CPU) ms | ARAP / ours solve |");
  line("|---|---|---|---|---|---|---|---|---|");
  for (const T3& r : t3)
    line("| " + std::to_string(r.vertices) + " | " + std::to_string(r.triangles) + " | " + fixed(r.arap_factor_ms, 0) + " | " +
         fixed(r.arap_ms, 1) + " | " + fixed(ours_sum.mean_ms, 1) + " | " + fixed(r.ours_eval_cpu_ms, 1) + " | " +
         fixed(r.ours_eval_vk_ms, 1) + " | " + fixed(ours_sum.mean_ms + r.ours_eval_cpu_ms, 1) + " | " +
         sci(r.arap_ms / ours_sum.mean_ms) + " |");
  if (t3.empty()) line("| (no resolutions requested) | | | | | | | | |");
  line();
  line("## Table 4: time per frame against ARAP");
  line();
  line("At the " + std::to_string(mesh.vertex_count()) + "-vertex mesh, means over the " + std::to_string(F) + " frames of the sequence" +
       (bm.own_mesh ? " (CCW16 (boundary metric): at its " + std::to_string(bm.mesh->vertex_count()) + "-vertex mesh)" : std::string()) +
       (bm.applies ? "." : "; CCW16 (boundary metric) does not apply to a shape with holes."));
  line();
  line("![time per frame](frame_time.png)");
  line();
  line("| ARAP ms | CCW16 (log derivatives) ms | CCW16 (boundary metric) ms | ours solve ms | ours #iter | ours solve + f at vertices (CPU) ms | ARAP / ours solve | ARAP / ours solve + f |");
  line("|---|---|---|---|---|---|---|---|");
  line("| " + fixed(arap_frame_ms, 2) + " | " + fixed(ccw_frame_ms, 2) + " | " + (bm.applies ? fixed(mean_of(bm_ms), 2) : std::string("n/a")) +
       " | " + fixed(ours_sum.mean_ms, 2) + " | " +
       fixed(ours_sum.mean_iterations, 2) + " | " + fixed(ours_sum.mean_ms + ours_eval_default_ms, 2) + " | " +
       sci(arap_frame_ms / ours_sum.mean_ms) + " | " + sci(arap_frame_ms / (ours_sum.mean_ms + ours_eval_default_ms)) + " |");
  line();
  line("Raw numbers: [report.json](report.json). Made by `hsi compare` in " + fixed(s_since(t_start), 1) + " s.");
  write_file_atomic(out.add("report.md"), md);
  out.commit();
  stage(t_start, "wrote %s/report.md with 3 side-by-side figures, %d plots and Tables 1-4 (report.json: raw numbers)",
        out.dir().string().c_str(), bm.applies ? 4 : 3);
  std::printf("%s/report.md\n", out.dir().string().c_str());
}

}  // namespace
#endif

void register_compare(CLI::App& app) {
#ifdef HSI_COMPARE
  auto o = std::make_shared<Opts>();
#endif
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "Reproduce the paper's comparisons on one scene, measured on this machine: ours, ARAP and CCW16 (log\n"
      "derivatives; on a simply-connected shape also its boundary-metric variant, the paper's Fig. 8) side by\n"
      "side with the distortion colour map at t = 0.25, 0.5, 0.75 of a keyframe interval, each method's largest\n"
      "distortion over the sequence against the keyframes' bounds, and Tables 1-4 (Hessian projections, the\n"
      "Hessian sample ratio, time against mesh resolution and against ARAP). Writes PNGs, report.json and\n"
      "report.md (last; a failed run leaves no report) into DIR.");
#ifdef HSI_COMPARE
  cmd->add_option("scene", o->scene, "Scene file (.json) with two or more keyframes")->required();
  cmd->add_option("-o,--output", o->out, "Output folder")->required();
  cmd->add_option("--frames", o->frames, "Frames over the keyframes' range for the distortion plots")
      ->capture_default_str()->check(CLI::Range(2, 100000));
  cmd->add_option("--table-frames", o->table_frames, "Frames of each sequence of Tables 1 and 2")
      ->capture_default_str()->check(CLI::Range(2, 100000));
  cmd->add_option("--mesh-vertices", o->mesh_vertices, "Vertices of the mesh the baselines run on and the figures use (about)")
      ->capture_default_str()->check(CLI::Range(100, 5000000));
  cmd->add_option("--samples", o->samples, "Boundary samples |G| (default: the scene's)")->check(CLI::Range(100, 10000000));
  cmd->add_option("--size", o->size, "Longer side of each panel of the side-by-side figures, in pixels")->capture_default_str();
  cmd->add_option("--segment", o->segment, "Keyframe interval of the side-by-side figures (0: keyframes 0 to 1)")->capture_default_str();
  cmd->add_option("--ratios", o->ratios, "Hessian sample ratios r of Table 2")->capture_default_str()->delimiter(',');
  cmd->add_option("--table3-vertices", o->table3_vertices, "Mesh resolutions of Table 3 (vertices, about)")
      ->capture_default_str()->delimiter(',');
  cmd->add_option("--ccw16-memory", o->ccw16_memory_mb,
                  "MB of basis rows CCW16's boundary-metric variant may hold (it keeps them at every vertex and quadrature\n"
                  "node: ~300 MB at 10k vertices); above it, that variant runs on a coarser mesh and the report says so")
      ->capture_default_str()->check(CLI::Range(1.0, 1e6));
  cmd->add_flag("--no-800k", o->no_800k, "Skip Table 3's rows of 800k vertices or more (a quick run)");
  cmd->add_option("--timing-frames", o->timing_frames, "Frames timed per resolution in Table 3")
      ->capture_default_str()->check(CLI::Range(1, 1000));
  cmd->add_option("--backend", o->backend, "Newton core for our solves: cpu, cuda, or auto (CUDA when a device is present)")
      ->capture_default_str()->check(CLI::IsMember({"cpu", "cuda", "auto"}));
  cmd->add_option("--device", o->device, "Vulkan device name substring (default: HSI_VULKAN_DEVICE, else the best)");
  cmd->add_flag("--validation", o->validation, "Run with the Vulkan validation layer; fail on any message");
  cmd->callback([o] { run_compare(*o); });
#else
  cmd->allow_extras();
  cmd->callback([] {
    throw std::runtime_error("this hsi was built without Vulkan (compute/) or the baselines (engine/baselines/), which hsi compare needs");
  });
#endif
}

}  // namespace hsi::cli
