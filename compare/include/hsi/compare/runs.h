// hsi compare, stage 1: the runs. Ours at the chosen settings (the main sequence, the side-
// by-side frames, the sequences of Tables 1–2), the mesh baselines ARAP [ACOL00], FFMP
// [KG08] and GE [SGK19] and CCW16 (log derivatives; on a simply-connected shape also its
// boundary-metric variant, Fig. 8) on the render mesh, and the timings of Tables 3–4. Each
// run's numbers are plain values for the later stages.
#pragma once

#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hsi/baselines/arap.h"
#include "hsi/baselines/ccw16.h"
#include "hsi/baselines/ffmp.h"
#include "hsi/baselines/ge.h"
#include "hsi/compare/alignment.h"
#include "hsi/compare/compare.h"
#include "hsi/png.h"
#include "hsi/scene_texture.h"
#include "hsi/interpolation.h"
#include "hsi/scene_io.h"
#include "hsi/scene_sequence.h"
#include "hsi/triangulate.h"

namespace hsi::compare {

// The scene with its keyframes solved, and the options checked.
struct Inputs {
  Scene scene;
  std::string scene_path;
  SceneTexture texture;  // the scene's, or a checkerboard
  std::shared_ptr<const ShapeSetup> setup;
  std::vector<double> times;
  std::vector<HarmonicMap> keys;
  double seg_t0 = 0, seg_t1 = 1, t_mid = 0.5;  // the side-by-side keyframe interval and its middle
  std::vector<int> table3;                      // Table 3's resolutions, --no-800k applied
  int holes() const { return setup->cage.hole_count(); }
  double size() const { return setup->size; }
};
// Everything that can be refused is refused here (InputError naming the option or the scene).
void check_options(const Options& o);
Inputs prepare_inputs(const Options& o);

// The caller's Newton core (Backends::newton_core), else the CPU reference.
std::unique_ptr<NewtonCore> make_core(const Backends& b, const ShapeSetup& setup);

// The main sequence of ours, with the interpolator the side-by-side frames are solved with.
struct OurSequence {
  std::unique_ptr<Interpolator> interp;
  std::string core;  // the Newton core's name
  std::vector<FrameResult> frames;
  SequenceSummary summary;
  int within_bound = 0;  // certified frames within the keyframes' sampled bound
};
OurSequence run_our_sequence(const Inputs& in, const Options& o);

// One of our sequences (a projection, a Hessian ratio) with what Tables 1–2 report.
struct OurRun {
  std::string label;
  std::string core;
  int hessian_samples = 0;
  double ratio = 0;
  FrameResult cold;  // the segment's middle frame solved from its first keyframe (the paper's Table 1 setting)
  SequenceSummary summary;
  int max_iterations = 0;
};
OurRun run_ours(const std::string& label, const ShapeSetup& setup, const Inputs& in, HessianProjection projection,
                std::unique_ptr<NewtonCore> core, int frames, double ratio);
std::vector<OurRun> run_table1(const Inputs& in, const Options& o, const std::string& main_core);  // projections
std::vector<OurRun> run_table2(Inputs& in, const Options& o);                                      // Hessian ratios

// CCW16's boundary-metric variant (Fig. 8): only on a simply-connected shape (paper §1); with
// holes it is reported as not applicable. Above the memory budget it runs on a coarser mesh.
struct MetricVariant {
  bool applies = false;
  std::string why_not;
  bool own_mesh = false;  // true: on `coarse`, not the render mesh
  TriMesh coarse;
  double render_mesh_mb = 0, mb = 0, setup_ms = 0;
  std::optional<baselines::Ccw16Interpolation> interp;
  std::optional<baselines::Ccw16Mesh> prepared;
};

// Per triangle of a mesh under positions: the area ratio det J (image area / rest area)
// and the turn arg f_z (radians; f_z the conformal part of J). Degenerate: det 0.
struct TriangleShape {
  std::vector<double> det, turn;
};
TriangleShape triangle_shape(const TriMesh& rest, std::span<const cd> positions);

// The keyframes on the render mesh, as the mesh baselines receive them: per keyframe its
// largest per-triangle distortion and each triangle's area ratio, so that a frame between
// keyframes k and k+1 can be held against them on the same triangles.
struct MeshKeyframes {
  std::vector<double> times;
  std::vector<baselines::MeshDistortion> distortion;
  std::vector<TriangleShape> shape;
  double max_turn = 0;  // the largest per-triangle turn between neighbouring keyframes, radians (wrapped to [0, π])
  // The neighbouring keyframes of time t (its interval; clamped to the range).
  std::pair<size_t, size_t> around(double t) const;
  // Per frame: the envelope (max) of the two neighbouring keyframes' largest κ / isometric.
  double kappa_bound(double t) const;
  double iso_bound(double t) const;
  // How far the frame shrinks a triangle below both neighbouring keyframes: the largest
  // min(det_k, det_k+1) / det − 1 over the triangles (0: none smaller than both), +inf for a
  // flipped or degenerate triangle. Only shrinking counts: the metric blend that ours and GE
  // target never shrinks a triangle below both keyframes (√det is concave on positive
  // definite 2×2 matrices: √det M(t) ≥ (1−s)√det M_k + s√det M_k+1), but it may grow one
  // beyond both (axes that turn), so growth is no sign of an unnatural scaling.
  double area_shrink(double t, const TriangleShape& frame) const;
};
MeshKeyframes mesh_keyframes(const TriMesh& mesh, const std::vector<baselines::MeshKeyframe>& keys);

// The baselines, set up on the render mesh with our keyframes.
struct Baselines {
  TriMesh mesh;  // the render mesh
  std::vector<baselines::ArapKeyframe> arap_keys;  // our keyframe maps at its vertices: ARAP's, FFMP's and GE's keyframes
  MeshKeyframes keys_on_mesh;
  std::optional<baselines::ArapInterpolation> arap;
  std::optional<baselines::FfmpInterpolation> ffmp;
  std::optional<baselines::GeInterpolation> ge;
  std::optional<baselines::Ccw16Interpolation> ccw;
  std::optional<baselines::Ccw16Mesh> ccw_mesh;
  double arap_setup_ms = 0, ffmp_setup_ms = 0, ge_setup_ms = 0, ccw_setup_ms = 0;
  double arap_key_error = 0;  // ARAP's largest distance to its keyframes / size (a check of the baseline)
  MetricVariant bm;
  const TriMesh& bm_mesh() const { return bm.own_mesh ? bm.coarse : mesh; }
};
Baselines set_up_baselines(const Inputs& in, const Options& o);

// Bytes CCW16's boundary-metric variant holds once prepare()d on a mesh (its basis rows).
double metric_rows_bytes(const TriMesh& mesh, int columns, const baselines::Ccw16Options& co, double size);
TriMesh mesh_with(const Shape& shape, int vertices);
// f of a map at many points, in chunks so that the basis rows stay small.
std::vector<cd> map_points_chunked(const Cage& cage, const HarmonicMap& map, std::span<const cd> points);

// GE over the main sequence's times, each frame warm-started from the previous one.
std::vector<baselines::GeFrame> run_ge_sequence(const std::vector<FrameResult>& ours, const Baselines& b, const Progress& progress);

// Per frame of the main sequence: each method's largest distortion and its time. Ours
// sampled at the certificate's breakpoints (as the keyframes' bound_*) and certified (*_c,
// NaN where not certified); the boundary-metric variant and both CCW16 variants'
// distances to ours after rigid alignment (Fig. 8) only on a simply-connected shape (NaN else).
// On the render mesh, per triangle: the mesh methods (ARAP, FFMP, GE), ours at the mesh's
// vertices (ours_mesh_*, the same discretisation: a control), and the keyframes' envelope
// there (mesh_bound_*); *_shrink: how far a triangle shrinks below both keyframes
// (MeshKeyframes::area_shrink).
struct PerFrame {
  std::vector<double> t, our_kappa, our_iso, bound_kappa, bound_iso, our_ms, our_iters;
  std::vector<double> our_kappa_c, our_iso_c, bound_kappa_c, bound_iso_c;
  std::vector<double> mesh_bound_kappa, mesh_bound_iso, ours_mesh_kappa, ours_mesh_iso, ours_mesh_shrink;
  std::vector<double> arap_kappa, arap_iso, arap_ms, arap_flipped, arap_shrink;
  std::vector<double> ffmp_kappa, ffmp_iso, ffmp_ms, ffmp_flipped, ffmp_shrink;
  std::vector<double> ge_kappa, ge_iso, ge_ms, ge_iters, ge_flipped, ge_shrink, ge_converged, ge_dist;  // ge_dist: to ours, rigid, / size
  std::vector<double> ccw_kappa, ccw_iso, ccw_ms, ccw_period;
  std::vector<double> bm_kappa, bm_iso, bm_ms, bm_fit, ccw_dist, bm_dist;
  std::vector<bool> keyframe;
  std::vector<double> uncertified_t, unconverged_t;
  size_t size() const { return t.size(); }
};
PerFrame measure_sequence(const Inputs& in, const std::vector<FrameResult>& ours, const Baselines& b,
                          const std::vector<baselines::GeFrame>& ge, const Progress& progress);

// One time of the side-by-side figures, every method at it.
struct Snapshot {
  double u = 0, t = 0;  // fraction of the keyframe interval, time
  FrameResult ours;
  std::vector<cd> ours_pos, arap_pos, ffmp_pos, ge_pos;  // at the render mesh's vertices
  baselines::MeshDistortion arap_d, ffmp_d, ge_d;
  int ge_iterations = 0;
  bool ge_converged = true;
  Gap ge_gap;  // GE vs ours
  baselines::Ccw16Frame ccw, bm;  // CCW16: log derivatives; boundary metric (simply connected only)
  Gap gap, bm_gap;                // ours vs each CCW16 variant
  std::string png;                // the figure's file name, and its size (figures.h)
  int width = 0, height = 0;
};
// At t = 0.25, 0.5, 0.75 of the segment, ours and GE warm-started from their sequence's frame before t.
std::vector<Snapshot> snapshots(const Inputs& in, const OurSequence& ours, const Baselines& b, const std::vector<baselines::GeFrame>& ge);

// Ours timed for Tables 3–4 (issue #23) in one block: `warmup` frames untimed, then the
// sequence's frames back to back, each solved (warm-started from the one before) and then
// f evaluated at the render mesh's vertices from cached basis rows, nothing else in
// between: a GPU then does not idle, and drop its clocks, between our frames as it does
// while the baselines run on the CPU.
struct OurTiming {
  std::string evaluator = "cpu";  // where f at the vertices was evaluated (MeshEvaluator::name)
  int warmup = 0, frames = 0;     // solved frames (keyframes are not solved and not counted)
  double solve_ms = 0, eval_ms = 0, iterations = 0;  // means per solved frame of the block
  double eval_cpu_ms = 0;         // the CPU evaluator at the same maps (= eval_ms where it is the one timed)
  double eval_setup_ms = 0;       // the basis rows at the vertices, once per mesh
  std::string clocks_before, clocks_after;  // the GPU's clocks before the warm-up and after the block; empty: no GPU
  double total_ms() const { return solve_ms + eval_ms; }
  std::string describe() const;   // how it was timed, for the tables' captions
};
OurTiming time_ours(const Inputs& in, const OurSequence& ours, const TriMesh& mesh, const Options& o);

// The cached evaluator of the caller's backend (Backends::mesh_evaluator), else the CPU one.
std::unique_ptr<MeshEvaluator> make_mesh_evaluator(const Backends& b, const Cage& cage, std::span<const cd> points);

// Table 3: time per frame against the render mesh's resolution.
// GE at a row: warm-started from its own frame at the sequence's previous time (that one
// solved from our frame there, untimed); above Options::ge_max_vertices not run, and
// ge_not_run says why, with an estimate from the largest row it ran at.
struct Table3Row {
  int vertices = 0, triangles = 0;
  double mesh_s = 0, arap_factor_ms = 0, arap_ms = 0, ours_eval_cpu_ms = 0;  // f from cached rows on the CPU
  double ours_eval_gpu_ms = 0;  // NaN where no GPU dense evaluation was given
  double ours_eval_cuda_ms = std::numeric_limits<double>::quiet_NaN();  // cached rows on the GPU; NaN: not the backend
  double ours_eval_setup_ms = 0;  // the CPU evaluator's rows at the vertices, once per mesh
  // f at the vertices on the backend our solve ran on: CUDA where timed, else the CPU.
  double ours_eval_ms() const { return std::isnan(ours_eval_cuda_ms) ? ours_eval_cpu_ms : ours_eval_cuda_ms; }
  double ge_ms = std::numeric_limits<double>::quiet_NaN(), ge_iterations = std::numeric_limits<double>::quiet_NaN();
  int ge_not_converged = 0;
  std::string ge_not_run;  // non-empty: GE was not run at this row, and why
};
// Frames of the sequence whose maps and times Table 3 uses.
std::vector<size_t> timed_frames(size_t frames, int timing_frames);
std::vector<Table3Row> run_table3(const Inputs& in, const std::vector<FrameResult>& ours, const std::vector<size_t>& timed,
                                  const Options& o);
// What Table 3 says for GE at `vertices` where it is not run, from the rows it ran at.
std::string ge_not_run_note(int vertices, int max_vertices, const std::vector<Table3Row>& rows);

// GE's middle frame of the side-by-side interval solved from the interval's first keyframe
// (the paper's Table 1 setting for ours): how many iterations GE needs without a warm start.
baselines::GeFrame ge_cold_frame(const Inputs& in, const Baselines& b, int segment);

}  // namespace hsi::compare
