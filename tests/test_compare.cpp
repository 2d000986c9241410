// The comparison library (compare/, hsi compare) stage by stage on small synthetic input:
// Tables 1–4 from made-up run results (values, ratios, markdown), Fig. 8's alignment
// recovering a known rigid motion, the keyframes' envelope on a mesh, each of the paper's
// claims decided on made-up runs where the answer is known, report.json carrying the
// fields the README lists, and a figure and a plot written at the expected size. No
// solve, no Vulkan device: seconds.
#include <catch2/catch.hpp>
#include <cmath>
#include <complex>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "hsi/compare/alignment.h"
#include "hsi/compare/figures.h"
#include "hsi/compare/outputs.h"
#include "hsi/compare/report.h"
#include "hsi/compare/tables.h"
#include "hsi/rigid_fit.h"

using namespace hsi;
using namespace hsi::compare;
using Catch::Matchers::Contains;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

OurRun made_run(const std::string& label, double ratio, int cold_it, double cold_ms, double mean_it, int max_it, double mean_ms,
                int certified, int frames) {
  OurRun r;
  r.label = label;
  r.core = "cpu";
  r.ratio = ratio;
  r.hessian_samples = static_cast<int>(std::lround(ratio * 1000));
  r.cold.iterations = cold_it;
  r.cold.ms = cold_ms;
  r.cold.certified = true;
  r.summary.mean_iterations = mean_it;
  r.summary.mean_ms = mean_ms;
  r.summary.max_ms = 2 * mean_ms;
  r.summary.certified = certified;
  r.summary.frames = frames;
  r.max_iterations = max_it;
  return r;
}

// A row of Table 3 without GE's columns (GE not timed: NaN).
Table3Row made_row(int vertices, int triangles, double mesh_s, double arap_factor_ms, double arap_ms, double cpu_ms, double gpu_ms) {
  Table3Row r;
  r.vertices = vertices;
  r.triangles = triangles;
  r.mesh_s = mesh_s;
  r.arap_factor_ms = arap_factor_ms;
  r.arap_ms = arap_ms;
  r.ours_eval_cpu_ms = cpu_ms;
  r.ours_eval_gpu_ms = gpu_ms;
  return r;
}

// The width and height a PNG file's header gives.
std::pair<int, int> png_size(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  unsigned char h[24] = {};
  in.read(reinterpret_cast<char*>(h), sizeof h);
  REQUIRE(in.gcount() == 24);
  REQUIRE(h[1] == 'P');
  REQUIRE(h[2] == 'N');
  auto be = [&](int i) { return (h[i] << 24) | (h[i + 1] << 16) | (h[i + 2] << 8) | h[i + 3]; };
  return {be(16), be(20)};
}

std::filesystem::path fresh_dir(const std::string& name) {
  const auto d = std::filesystem::path(HSI_TEST_TMP) / "compare" / name;
  std::filesystem::remove_all(d);
  return d;
}

// A per-frame record of `n` frames with keyframes at t = 0 and 1 (the ends).
PerFrame made_frames(int n, bool boundary_metric) {
  PerFrame p;
  for (int i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / (n - 1), bump = std::sin(M_PI * t);
    p.t.push_back(t);
    p.keyframe.push_back(i == 0 || i == n - 1);
    p.our_kappa.push_back(1.2 + 0.1 * bump);
    p.our_kappa_c.push_back(1.25 + 0.1 * bump);
    p.bound_kappa.push_back(1.4);
    p.bound_kappa_c.push_back(1.45);
    p.our_iso.push_back(4.1 + bump);
    p.our_iso_c.push_back(4.2 + bump);
    p.bound_iso.push_back(5.5);
    p.bound_iso_c.push_back(5.6);
    p.our_ms.push_back(p.keyframe.back() ? kNaN : 90 + i);
    p.our_iters.push_back(p.keyframe.back() ? 0 : 5);
    // On the mesh, per triangle: the keyframes' envelope, ours there, and the mesh methods.
    // As made, the claims come out: ARAP does not fail (κ at most 1.6 / 1.45 of the
    // keyframes', no flip), FFMP scales (a triangle 30% smaller than both keyframes', ours 2%), GE is
    // close (0.5% of the size) with a 5% κ peak, ours within its bounds.
    p.mesh_bound_kappa.push_back(1.45);
    p.mesh_bound_iso.push_back(5.6);
    p.ours_mesh_kappa.push_back(1.22 + 0.1 * bump);
    p.ours_mesh_iso.push_back(4.1 + bump);
    p.ours_mesh_shrink.push_back(0.02 * bump);
    p.arap_kappa.push_back(1.3 + 0.3 * bump);
    p.arap_iso.push_back(4.3 + 2 * bump);
    p.arap_ms.push_back(2.0);
    p.arap_flipped.push_back(0);
    p.arap_shrink.push_back(0.05 * bump);
    p.ffmp_kappa.push_back(1.3 + 0.5 * bump);
    p.ffmp_iso.push_back(4.3 + 3 * bump);
    p.ffmp_ms.push_back(200.0);
    p.ffmp_flipped.push_back(0);
    p.ffmp_shrink.push_back(0.3 * bump);
    p.ge_kappa.push_back(1.45 * (1 + 0.05 * bump));
    p.ge_iso.push_back(4.2 + bump);
    p.ge_ms.push_back(p.keyframe.back() ? kNaN : 800.0);
    p.ge_iters.push_back(3);
    p.ge_flipped.push_back(0);
    p.ge_shrink.push_back(0.04 * bump);
    p.ge_converged.push_back(1);
    p.ge_dist.push_back(0.005 * bump);
    p.ccw_kappa.push_back(1.25 + 0.2 * bump);
    p.ccw_iso.push_back(4.2 + bump);
    p.ccw_ms.push_back(5.0);
    p.ccw_period.push_back(boundary_metric ? 0 : 0.01 * bump);
    p.bm_kappa.push_back(boundary_metric ? 1.21 + 0.1 * bump : kNaN);
    p.bm_iso.push_back(boundary_metric ? 4.1 + bump : kNaN);
    p.bm_ms.push_back(boundary_metric ? 80.0 : kNaN);
    p.bm_fit.push_back(boundary_metric ? 1e-4 : kNaN);
    p.ccw_dist.push_back(boundary_metric ? 0.05 * bump : kNaN);
    p.bm_dist.push_back(boundary_metric ? 1e-4 * bump + 1e-6 : kNaN);
  }
  return p;
}

// The one made-up comparison the report and claims tests start from: 5 frames (made_frames),
// every frame of ours certified and within its bounds, GE 800 ms per frame against our 40 ms
// solve (20×, below the paper's 20.6×), a shape with a hole or a simply-connected one.
Comparison made_comparison(bool simply_connected) {
  Comparison c;
  c.scene_path = "assets/made_up.json";
  c.name = "made_up";
  c.date = "2026-01-01 00:00:00 UTC";
  c.vulkan_device = "llvmpipe (CPU)";
  c.machine = {"a CPU", 2};
  c.holes = simply_connected ? 0 : 1;
  c.loops = 1 + c.holes;
  c.size = 2;
  c.times = {0, 1};
  c.keyframes = {{0, {}, {}}, {1, {}, {}}};
  c.frames = 5;
  c.table_frames = 4;
  c.samples = 800;
  c.hessian_samples = 160;
  c.hessian_ratio = 0.2;
  c.mesh_vertices = 1500;
  c.mesh_triangles = 2800;
  c.ccw16_memory_mb = 30;
  c.core = "cpu";
  c.panel_width = 200;
  c.panel_height = 138;
  c.per_frame = made_frames(5, simply_connected);
  c.ours.frames = c.ours.certified = c.ours.within_certified_bounds = c.ours_within_bound = 5;
  c.ours.mean_ms = 40;
  c.ours.mean_iterations = 3;
  c.keyframes_max_turn = 2.0;  // about 115°: a large rotation
  c.bm.applies = simply_connected;
  c.bm.why_not = simply_connected ? "" : "CCW16 (boundary metric) does not apply: 1 hole";
  c.bm.mesh_vertices = 900;
  c.bm.own_mesh = true;
  for (const double u : {0.25, 0.5, 0.75}) {
    Snapshot s;
    s.u = u;
    s.t = u;
    char png[64];
    std::snprintf(png, sizeof png, "side_by_side_t%.2f.png", u);
    s.png = png;
    s.width = 640;
    s.height = 300;
    s.ccw.hole_period = simply_connected ? std::vector<double>{} : std::vector<double>{0.02};
    s.ccw.seam_jump = s.ccw.hole_period;
    s.ge_iterations = 3;
    c.snaps.push_back(s);
  }
  c.table1 = {made_run("partproj", 0.2, 6, 49, 6.5, 7, 57, 4, 4)};
  c.table2 = {made_run("r = 0.5", 0.5, 6, 49, 6.5, 7, 57, 4, 4)};
  c.table3 = {made_row(1500, 2800, 0.1, 16, 0.2, 8, 13)};
  c.table3[0].ge_ms = 150;
  c.table3[0].ge_iterations = 3;
  c.table3_context = {40, 3, 1, c.vulkan_device, ""};
  c.table4 = {};
  c.table4.mesh_vertices = 1500;
  c.table4.arap_ms = 2;
  c.table4.ffmp_ms = 200;
  c.table4.ge_ms = 800;
  c.table4.ge_iterations = 3;
  c.table4.ours_solve_ms = 40;
  c.table4.ours_iterations = 3;
  c.claims = decide_claims(c);
  return c;
}

// The claim `id` of a comparison, decided afresh.
Claim claim(const Comparison& c, const std::string& id) {
  for (const Claim& k : decide_claims(c))
    if (k.id == id) return k;
  FAIL("no claim " << id);
  return {};
}

}  // namespace

TEST_CASE("tables 1 and 2 from run results: values and markdown rows", "[compare]") {
  const std::vector<OurRun> t1 = {made_run("delete", 0.2, 7, 251.84, 10.0, 14, 88.66, 4, 4),
                                  made_run("partproj", 0.2, 6, 49.1, 6.5, 7, 57.12, 3, 4)};
  const std::string md1 = table1_markdown(t1, 4);
  CHECK_THAT(md1, Contains("## Table 1: Hessian PSD projection"));
  CHECK_THAT(md1, Contains("\"sequence\": 4 frames, each warm-started"));
  CHECK_THAT(md1, Contains("| delete | cpu | 7 | 251.8 | 10.00 | 14 | 88.7 | 4/4 |\n"));
  CHECK_THAT(md1, Contains("| partproj | cpu | 6 | 49.1 | 6.50 | 7 | 57.1 | 3/4 |\n"));  // an uncertified frame shows
  const std::string md2 = table2_markdown({made_run("r = 0.05", 0.05, 6, 40, 7.25, 9, 31.04, 4, 4)}, 4);
  CHECK_THAT(md2, Contains("| 0.05 | 50 | 7.25 | 9 | 31.0 | 4/4 |\n"));
  const nlohmann::json j = run_json(t1[1]);
  CHECK(j["label"] == "partproj");
  CHECK(j["hessian_samples"] == 200);
  CHECK(j["cold_iterations"] == 6);
  CHECK(j["certified"] == 3);
  CHECK(j["max_iterations"] == 7);
  CHECK(j["mean_ms"].get<double>() == Approx(57.12));
  // The summary with hsi interpolate's field names: flags such as not converged never left out.
  for (const char* key : {"frames", "uncertified", "not_converged", "overlapping", "frames_within_keyframe_bounds", "total_s"})
    CHECK(j.contains(key));
  CHECK(j["frames"].is_number_integer());
}

TEST_CASE("table 3: GE and ARAP against our solve per resolution, GE not run above its limit, the GPU column or why it is missing",
          "[compare]") {
  std::vector<Table3Row> rows(3);
  rows[0] = made_row(8000, 15000, 0.5, 160, 4, 50, 5);
  rows[1] = made_row(80000, 159000, 3, 2400, 60, 520, 20);
  rows[2] = made_row(800000, 1590000, 30, 44000, 850, 5200, 90);
  rows[0].ge_ms = 400;
  rows[0].ge_iterations = 3;
  rows[1].ge_ms = 5000;
  rows[1].ge_iterations = 3.5;
  rows[1].ge_not_converged = 1;
  // Above --ge-max-vertices: not run, estimated from the largest row GE ran at (80k: 5 s × 10).
  rows[2].ge_not_run = ge_not_run_note(800000, 200000, {rows[0], rows[1]});
  CHECK(rows[2].ge_not_run == "not run: above 200000 vertices (--ge-max-vertices); est. 50 s/frame (80000-vertex row \xc3\x97 10.0)");
  CHECK(ge_not_run_note(800000, 200000, {}) == "not run: above 200000 vertices (--ge-max-vertices)");
  Table3Context c{340, 3, 3, "llvmpipe (CPU)", ""};
  std::string md = table3_markdown(rows, c);
  CHECK_THAT(md, Contains("with the Vulkan dense evaluation on llvmpipe (CPU)."));
  CHECK_THAT(md, Contains("Times are means over 3 frames."));
  // GE / ours solve: 400 / 340; ARAP / ours solve: 4 / 340 and 850 / 340; ours total = solve + f at the vertices.
  // f at the vertices from cached rows on the CPU; no CUDA evaluator: n/a, and the total uses the CPU.
  CHECK_THAT(md, Contains("| 8000 | 15000 | 400.0 | 3.0 | 340.0 | 3.00 | 1.18 | 160 | 4.0 | 50.000 | n/a | 5.0 | 390.00 | 0.0118 | 0.0103 |\n"));
  CHECK_THAT(md, Contains("| 80000 | 159000 | 5000.0 (1 not converged) | 3.5 | 340.0 | 3.00 | 14.7 | 2400 |"));
  CHECK_THAT(md, Contains("| 800000 | 1590000 | " + rows[2].ge_not_run +
                          " | n/a | 340.0 | 3.00 | n/a | 44000 | 850.0 | 5200.000 | n/a | 90.0 | 5540.00 | 2.5 | 0.153 |\n"));
  CHECK_THAT(md, Contains("(mean of the sequence)"));
  nlohmann::json j = table3_json(rows, c);
  CHECK(j.size() == 3);
  CHECK(j[2]["ours_total_cpu_ms"].get<double>() == Approx(5540));
  CHECK(j[2]["ours_total_ms"].get<double>() == Approx(5540));
  CHECK(j[2]["ours_eval_cuda_ms"] == "nan");
  CHECK(j[2]["arap_factorisation_ms"].get<double>() == Approx(44000));
  CHECK(j[0]["ge_ms"].get<double>() == 400);
  CHECK(j[0]["ge_over_ours_solve"].get<double>() == Approx(400.0 / 340));
  CHECK(j[1]["ge_not_converged"] == 1);
  CHECK(j[2]["ge_run"] == false);
  CHECK(j[2]["ge_ms"].is_null());
  CHECK(j[2]["ge_not_run"] == rows[2].ge_not_run);
  // Our solve on CUDA: f at the vertices on the GPU counts in the total; the block timing is named.
  rows[2].ours_eval_cuda_ms = 2;
  c.ours_timing = "timed in one block: 10 warm-up frames";
  md = table3_markdown(rows, c);
  CHECK_THAT(md, Contains("| 44000 | 850.0 | 5200.000 | 2.000 | 90.0 | 342.00 | 2.5 | 2.49 |\n"));
  CHECK_THAT(md, Contains("(timed in one block: 10 warm-up frames)"));
  j = table3_json(rows, c);
  CHECK(j[2]["ours_total_cpu_ms"].get<double>() == Approx(5540));
  CHECK(j[2]["ours_total_ms"].get<double>() == Approx(342));
  rows[2].ours_eval_cuda_ms = kNaN;
  c.ours_timing.clear();

  for (Table3Row& r : rows) r.ours_eval_gpu_ms = kNaN;
  c.gpu_unavailable = "this hsi was built without Vulkan";
  md = table3_markdown(rows, c);
  CHECK_THAT(md, Contains("the Vulkan dense evaluation is not available (this hsi was built without Vulkan)"));
  CHECK_THAT(md, Contains("| 50.000 | n/a | n/a | 390.00 |"));
  CHECK(table3_json(rows, c)[0]["ours_eval_vulkan_ms"] == "nan");
  CHECK_THAT(table3_markdown({}, c), Contains("| (no resolutions requested) |"));
}

TEST_CASE("table 4: time per frame against ARAP, FFMP and GE, ratios, the boundary-metric variant or n/a", "[compare]") {
  Table4 t;
  t.mesh_vertices = 10700;
  t.arap_ms = 2;
  t.ffmp_ms = 250;
  t.ge_ms = 6800;
  t.ge_iterations = 3.5;
  t.ge_frames = 98;
  t.ge_cold_iterations = 12;
  t.ours_cold_iterations = 6;
  t.ccw16_ms = 12;
  t.ours_solve_ms = 340;
  t.ours_iterations = 5.75;
  t.ours_eval_cpu_ms = 60;
  CHECK(t.ours_total_ms() == 400);
  CHECK(t.arap_over_ours_solve() == Approx(2.0 / 340));
  CHECK(t.arap_over_ours_total() == Approx(0.005));
  CHECK(t.ge_over_ours_solve() == Approx(20));
  CHECK(t.ge_over_ours_total() == Approx(17));
  std::string md = table4_markdown(t, 100);
  CHECK_THAT(md, Contains("At the 10700-vertex mesh, means over the 100 frames of the sequence; CCW16 (boundary metric) does not apply"));
  CHECK_THAT(md, Contains("| 2.00 | 250.00 | 6800.00 | 3.50 | 340.00 | 5.75 | 400.00 | 12.00 | n/a | 0.00588 | 0.005 | 20 | 17 |\n"));
  CHECK_THAT(md, Contains("GE: 0 of 98 frames not converged. Solved cold"));
  CHECK_THAT(md, Contains("GE 12 iterations"));
  nlohmann::json j = table4_json(t);
  CHECK(j["ccw16_boundary_metric_ms"].is_null());
  CHECK(j["arap_over_ours_total"].get<double>() == Approx(0.005));
  // f at the vertices on CUDA (our solve's backend) counts in the total; the CPU's is named too.
  t.ours_eval_cuda_ms = 0.5;
  t.ours_timing = "timed in one block: 10 warm-up frames";
  CHECK(t.ours_total_ms() == Approx(340.5));
  md = table4_markdown(t, 100);
  CHECK_THAT(md, Contains("Ours: timed in one block: 10 warm-up frames (f at the vertices on the CPU instead: 60.000 ms)."));
  CHECK_THAT(md, Contains("| 340.00 | 5.75 | 340.50 |"));
  j = table4_json(t);
  CHECK(j["ours_total_ms"].get<double>() == Approx(340.5));
  CHECK(j["ours_total_cpu_ms"].get<double>() == Approx(400));
  t.ours_eval_cuda_ms = kNaN;
  t.ours_timing.clear();
  CHECK(j["ffmp_ms"].get<double>() == 250);
  CHECK(j["ge_iterations"].get<double>() == 3.5);
  CHECK(j["ge_cold_iterations"].get<double>() == 12);

  t.boundary_metric = true;
  t.ccw16_bm_ms = 80;
  t.ccw16_bm_own_mesh = true;
  t.ccw16_bm_mesh_vertices = 4200;
  md = table4_markdown(t, 100);
  CHECK_THAT(md, Contains("(CCW16 (boundary metric): at its 4200-vertex mesh)."));
  CHECK_THAT(md, Contains("| 12.00 | 80.00 | 0.00588 |"));
  j = table4_json(t);
  CHECK(j["ccw16_boundary_metric_ms"].get<double>() == 80);
  CHECK(j["ccw16_boundary_metric_mesh_vertices"] == 4200);
}

TEST_CASE("the keyframes on a mesh: their distortion, areas and turn, against which a frame is held", "[compare]") {
  TriMesh mesh;
  mesh.vertices = {{0, 0}, {1, 0}, {0, 1}};
  mesh.triangles = {{0, 1, 2}};
  // Keyframe 0: the rest triangle; keyframe 1: scaled by 2 (area × 4) and turned by 100°.
  const cd turn = std::polar(2.0, 100 * M_PI / 180);
  std::vector<baselines::MeshKeyframe> keys = {{0, mesh.vertices}, {1, {}}};
  for (const cd& z : mesh.vertices) keys[1].positions.push_back(turn * z);
  const MeshKeyframes m = mesh_keyframes(mesh, keys);
  CHECK(m.max_turn == Approx(100 * M_PI / 180));
  CHECK(m.shape[1].det[0] == Approx(4));
  CHECK(m.kappa_bound(0.5) == Approx(1));  // both similarities
  // A frame stretched along x by s: area ratio s, κ s.
  auto stretched = [&](double s) {
    std::vector<cd> x;
    for (const cd& z : mesh.vertices) x.emplace_back(s * z.real(), z.imag());
    return triangle_shape(mesh, x);
  };
  CHECK(stretched(3).det[0] == Approx(3));
  CHECK(stretched(3).turn[0] == Approx(0).margin(1e-12));
  CHECK(m.area_shrink(0.5, stretched(2)) == 0);            // within [1, 4]
  CHECK(m.area_shrink(0.5, stretched(0.5)) == Approx(1));  // 1 / 0.5 − 1
  CHECK(m.area_shrink(0.5, stretched(5)) == 0);            // growing beyond both keyframes does not count
  CHECK(std::isinf(m.area_shrink(0.5, stretched(-1))));    // flipped
}

TEST_CASE("claims: each decided on made-up runs where the answer is known", "[compare]") {
  const Comparison base = made_comparison(false);
  REQUIRE(base.claims.size() == 5);
  SECTION("ARAP fails: a flipped triangle or κ above twice the keyframes' on the mesh") {
    Comparison c = base;
    Claim k = claim(c, "arap_fails");
    CHECK_FALSE(k.holds);  // at most 1.6 / 1.45 of the keyframes'
    CHECK(k.value == Approx(1.6 / 1.45));
    CHECK(k.threshold == 2);
    c.per_frame.arap_flipped[2] = 3;
    CHECK(claim(c, "arap_fails").holds);
    c.per_frame.arap_flipped[2] = 0;
    c.per_frame.arap_kappa[3] = 3.0;  // 3.0 / 1.45 > 2
    CHECK(claim(c, "arap_fails").holds);
    c.per_frame.arap_kappa[3] = 2.8;  // 2.8 / 1.45 < 2
    CHECK_FALSE(claim(c, "arap_fails").holds);
    c.keyframes_max_turn = 0.5;  // about 29°: the claim's condition is not met, and the evidence says so
    CHECK_THAT(claim(c, "arap_fails").evidence, Contains("no large rotation in this scene"));
  }
  SECTION("FFMP scales unnaturally: a triangle more than 10% smaller than both keyframes', and more than ours") {
    Comparison c = base;
    CHECK(claim(c, "ffmp_scales").holds);
    CHECK(claim(c, "ffmp_scales").value == Approx(0.3));
    for (double& v : c.per_frame.ffmp_shrink) v *= 0.3;  // 9%
    CHECK_FALSE(claim(c, "ffmp_scales").holds);
    c = base;
    for (double& v : c.per_frame.ours_mesh_shrink) v *= 20;  // ours 40%: FFMP no worse than ours
    CHECK_FALSE(claim(c, "ffmp_scales").holds);
  }
  SECTION("GE is close to ours but with distortion peaks") {
    Comparison c = base;
    Claim k = claim(c, "ge_close_with_peaks");
    CHECK(k.holds);
    CHECK(k.value == Approx(0.05));
    for (double& v : c.per_frame.ge_dist) v *= 10;  // 5% of the size: not close
    k = claim(c, "ge_close_with_peaks");
    CHECK_FALSE(k.holds);
    CHECK(k.verdict == "does not hold: peaks, but not close");
    c = base;
    c.per_frame.ge_kappa = c.per_frame.mesh_bound_kappa;  // at the keyframes' envelope: no peak
    k = claim(c, "ge_close_with_peaks");
    CHECK_FALSE(k.holds);
    CHECK(k.verdict == "does not hold: close, but no distortion peak");
  }
  SECTION("ours stays within the keyframes' bounds: certified, or only as sampled") {
    Comparison c = base;
    Claim k = claim(c, "ours_within_bounds");
    CHECK(k.holds);
    CHECK(k.verdict == "holds (certified)");
    c.ours.within_certified_bounds = 4;
    c.ours.max_certified_bound_excess = 0.02;
    k = claim(c, "ours_within_bounds");
    CHECK_FALSE(k.holds);
    CHECK(k.verdict == "holds only as sampled");
    CHECK(k.value == Approx(0.02));
    c.ours_within_bound = 4;
    CHECK(claim(c, "ours_within_bounds").verdict == "does not hold");
    c = base;
    c.ours.certified = 4;  // an uncertified frame: not within, certified
    CHECK_FALSE(claim(c, "ours_within_bounds").holds);
  }
  SECTION("ours faster than GE by the paper's margin (20.6x, its Table 4's smallest)") {
    Comparison c = base;
    Claim k = claim(c, "ours_faster_than_ge");
    CHECK(k.threshold == Approx(20.58).epsilon(1e-3));
    CHECK(k.value == Approx(20));  // 800 / 40
    CHECK_FALSE(k.holds);
    CHECK(k.verdict == "does not hold: faster, but by less");
    c.table4.ge_ms = 830;  // 20.75
    CHECK(claim(c, "ours_faster_than_ge").holds);
    c.table4.ge_ms = 30;
    CHECK(claim(c, "ours_faster_than_ge").verdict == "does not hold");
  }
  const nlohmann::json j = claims_json(base.claims);
  CHECK(j.size() == 5);
  CHECK(j[0]["id"] == "arap_fails");
  CHECK(j[1]["holds"] == true);
  const std::string md = claims_markdown(base.claims);
  CHECK_THAT(md, Contains("## Claims"));
  CHECK_THAT(md, Contains("| FFMP scales unnaturally | **holds** | 0.3 | 0.1 |"));
  CHECK_THAT(md, Contains("| ARAP fails under large rotations | **does not hold** |"));
}

TEST_CASE("Fig. 8 alignment recovers a known rigid motion", "[compare]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<cd> a, b;
  const cd rotation = std::polar(1.0, 2.3), shift(1e4, -3e3);  // far from the origin: the residual is formed about the centroids
  for (int i = 0; i < 200; ++i) {
    a.emplace_back(u(rng), u(rng));
    b.push_back(rotation * a.back() + shift);
  }
  const RigidMotion m = rigid_fit(a, b);
  CHECK(std::abs(m.rotation - rotation) < 1e-10);
  for (size_t i = 0; i < a.size(); i += 37) CHECK(std::abs(m(a[i]) - b[i]) < 1e-9);
  const Gap g = point_gap(a, b, 2.0);
  CHECK(g.raw > 1e3);          // as given: the shift
  CHECK(g.rigid < 1e-12 * 1e4);  // after alignment: rounding of the shift
  // A non-rigid part stays: stretch one point by 0.1; the best fit leaves at most that.
  b[5] += rotation * cd(0.1, 0);
  const Gap h = point_gap(a, b, 2.0);
  CHECK(h.rigid > 0.01 / 2.0);
  CHECK(h.rigid < 0.1 / 2.0);
  CHECK_THROWS_AS(rigid_fit(a, std::vector<cd>(3)), InputError);

  // Over the sequence: the largest distance and its time; between keyframes without their frames.
  const PerFrame p = made_frames(5, true);
  std::vector<double> dist = {0.0, 0.2, 0.1, 0.05, 0.3};  // the largest at a keyframe (the last frame)
  const std::vector<Gap> at = {{0.4, 0.01}, {0.5, 0.02}, {0.3, 0.015}};
  const Fig8 f = fig8(at, dist, p.t, p.keyframe);
  CHECK(f.raw == 0.5);
  CHECK(f.rigid == 0.02);
  CHECK(f.sequence_rigid == 0.3);
  CHECK(f.sequence_t == 1.0);
  CHECK(f.between_keyframes_rigid == 0.2);
}

TEST_CASE("report.json carries the fields the README lists; report.md embeds the figures", "[compare]") {
  for (const bool simply_connected : {false, true}) {
    const Comparison c = made_comparison(simply_connected);
    const nlohmann::json j = report_json(c);
    INFO((simply_connected ? "simply connected" : "with a hole"));
    for (const char* key : {"scene", "name", "holes", "date", "machine", "settings", "keyframes", "distortion_kinds", "sequence",
                            "ccw16_variants", "summary", "side_by_side", "fig8", "colour_range", "table1_projection",
                            "table2_ratio", "table3_resolution", "table4_per_frame", "claims", "total_s"})
      CHECK(j.contains(key));
    // Every baseline's columns: per frame, summed up, at the side-by-side times, in Tables 3-4.
    for (const char* method : {"arap", "ffmp", "ge", "ccw16", "keyframes_on_mesh", "ours_on_mesh"}) {
      CHECK(j["sequence"][method]["kappa"].size() == 5);
      CHECK(j["summary"][method].contains("max_kappa"));
    }
    for (const char* method : {"arap", "ffmp", "ge", "ccw16"}) CHECK(j["side_by_side"][0].contains(method));
    CHECK(j["sequence"]["ge"]["iterations"].size() == 5);
    CHECK(j["summary"]["ffmp"]["max_area_shrink"].get<double>() == Approx(0.3));
    CHECK(j["table3_resolution"][0]["ge_ms"].get<double>() == 150);
    CHECK(j["table3_resolution"][0]["ge_iterations"].get<double>() == 3);
    CHECK(j["table4_per_frame"]["ffmp_ms"].get<double>() == 200);
    CHECK(j["table4_per_frame"]["ge_over_ours_solve"].get<double>() == Approx(20));
    CHECK(j["claims"].size() == 5);
    for (const nlohmann::json& k : j["claims"])
      for (const char* key : {"id", "claim", "holds", "verdict", "value", "threshold", "definition", "evidence"}) CHECK(k.contains(key));
    CHECK(j["machine"]["vulkan_device"] == "llvmpipe (CPU)");
    CHECK(j["settings"]["panel_size"] == nlohmann::json({200, 138}));
    CHECK(j["sequence"]["t"].size() == 5);
    CHECK(j["side_by_side"].size() == 3);
    CHECK(j["side_by_side"][1]["png"] == "side_by_side_t0.50.png");
    CHECK(j["side_by_side"][1]["image_size"] == nlohmann::json({640, 300}));
    // What each CCW16 variant blends, its mesh and memory, or why it does not apply.
    const nlohmann::json& bm = j["ccw16_variants"]["boundary_metric"];
    CHECK(bm["blends"] == kBmBlends);
    CHECK(j["ccw16_variants"]["log_derivatives"]["blends"] == kLogBlends);
    CHECK(bm["applies"] == simply_connected);
    CHECK(j["fig8"]["applies"] == simply_connected);
    if (simply_connected) {
      CHECK(bm["mesh_vertices"] == 900);
      CHECK(bm["coarser_than_render_mesh"] == true);
      CHECK(bm.contains("basis_rows_mb"));
      CHECK(j["fig8"]["boundary_metric"].contains("sequence_max_distance_after_rigid_alignment_over_size"));
      CHECK(j["sequence"]["ccw16_boundary_metric"]["distance_to_ours_after_rigid_alignment_over_size"].size() == 5);
      CHECK(j["side_by_side"][0].contains("ccw16_boundary_metric"));
    } else {
      CHECK(bm["reason"] == c.bm.why_not);
      CHECK_THAT(j["fig8"]["reason"].get<std::string>(), Contains(c.bm.why_not));
      CHECK(j["side_by_side"][0]["ccw16"]["hole_period_over_size"][0].get<double>() == Approx(0.01));  // 0.02 / size 2
      CHECK_FALSE(j["sequence"].contains("ccw16_boundary_metric"));
    }
    // An uncertified frame's NaN and a folded frame's +inf are written as strings, not dropped.
    CHECK(j["sequence"]["ours"]["ms"][0] == "nan");

    const std::string md = report_markdown(c);
    for (const char* png : {"side_by_side_t0.25.png", "kappa.png", "isometric.png", "frame_time.png"}) CHECK_THAT(md, Contains(png));
    CHECK_THAT(md, Contains(simply_connected ? "(Fig. 8)" : "(Fig. 2)"));
    CHECK((md.find("ccw16_distance.png") != std::string::npos) == simply_connected);
    CHECK_THAT(md, Contains("## Table 4: time per frame against ARAP, FFMP and GE"));
    CHECK_THAT(md, Contains("## Claims"));
    CHECK_THAT(md, Contains("| GE | "));
    CHECK_THAT(md, Contains("| FFMP | "));
    CHECK_THAT(md, Contains("## Side by side (ours, ARAP, FFMP, GE, CCW16"));
    CHECK_THAT(md, Contains("**Machine:** a CPU, 2 logical cores; Vulkan device llvmpipe (CPU)"));
  }
}

TEST_CASE("figures: a side-by-side figure and the plots are written at the expected size", "[compare]") {
  const auto dir = fresh_dir("figures");
  Outputs out(dir);
  out.open();
  // Three 120 × 80 panels side by side: the width holds them and their gaps, the height
  // the title, the captions, the panels and the colour bar.
  std::vector<Column> cols;
  for (int k = 0; k < 3; ++k) cols.push_back({"method " + std::to_string(k), "max κ 1.234", k == 2, RgbaImage(120, 80, {200, 100, 50, 255})});
  const draw::Surface fig = compose("a made-up figure", cols, 1, 2);
  const int w = cairo_image_surface_get_width(fig.surf.get()), h = cairo_image_surface_get_height(fig.surf.get());
  const int gap = static_cast<int>(std::ceil(0.6 * 12.0));  // font 12 for panels this small
  CHECK(w == 3 * 120 + 4 * gap);
  CHECK(h > 80 + 3 * 12);
  draw::write_surface(fig, out.add("side_by_side.png"));
  CHECK(png_size(dir / "side_by_side.png") == std::make_pair(w, h));

  for (const bool simply_connected : {false, true}) {
    PlotLabels labels;
    labels.scene_name = "made_up";
    labels.keyframe_times = {0, 1};
    labels.holes = !simply_connected;
    labels.boundary_metric = simply_connected;
    labels.mesh_vertices = 1500;
    labels.core = "cpu";
    const int n = plots(made_frames(9, simply_connected), labels, out);
    CHECK(n == (simply_connected ? 4 : 3));
    for (const char* png : {"kappa.png", "isometric.png", "frame_time.png"}) CHECK(png_size(dir / png) == std::make_pair(900, 420));
    CHECK(std::filesystem::exists(dir / "ccw16_distance.png") == simply_connected);
  }
  // Not committed: what this run wrote is removed again (a failed run leaves no report).
}

TEST_CASE("a compare run that fails removes what it wrote and refuses bad options by name", "[compare]") {
  const auto dir = fresh_dir("outputs");
  {
    Outputs out(dir);
    out.open();
    std::ofstream(out.add("kappa.png")) << "x";
    CHECK(std::filesystem::exists(dir / "kappa.png"));
  }
  CHECK_FALSE(std::filesystem::exists(dir));
  Options o;
  o.panel = 50;
  CHECK_THROWS_WITH(check_options(o), Contains("--size"));
  o.panel = 420;
  o.ratios = {0.5, 1.5};
  CHECK_THROWS_WITH(check_options(o), Contains("--ratios"));
  o.ratios = {0.5};
  o.table3_vertices = {10};
  CHECK_THROWS_WITH(check_options(o), Contains("--table3-vertices"));
  o.table3_vertices = {1000};
  CHECK_NOTHROW(check_options(o));
  CHECK_THROWS_AS(run(o), std::invalid_argument);  // no Vulkan context to render with
}

TEST_CASE("ours timed in one block: the captions say how, and the GPU's clocks where there is one", "[compare]") {
  OurTiming t;
  t.warmup = 10;
  t.frames = 98;
  t.evaluator = "cuda";
  t.eval_setup_ms = 12;
  std::string d = t.describe();
  CHECK_THAT(d, Contains("timed in one block: 10 warm-up frames (not timed), then the sequence's 98 solved frames back to back"));
  CHECK_THAT(d, Contains("from cached basis rows on the GPU (CUDA) (the rows evaluated once per mesh, 12 ms)"));
  CHECK_THAT(d, !Contains("GPU clocks"));
  t.clocks_before = "H100: SM 345 MHz";
  t.clocks_after = "H100: SM 1980 MHz";
  d = t.describe();
  CHECK_THAT(d, Contains("GPU clocks before the warm-up: H100: SM 345 MHz; after the block: H100: SM 1980 MHz"));
  t.evaluator = "cpu";
  CHECK_THAT(t.describe(), Contains("on the CPU"));
  t.solve_ms = 1.5;
  t.eval_ms = 0.25;
  CHECK(t.total_ms() == 1.75);
}
