// Benchmark of the CUDA Newton core against the CPU one, in the same run: per bundled
// scene and |G|, the time per call of each core method, the floor set by the library
// calls alone (the Hessian's ZGEMM, a Cholesky factor-and-solve of its size), and a
// warm-started interpolation sequence with each backend (set-up, first frame and warm
// frames apart); per scene, f at a mesh's vertices per frame: the basis evaluated
// directly, and from cached rows on the CPU and on the GPU (hsi/mesh_evaluator.h). Prints
// Markdown tables with CUDA/CPU ratios, and the GPU's clocks. Not a test: timings only.
#include "hsi/stopwatch.h"
#include <CLI/CLI.hpp>
#include <Eigen/Cholesky>
#include <chrono>
#include <cstdio>
#include <cusolverDn.h>
#include <omp.h>
#include <random>
#include <sstream>

#include "bench_scenes.h"
#include "device.h"
#include "hsi/cuda/clocks.h"
#include "hsi/cuda/mesh_evaluator.h"
#include "hsi/cuda/newton_core.h"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/mesh_evaluator.h"
#include "hsi/triangulate.h"
#include "trace_range.h"

using namespace hsi;
namespace hc = hsi::cuda;

namespace {

using Clock = std::chrono::steady_clock;

using bench::Loaded;
using bench::load;

// Mean ms per call of f over `reps` calls, after two warm-up calls. Every timed core
// call ends in a host synchronisation (its result is on the host), so wall-clock time
// is the cost the Newton loop sees.
template <class F>
double time_calls(int reps, F&& f) {
  f();
  f();
  const auto t0 = Clock::now();
  for (int i = 0; i < reps; ++i) f();
  return ms_since(t0) / reps;
}

volatile double g_sink = 0;

struct CallTimes {
  double energy_gradient = 0, hessian = 0, line_search = 0;
  // The exact Hessian over all of G (the CUDA core's exact systems) as a matrix, and its
  // product with a vector without forming it (NewtonCore::hessian_times: a Krylov solve's
  // step), each a call that ends with its result on the host.
  double exact_all = 0, exact_all_times = 0;
};

// One core at a fixed, realistic state: keyframe 0's coefficients against the metric
// blended halfway to keyframe 1, the direction towards keyframe 1.
CallTimes time_core(NewtonCore& core, const Loaded& L, const std::vector<Metric>& targets, int reps) {
  const MapSpace& space = L.setup->metric_space;
  const Eigen::VectorXd x0 = space.reduce(L.maps[0]).x, x1 = space.reduce(L.maps[1]).x;
  const Eigen::VectorXd v = space.T() * x0, dv = space.T() * (x1 - x0);
  core.set_targets(targets);
  CallTimes t;
  double sink = 0;
  t.energy_gradient = time_calls(reps, [&] {
    core.set_coefficients(v);
    sink += core.energy();
    sink += core.gradient()(0);
  });
  t.hessian = time_calls(reps, [&] { sink += core.hessian(HessianProjection::PartProj)(0, 0); });
  t.exact_all = time_calls(reps, [&] { sink += core.hessian(HessianProjection::PartProj, true, true)(0, 0); });
  t.exact_all_times = time_calls(reps, [&] { sink += core.hessian_times(HessianProjection::PartProj, true, true, dv)(0); });
  t.line_search = time_calls(reps, [&] {
    core.set_direction(dv);
    const double s = core.max_safe_step();
    sink += core.energy_at(0.5 * std::min(1.0, s));
  });
  g_sink = sink;  // keep the results observable
  return t;
}

struct Floors {
  double zgemm_ms = 0, zgemm_tflops = 0, potrf_potrs_ms = 0, eigen_llt_ms = 0;
};

// The library calls alone, timed with CUDA events on a stream of their own: the
// Hessian's ZGEMM (n × 6n × |H|) and a Cholesky factor + solve of a (4n) × (4n) SPD matrix.
Floors time_floors(int n, int h, const Eigen::MatrixXd& spd, int reps) {
  Floors f;
  hc::Stream stream;
  hc::BlasHandle blas(stream);
  hc::Event start(true), stop(true);
  auto event_ms = [&](auto&& body) {
    body();  // warm-up
    HSI_CUDA_CHECK(cudaEventRecord(start, stream));
    for (int i = 0; i < reps; ++i) body();
    HSI_CUDA_CHECK(cudaEventRecord(stop, stream));
    HSI_CUDA_CHECK(cudaEventSynchronize(stop));
    float ms = 0;
    HSI_CUDA_CHECK(cudaEventElapsedTime(&ms, start, stop));
    return static_cast<double>(ms) / reps;
  };
  {
    const size_t sn = static_cast<size_t>(n), sh = static_cast<size_t>(h);
    hc::DeviceArray<cuDoubleComplex> A(sh * sn), B(sh * 6 * sn), C(sn * 6 * sn);
    HSI_CUDA_CHECK(cudaMemsetAsync(A.get(), 0, A.bytes(), stream));
    HSI_CUDA_CHECK(cudaMemsetAsync(B.get(), 0, B.bytes(), stream));
    const cuDoubleComplex one{1, 0}, zero{0, 0};
    f.zgemm_ms = event_ms([&] {
      HSI_CUDA_CHECK(cublasZgemm(blas, CUBLAS_OP_C, CUBLAS_OP_N, n, 6 * n, h, &one, A.get(), h, B.get(), h, &zero, C.get(), n));
    });
    f.zgemm_tflops = 8.0 * n * 6.0 * n * h / (f.zgemm_ms * 1e-3) / 1e12;
  }
  {
    const int N = static_cast<int>(spd.rows());
    const size_t NN = static_cast<size_t>(N) * static_cast<size_t>(N);
    hc::SolverHandle solver(stream);
    hc::DeviceArray<double> A0(NN), A(NN), b(static_cast<size_t>(N));
    hc::DeviceArray<int> info(1);
    HSI_CUDA_CHECK(cudaMemcpyAsync(A0.get(), spd.data(), A0.bytes(), cudaMemcpyHostToDevice, stream));
    HSI_CUDA_CHECK(cudaMemcpyAsync(A.get(), spd.data(), A.bytes(), cudaMemcpyHostToDevice, stream));
    int lwork = 0;
    HSI_CUDA_CHECK(cusolverDnDpotrf_bufferSize(solver, CUBLAS_FILL_MODE_LOWER, N, A.get(), N, &lwork));
    hc::DeviceArray<double> work(static_cast<size_t>(std::max(lwork, 1)));
    const Eigen::VectorXd rhs = Eigen::VectorXd::Ones(N);
    // Restoring A and b is part of each timed round (a device copy of (4n)², small
    // against the factorisation); what a solver on the device would pay too.
    f.potrf_potrs_ms = event_ms([&] {
      HSI_CUDA_CHECK(cudaMemcpyAsync(A.get(), A0.get(), A.bytes(), cudaMemcpyDeviceToDevice, stream));
      HSI_CUDA_CHECK(cudaMemcpyAsync(b.get(), rhs.data(), b.bytes(), cudaMemcpyHostToDevice, stream));
      HSI_CUDA_CHECK(cusolverDnDpotrf(solver, CUBLAS_FILL_MODE_LOWER, N, A.get(), N, work.get(), lwork, info.get()));
      HSI_CUDA_CHECK(cusolverDnDpotrs(solver, CUBLAS_FILL_MODE_LOWER, N, 1, A.get(), N, b.get(), N, info.get()));
    });
    int host_info = -1;
    HSI_CUDA_CHECK(cudaMemcpyAsync(&host_info, info.get(), sizeof(int), cudaMemcpyDeviceToHost, stream));
    HSI_CUDA_CHECK(cudaStreamSynchronize(stream));
    if (host_info != 0) std::fprintf(stderr, "warning: cusolverDnDpotrf/potrs reported info = %d\n", host_info);
    f.eigen_llt_ms = time_calls(std::max(1, reps / 4), [&] {
      Eigen::LLT<Eigen::MatrixXd> llt(spd);
      const Eigen::VectorXd x = llt.solve(rhs);
      if (!x.allFinite()) std::fprintf(stderr, "warning: Eigen LLT failed\n");
    });
  }
  return f;
}

struct SequenceStats {
  bool ran = false;
  double setup_ms = 0;        // the core made (for the CUDA core: its warm-up included)
  double interpolator_ms = 0; // the Interpolator made (keyframe certificates and metrics, on the host)
  double first_ms = 0;        // the first solved frame
  int first_iterations = 0;
  // Over the warm frames: every solved frame but the first.
  double mean_ms = 0, max_ms = 0, iterations = 0, ms_per_iteration = 0;
  int uncertified = 0;
  NewtonResult::Timing per_iteration;
  double scratch_ms = 0;  // the frame midway between the first two keyframes, started from the first
  int scratch_iterations = 0;
  bench::FrameParts parts;  // where the frames' time went (FrameResult::parts)
  bench::CrossingSearchTimes crossing;  // the crossing search alone on these frames' images (when asked)
  // CUDA graphs launched and their nodes, per solved frame of the sequence (the first
  // frame's captures included; device.h graph_counts: 0 on the CPU core).
  double graph_launches = 0, graph_nodes = 0;
};

// label: the row's backend label, also the name of the NVTX range around the sequence
// ("sequence <label>", for bench/cuda_trace). gpu_boundary: the overlap check's image (f at its breakpoints) by the CUDA mesh
// evaluator, as runtime's make_newton_core gives with the CUDA core; else the setup's CPU
// one. pipelined: InterpolationOptions::pipelined_overlap (the crossing search beside the
// next solve; off: in series). crossing_reps > 0: the crossing search alone timed on
// the frames' images too. chord: InterpolationOptions::chord_steps; exact:
// InterpolationOptions::exact_samples; chord_stop: InterpolationOptions::chord_decrement_stop.
template <class MakeCore>
SequenceStats run_sequence(const std::string& label, const Loaded& L, MakeCore&& make_core, int frames, bool gpu_boundary, bool pipelined = true,
                           int crossing_reps = 0, bool chord = true, ExactSamples exact = InterpolationOptions{}.exact_samples,
                           double chord_stop = InterpolationOptions{}.chord_decrement_stop) {
  SequenceStats s;
  auto t0 = Clock::now();
  std::unique_ptr<NewtonCore> core = make_core();
  std::unique_ptr<MeshEvaluator> boundary;
  if (gpu_boundary) boundary = std::make_unique<hc::MeshEvaluator>(L.setup->overlap.evaluator());  // the setup's rows, uploaded
  s.setup_ms = ms_since(t0);
  t0 = Clock::now();
  InterpolationOptions o;
  o.pipelined_overlap = pipelined;
  o.chord_steps = chord;
  o.chord_decrement_stop = chord ? chord_stop : 0.0;
  o.exact_samples = exact;
  Interpolator interp(*L.setup, L.times, L.maps, o, std::move(core), std::move(boundary));
  s.interpolator_ms = ms_since(t0);
  t0 = Clock::now();
  const long launches0 = hc::graph_counts().launches.load(), nodes0 = hc::graph_counts().nodes.load();
  const auto seq = [&] {
    const bench::TraceRange range("sequence " + label);  // (bench/cuda_trace)
    return interp.sequence(frames);
  }();
  s.parts = bench::frame_parts(seq, ms_since(t0));
  {
    int solved_frames = 0;
    for (const FrameResult& f : seq) solved_frames += !f.keyframe;
    s.graph_launches = static_cast<double>(hc::graph_counts().launches.load() - launches0) / std::max(solved_frames, 1);
    s.graph_nodes = static_cast<double>(hc::graph_counts().nodes.load() - nodes0) / std::max(solved_frames, 1);
  }
  if (crossing_reps > 0) s.crossing = bench::time_crossing_search(*L.setup, seq, 20, crossing_reps);
  s.ran = true;
  int solved = 0;
  double its = 0;
  NewtonResult::Timing t;
  bool first = true;
  for (const FrameResult& f : seq) {
    s.uncertified += !f.certified;
    if (f.keyframe) continue;
    if (first) {  // reported apart: what set-up left to the first solve
      first = false;
      s.first_ms = f.ms;
      s.first_iterations = f.iterations;
      continue;
    }
    ++solved;
    s.mean_ms += f.ms;
    s.max_ms = std::max(s.max_ms, f.ms);
    its += f.iterations;
    t += f.timing;
  }
  solved = std::max(solved, 1);
  const double total_ms = s.mean_ms;
  s.mean_ms /= solved;
  s.iterations = its / solved;
  const double per = std::max(its, 1.0);
  s.ms_per_iteration = total_ms / per;
  s.per_iteration = {t.energy_gradient / per, t.hessian / per, t.solve / per, t.line_search / per, t.certificate / per};
  const FrameResult scratch = interp.frame(0.5 * (L.times[0] + L.times[1]));
  s.scratch_ms = scratch.ms;
  s.scratch_iterations = scratch.iterations;
  s.uncertified += !scratch.certified;
  return s;
}

// f at a mesh's vertices per frame (issue #23): the direct path (the basis rows
// evaluated at every vertex for every frame, as hsi compare did), and from cached rows
// on the CPU and, where a device is there, on the GPU: values left on the device
// (enqueue + synchronize) and copied to the host. Wall-clock per frame, the keyframes'
// maps in turn, after two untimed frames.
struct MeshEvalTimes {
  int vertices = 0, columns = 0;
  double direct_ms = 0, cpu_ms = 0, cpu_setup_ms = 0, cpu_gap = 0;
  bool cuda = false;
  double cuda_device_ms = 0, cuda_host_ms = 0, cuda_setup_ms = 0, cuda_gap = 0;
};

MeshEvalTimes time_mesh_eval(const Loaded& L, int vertices, int reps, bool cuda) {
  MeshEvalTimes r;
  TriangulateOptions to;
  to.max_edge = edge_for_vertex_count(L.scene.shape, vertices);
  const TriMesh mesh = triangulate(L.scene.shape, to);
  const Cage& cage = L.setup->cage;
  r.vertices = mesh.vertex_count();
  r.columns = basis_size(cage);
  size_t k = 0;
  auto next_map = [&]() -> const HarmonicMap& { return L.maps[k++ % L.maps.size()]; };
  auto gap = [](const VectorXcd& got, const VectorXcd& want) {
    return (got - want).cwiseAbs().maxCoeff() / std::max(want.cwiseAbs().maxCoeff(), 1e-300);
  };
  const std::vector<cd> direct0 = map_points(cage, L.maps[0], mesh.vertices);
  const VectorXcd want = Eigen::Map<const VectorXcd>(direct0.data(), static_cast<Eigen::Index>(direct0.size()));
  double sink = 0;
  r.direct_ms = time_calls(std::max(1, reps / 4), [&] { sink += map_points(cage, next_map(), mesh.vertices)[0].real(); });
  auto t0 = Clock::now();
  const auto cpu = make_cpu_mesh_evaluator(cage, mesh.vertices);
  r.cpu_setup_ms = ms_since(t0);
  MapValues v;
  r.cpu_ms = time_calls(reps, [&] {
    cpu->evaluate(next_map(), v);
    sink += v.f(0).real();
  });
  cpu->evaluate(L.maps[0], v);
  r.cpu_gap = gap(v.f, want);
  if (cuda) {
    r.cuda = true;
    t0 = Clock::now();
    hc::MeshEvaluator gpu(cage, mesh.vertices);
    r.cuda_setup_ms = ms_since(t0);
    r.cuda_device_ms = time_calls(reps, [&] {
      gpu.enqueue(next_map());
      gpu.synchronize();
    });
    r.cuda_host_ms = time_calls(reps, [&] {
      gpu.evaluate(next_map(), v);
      sink += v.f(0).real();
    });
    gpu.evaluate(L.maps[0], v);
    r.cuda_gap = gap(v.f, want);
  }
  g_sink = sink;
  return r;
}

std::string ratio(double cuda, double cpu) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", cuda / cpu);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hsi CUDA Newton core benchmark: CPU vs CUDA in one run, Markdown tables"};
  std::vector<std::string> scenes;
  std::vector<int> sample_counts{10000, 100000};
  double ratio_r = 0.2;
  int frames = 500, reps = 20, cpu_sequence_max = 10000;
  bool skip_sequence = false, mesh_only = false;
  int mesh_vertices = 10000;
  app.add_option("scenes", scenes, "Scene files with two or more keyframes")->required();
  app.add_option("--samples", sample_counts, "|G| values")->capture_default_str();
  app.add_option("--ratio", ratio_r, "Hessian sample ratio r = |H|/|G|")->capture_default_str();
  app.add_option("--frames", frames, "Frames of the warm-started sequences")->capture_default_str();
  app.add_option("--reps", reps, "Timed calls per core method")->capture_default_str();
  app.add_option("--cpu-sequence-max-samples", cpu_sequence_max, "Run the CPU and host-driven CUDA sequences only up to this |G| (at 100,000: minutes per scene)")->capture_default_str();
  app.add_flag("--skip-sequence", skip_sequence, "Skip the warm-started sequences");
  app.add_option("--mesh-vertices", mesh_vertices, "Vertices (about) of the mesh f is evaluated at per frame")
      ->capture_default_str()->check(CLI::Range(100, 5000000));
  app.add_flag("--f-at-mesh-only", mesh_only,
               "Only the table of f at the mesh's vertices (runs without a GPU: then the CPU columns only)");
  CLI11_PARSE(app, argc, argv);

  std::string why;
  const bool device = hc::device_available(&why);
  if (!device && !mesh_only) {
    std::fprintf(stderr, "no CUDA device: %s\n", why.c_str());
    return 1;
  }
  std::printf("Device: %s; CPU threads: %d; r = %.0f%%; %s (the interpolation's default projection)\n",
              device ? why.c_str() : ("none (" + why + ")").c_str(), omp_get_max_threads(), 100 * ratio_r,
              to_string(InterpolationOptions{}.projection));
  if (device) std::printf("GPU clocks at the start: %s\n", hc::clocks().describe().c_str());
  std::printf("\n");

  std::ostringstream mesh_eval;
  mesh_eval << "## f at the mesh's vertices per frame (ms, mean of " << reps
            << " frames; direct: the basis evaluated at every vertex every frame; cached: rows evaluated once, then one "
               "matrix-vector product per frame; CUDA on device: values left on the GPU; to host: copied back into MapValues)\n\n"
            << "| scene | vertices | m + N | direct CPU | cached CPU | direct / cached | CPU rows set-up | CUDA on device | "
               "CUDA to host | CUDA rows set-up | CUDA on device / cached CPU | max rel. gap to direct (CPU, CUDA) |\n"
               "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  auto mesh_row = [&](const Loaded& L) {
    std::fprintf(stderr, "  f at the mesh's vertices\n");
    const MeshEvalTimes m = time_mesh_eval(L, mesh_vertices, reps, device);
    char row[512];
    if (m.cuda)
      std::snprintf(row, sizeof row, "| %s | %d | %d | %.3f | %.3f | %.1f | %.1f | %.4f | %.4f | %.1f | %s | %.1e, %.1e |\n",
                    L.name.c_str(), m.vertices, m.columns, m.direct_ms, m.cpu_ms, m.direct_ms / m.cpu_ms, m.cpu_setup_ms,
                    m.cuda_device_ms, m.cuda_host_ms, m.cuda_setup_ms, ratio(m.cuda_device_ms, m.cpu_ms).c_str(), m.cpu_gap,
                    m.cuda_gap);
    else
      std::snprintf(row, sizeof row, "| %s | %d | %d | %.3f | %.3f | %.1f | %.1f | n/a | n/a | n/a | n/a | %.1e, n/a |\n",
                    L.name.c_str(), m.vertices, m.columns, m.direct_ms, m.cpu_ms, m.direct_ms / m.cpu_ms, m.cpu_setup_ms,
                    m.cpu_gap);
    mesh_eval << row;
    std::fprintf(stderr, "  %s", row);
  };
  if (mesh_only) {
    for (const std::string& path : scenes) {
      std::fprintf(stderr, "%s, |G| = %d: setting up\n", path.c_str(), sample_counts.front());
      mesh_row(load(path, sample_counts.front(), ratio_r));
    }
    std::printf("\n---\n\n%s\n", mesh_eval.str().c_str());
    return 0;
  }

  std::ostringstream calls, floors, seqs, parts, crossing;
  calls << "## Core calls (ms per call, mean of " << reps << "; CUDA/CPU < 1: CUDA faster)\n\n"
        << "| scene | |G| | n | |H| | E+∇ CPU | E+∇ CUDA | ratio | Hessian CPU | Hessian CUDA | ratio | "
           "safe step+E(s) CPU | safe step+E(s) CUDA | ratio | exact Hessian over G CPU | CUDA | H·p over G, unformed, CPU | CUDA | "
           "CUDA H·p / CUDA Hessian |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  floors << "## Library floors on the GPU (CUDA events) against the CUDA Hessian call and the CPU Cholesky\n\n"
         << "| scene | |G| | n | ZGEMM n×6n×|H| ms | ZGEMM TFLOP/s | CUDA Hessian call ms | GEMM share | potrf+potrs (4n) ms | "
            "Eigen LLT (4n) CPU ms | ratio |\n|---|---|---|---|---|---|---|---|---|---|\n";
  seqs << "## Warm-started sequences (" << frames << " frames; per-iteration parts in ms)\n\n"
       << "cuda-host: the CUDA core driven call by call from the host (Cholesky and certificate on the CPU); "
          "cuda: the whole solve on the GPU (cuSOLVER, GPU line search and certificate); -nochord: the same without chord "
          "steps (InterpolationOptions::chord_steps off: every frame's systems built and factored at its own points); "
          "-chordstop: with the chord decrement stop at 1 % of the tolerance (InterpolationOptions::chord_decrement_stop "
          "0.01: after a full chord step a frame may end on the kept system's decrement, with no exact system of its own); "
          "-exact-all / -exact-subset: exact systems' Hessians over all of G / over H, -exact-then-all: over H, then over G "
          "where that is not positive definite (InterpolationOptions::exact_samples; the other rows: its default, Auto: "
          "the core's choice, over H on the CPU and over G on CUDA). "
          "t = ½: the frame midway "
          "between the first two keyframes solved from the first (no warm start). Set-up: the core made (the CUDA "
          "core runs every call of a solve once while it is made); interpolator: the Interpolator made (host); first "
          "frame: the first solved frame after both; mean, max, iterations and the per-iteration parts are over the "
          "warm frames (every solved frame but the first).\n\n"
       << "| scene | |G| | backend | set-up ms | interpolator ms | first frame ms (iters) | mean ms/frame | max ms/frame | "
          "iters/frame | ms/iteration | uncertified | E+∇ | Hessian | solve | line search | certificate | t = ½ ms (iters) | "
          "CPU/this per iteration |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";

  parts << "## Where a frame's time goes (ms, wall clock; FrameResult::parts: the first solved frame, then means over the "
           "warm frames; image: f at the overlap check's breakpoints, by the CUDA mesh evaluator in the cuda rows, the "
           "setup's CPU one otherwise; crossings: the exact crossing search on the host, its own time, on the sequence's "
           "crossing thread beside the next solve (cuda-series: in series, InterpolationOptions::pipelined_overlap off); "
           "crossings wait: what the sequence waited for it (counted in the warm frame); wall / frame: the sequence's "
           "wall clock over its solved frames; rest: the warm frame outside its parts, crossings counted by the wait; graphs / "
           "nodes: CUDA graphs launched per solved frame and the kernel, copy and memset nodes they held, the first frame's "
           "captures included: work launched outside graphs is not counted)\n\n"
        << "| scene | |G| | backend | first frame | first: solve | first: image + crossings | warm frame | wall / frame | "
           "targets | solve | pose | image | crossings | crossings wait | distortion | rest | graphs | nodes |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  crossing << "## The overlap check's crossing search alone (ms per call, one host thread, over 20 images of the cuda "
              "sequence's frames, each searched " << std::max(reps, 1) << " times: kept = the hierarchy kept by the checker "
              "and refit, check_points; reference = the polylines and hierarchy made per call, check_points_reference)\n\n"
           << "| scene | |G| | breakpoints | images (overlapping) | kept ms | reference ms | reference / kept | same results |\n"
              "|---|---|---|---|---|---|---|---|\n";
  for (const std::string& path : scenes) {
    for (int samples : sample_counts) {
      std::fprintf(stderr, "%s, |G| = %d: setting up\n", path.c_str(), samples);
      const Loaded L = load(path, samples, ratio_r);
      if (samples == sample_counts.front()) mesh_row(L);  // f at the mesh does not depend on |G|
      const int n = L.setup->metric_space.n();
      const int h = static_cast<int>(L.setup->H.size());
      const int G = static_cast<int>(L.setup->G.size());
      std::vector<Metric> targets;
      {
        Interpolator blend(*L.setup, L.times, L.maps);
        targets = blend.blended_metric(0.5 * (L.times[0] + L.times[1]));
      }
      auto cpu = make_cpu_newton_core(L.setup->D_G, L.setup->H);
      auto gpu = hc::make_newton_core(L.setup->D_G, L.setup->H);
      std::fprintf(stderr, "  core calls\n");
      const CallTimes tc = time_core(*cpu, L, targets, std::max(1, reps / 4));
      const CallTimes tg = time_core(*gpu, L, targets, reps);
      char row[1024];
      std::snprintf(row, sizeof row, "| %s | %d | %d | %d | %.3f | %.3f | %s | %.3f | %.3f | %s | %.3f | %.3f | %s | %.3f | %.3f | %.3f | %.3f | %s |\n",
                    L.name.c_str(), G, n, h, tc.energy_gradient, tg.energy_gradient, ratio(tg.energy_gradient, tc.energy_gradient).c_str(),
                    tc.hessian, tg.hessian, ratio(tg.hessian, tc.hessian).c_str(), tc.line_search, tg.line_search,
                    ratio(tg.line_search, tc.line_search).c_str(), tc.exact_all, tg.exact_all, tc.exact_all_times, tg.exact_all_times,
                    ratio(tg.exact_all_times, tg.exact_all).c_str());
      calls << row;
      std::fprintf(stderr, "  %s", row);

      std::fprintf(stderr, "  library floors\n");
      Eigen::MatrixXd spd = gpu->hessian(HessianProjection::PartProj);
      spd.diagonal().array() += 1e-3 * spd.diagonal().cwiseAbs().mean() + 1e-12;
      const Floors f = time_floors(n, h, spd, reps);
      std::snprintf(row, sizeof row, "| %s | %d | %d | %.3f | %.1f | %.3f | %.0f%% | %.3f | %.3f | %s |\n", L.name.c_str(), G, n, f.zgemm_ms,
                    f.zgemm_tflops, tg.hessian, 100 * f.zgemm_ms / tg.hessian, f.potrf_potrs_ms, f.eigen_llt_ms,
                    ratio(f.potrf_potrs_ms, f.eigen_llt_ms).c_str());
      floors << row;
      std::fprintf(stderr, "  %s", row);
      std::fflush(stderr);

      if (skip_sequence) continue;
      cpu.reset();  // the sequences make their own cores
      gpu.reset();
      SequenceStats sc, sh, sg, ss, sgn, sgs, scn, sga, sgt, sca, sct;
      std::fprintf(stderr, "  sequence (CUDA, device loop)\n");
      sg = run_sequence("cuda", L, [&] { return hc::make_newton_core(*L.setup); }, frames, true, true, std::max(reps, 1));
      std::fprintf(stderr, "  sequence (CUDA, device loop, crossing search in series)\n");
      ss = run_sequence("cuda-series", L, [&] { return hc::make_newton_core(*L.setup); }, frames, true, false);
      std::fprintf(stderr, "  sequence (CUDA, device loop, no chord steps)\n");
      sgn = run_sequence("cuda-nochord", L, [&] { return hc::make_newton_core(*L.setup); }, frames, true, true, 0, false);
      std::fprintf(stderr, "  sequence (CUDA, device loop, chord decrement stop at 1 %% of the tolerance)\n");
      sgs = run_sequence("cuda-chordstop", L, [&] { return hc::make_newton_core(*L.setup); }, frames, true, true, 0, true,
                         InterpolationOptions{}.exact_samples, 0.01);
      std::fprintf(stderr, "  sequence (CUDA, device loop, exact systems over H)\n");
      sga = run_sequence("cuda-exact-subset", L, [&] { return hc::make_newton_core(*L.setup); }, frames, true, true, 0, true, ExactSamples::Subset);
      std::fprintf(stderr, "  sequence (CUDA, device loop, exact systems over H, then G where indefinite)\n");
      sgt = run_sequence("cuda-exact-then-all", L, [&] { return hc::make_newton_core(*L.setup); }, frames, true, true, 0, true, ExactSamples::SubsetThenAll);
      {
        const bench::CrossingSearchTimes& c = sg.crossing;
        std::snprintf(row, sizeof row, "| %s | %d | %d | %d (%d) | %.3f | %.3f | %.1f | %s |\n", L.name.c_str(), G, c.points,
                      c.images, c.overlapping, c.kept_ms, c.reference_ms, c.reference_ms / c.kept_ms, c.same ? "yes" : "NO");
        crossing << row;
        std::fprintf(stderr, "  %s", row);
      }
      if (samples <= cpu_sequence_max) {
        std::fprintf(stderr, "  sequence (CUDA, host loop)\n");
        sh = run_sequence("cuda-host", L, [&] { return hc::make_newton_core(L.setup->D_G, L.setup->H); }, frames, false);
        std::fprintf(stderr, "  sequence (CPU)\n");
        sc = run_sequence("cpu", L, [&] { return make_cpu_newton_core(L.setup->D_G, L.setup->H); }, frames, false);
        std::fprintf(stderr, "  sequence (CPU, no chord steps)\n");
        scn = run_sequence("cpu-nochord", L, [&] { return make_cpu_newton_core(L.setup->D_G, L.setup->H); }, frames, false, true, 0, false);
        std::fprintf(stderr, "  sequence (CPU, exact systems over all of G)\n");
        sca = run_sequence("cpu-exact-all", L, [&] { return make_cpu_newton_core(L.setup->D_G, L.setup->H); }, frames, false, true, 0, true, ExactSamples::All);
        std::fprintf(stderr, "  sequence (CPU, exact systems over H, then G where indefinite)\n");
        sct = run_sequence("cpu-exact-then-all", L, [&] { return make_cpu_newton_core(L.setup->D_G, L.setup->H); }, frames, false, true, 0, true, ExactSamples::SubsetThenAll);
      }
      const std::pair<const char*, const SequenceStats*> rows[] = {
          {"cpu", &sc}, {"cpu-nochord", &scn}, {"cpu-exact-all", &sca}, {"cpu-exact-then-all", &sct}, {"cuda-host", &sh},
          {"cuda", &sg}, {"cuda-nochord", &sgn}, {"cuda-chordstop", &sgs}, {"cuda-exact-subset", &sga}, {"cuda-exact-then-all", &sgt}, {"cuda-series", &ss}};
      for (const auto& [label, s] : rows) {
        if (!s->ran) {
          std::snprintf(row, sizeof row, "| %s | %d | %s | skipped (--cpu-sequence-max-samples) | | | | | | | | | | | | | | |\n",
                        L.name.c_str(), G, label);
        } else {
          const auto& t = s->per_iteration;
          std::snprintf(row, sizeof row,
                        "| %s | %d | %s | %.1f | %.1f | %.2f (%d) | %.2f | %.2f | %.2f | %.3f | %d | %.3f | %.3f | %.3f | %.3f | %.3f | "
                        "%.1f (%d) | %s |\n",
                        L.name.c_str(), G, label, s->setup_ms, s->interpolator_ms, s->first_ms, s->first_iterations, s->mean_ms,
                        s->max_ms, s->iterations, s->ms_per_iteration, s->uncertified,
                        t.energy_gradient, t.hessian, t.solve, t.line_search, t.certificate, s->scratch_ms,
                        s->scratch_iterations, sc.ran ? ratio(sc.ms_per_iteration, s->ms_per_iteration).c_str() : "");
        }
        seqs << row;
        std::fprintf(stderr, "  %s", row);
        if (s->ran) {
          const bench::FrameParts& p = s->parts;
          std::snprintf(row, sizeof row,
                        "| %s | %d | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | "
                        "%.3f | %.1f | %.1f |\n",
                        L.name.c_str(), G, label, p.first_ms, p.first.solve, p.first.image + p.first.crossings, p.mean_ms,
                        p.wall_ms, p.mean.targets, p.mean.solve, p.mean.pose, p.mean.image, p.mean.crossings,
                        p.mean.crossings_wait, p.mean.distortion, p.rest(), s->graph_launches, s->graph_nodes);
          parts << row;
        }
      }
    }
  }
  std::printf("\n---\n\n%s\n%s\n%s\n", mesh_eval.str().c_str(), calls.str().c_str(), floors.str().c_str());
  if (!skip_sequence) std::printf("%s\n%s\n%s\n", seqs.str().c_str(), parts.str().c_str(), crossing.str().c_str());
  std::printf("GPU clocks at the end: %s\n", hc::clocks().describe().c_str());
  return 0;
}
