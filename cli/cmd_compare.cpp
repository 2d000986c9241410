// hsi compare SCENE -o DIR/: the paper's claims reproduced on one scene against the
// baselines (issues #11, #24), measured in one run on this machine: ours, ARAP, FFMP, GE and
// CCW16 side by side, each method's distortion over the sequence, Tables 1–4, the paper's
// claims decided on the scene, report.json and report.md.
// The work is the comparison library (compare/, hsi/compare/compare.h); this file keeps the
// options, picks the Newton core and the Vulkan pieces, and prints the progress.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <memory>

#include "hsi/sample_limits.h"
#include "commands.h"
#include "hsi/compare/compare.h"
#include "hsi/compare/runs.h"
#include "hsi/compute/dense_eval.h"
#include "hsi/compute/vulkan_context.h"
#include "hsi/runtime/backend.h"

namespace hsi::cli {

namespace {

struct Opts {
  compare::Options run;
  std::string out, size = "420";
  std::string backend = "auto", device;
  bool validation = false;
};

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

// The Newton core for our solves: the one backend factory's (hsi/runtime/backend.h).
std::unique_ptr<NewtonCore> make_core(const ShapeSetup& setup, const std::string& backend) {
  runtime::NewtonCoreChoice c = runtime::make_newton_core(setup, runtime::parse_backend(backend));
  if (!c.choice.fallback.empty()) std::printf("Newton core: %s\n", runtime::describe(c.choice).c_str());
  return std::move(c.core);
}

void run_compare(const Opts& o) {
  compare::Options r = o.run;  // its backends live no longer than the Vulkan context below
  r.panel = parse_size(o.size);
  r.out = o.out;
  compare::check_options(r);  // refused before the Vulkan device is opened
  compute::ContextOptions co;
  co.validation = o.validation;
  co.device_name = o.device;
  std::unique_ptr<compute::Context> ctx;
  try {
    ctx = std::make_unique<compute::Context>(co);
  } catch (const compute::VulkanUnavailable& e) {
    throw std::runtime_error(std::string("hsi compare renders with Vulkan and needs a device (a GPU, or lavapipe on the CPU): ") +
                             e.what());
  }
  compute::DenseEvaluator dense(*ctx);
  r.backends.vulkan = ctx.get();
  r.backends.newton_core = [backend = o.backend](const ShapeSetup& setup) { return make_core(setup, backend); };
  // f at the mesh's vertices (Tables 3–4) on the same backend, and the GPU's clocks where it may be used.
  const runtime::Backend requested = runtime::parse_backend(o.backend);
  r.backends.mesh_evaluator = [requested](const Cage& cage, std::span<const cd> points) {
    runtime::MeshEvaluatorChoice c = runtime::make_mesh_evaluator(cage, points, requested);
    if (!c.choice.fallback.empty()) std::printf("mesh evaluator: %s\n", runtime::describe(c.choice).c_str());
    return std::move(c.evaluator);
  };
  if (requested != runtime::Backend::Cpu) r.backends.gpu_clocks = [] { return runtime::gpu_clocks(); };
  r.backends.dense_eval = [&dense](const Cage& cage, const HarmonicMap& map, std::span<const cd> points) {
    return dense.evaluate_points(cage, map, points).size();
  };
  // Progress on stderr, one line per phase and run (a full run takes minutes on a laptop
  // CPU); per-frame counters only on a terminal, overwritten in place.
  const auto t0 = std::chrono::steady_clock::now();
  const bool tty = isatty(fileno(stderr));
  bool counting = false;  // a per-frame counter is on the line
  r.progress = [&](std::string_view line, bool transient) {
    if (transient) {
      if (tty) std::fprintf(stderr, "\r[compare] %.*s   ", static_cast<int>(line.size()), line.data());
      counting = tty;
      return;
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "%s[compare %6.1f s] %.*s\n", counting ? "\n" : "", s, static_cast<int>(line.size()), line.data());
    std::fflush(stderr);
    counting = false;
  };
  const std::filesystem::path md = compare::run(r);
  std::printf("%s\n", md.string().c_str());
}

}  // namespace

void register_compare(CLI::App& app) {
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "Reproduce the paper's comparisons on one scene, measured on this machine: ours, ARAP, FFMP, GE and CCW16\n"
      "(log derivatives; on a simply-connected shape also its boundary-metric variant, the paper's Fig. 8) side by\n"
      "side with the distortion colour map at t = 0.25, 0.5, 0.75 of a keyframe interval, each method's largest\n"
      "distortion over the sequence against the keyframes' bounds, Tables 1-4 (Hessian projections, the Hessian\n"
      "sample ratio, time against mesh resolution with GE, and against ARAP, FFMP and GE) and the paper's claims\n"
      "about them, each decided on the scene. Writes PNGs, report.json and report.md (last; a failed run leaves\n"
      "no report) into DIR.");
  cmd->add_option("scene", o->run.scene, "Scene file (.json) with two or more keyframes")->required();
  cmd->add_option("-o,--output", o->out, "Output folder")->required();
  cmd->add_option("--frames", o->run.frames, "Frames over the keyframes' range for the distortion plots")
      ->capture_default_str()->check(CLI::Range(2, 100000));
  cmd->add_option("--table-frames", o->run.table_frames, "Frames of each sequence of Tables 1 and 2")
      ->capture_default_str()->check(CLI::Range(2, 100000));
  cmd->add_option("--mesh-vertices", o->run.mesh_vertices, "Vertices of the mesh the baselines run on and the figures use (about)")
      ->capture_default_str()->check(CLI::Range(100, 5000000));
  cmd->add_option("--samples", o->run.samples, "Boundary samples |G| (default: the scene's)")->check(CLI::Range(kMinSamples, kMaxSamples));
  cmd->add_option("--size", o->size, "Longer side of each panel of the side-by-side figures, in pixels")->capture_default_str();
  cmd->add_option("--segment", o->run.segment, "Keyframe interval of the side-by-side figures (0: keyframes 0 to 1)")->capture_default_str();
  cmd->add_option("--ratios", o->run.ratios, "Hessian sample ratios r of Table 2")->capture_default_str()->delimiter(',');
  cmd->add_option("--table3-vertices", o->run.table3_vertices, "Mesh resolutions of Table 3 (vertices, about)")
      ->capture_default_str()->delimiter(',');
  cmd->add_option("--ccw16-memory", o->run.ccw16_memory_mb,
                  "MB of basis rows CCW16's boundary-metric variant may hold (it keeps them at every vertex and quadrature\n"
                  "node: ~300 MB at 10k vertices); above it, that variant runs on a coarser mesh and the report says so")
      ->capture_default_str()->check(CLI::Range(1.0, 1e6));
  cmd->add_flag("--no-800k", o->run.no_800k, "Skip Table 3's rows of 800k vertices or more (a quick run)");
  cmd->add_option("--ge-max-vertices", o->run.ge_max_vertices,
                  "Largest Table 3 resolution GE runs at (a sparse Cholesky of the whole mesh per Newton step); above it\n"
                  "the row says GE was not run, with an estimate of its time per frame")
      ->capture_default_str()->check(CLI::Range(100, 5000000));
  cmd->add_option("--timing-frames", o->run.timing_frames, "Frames timed per resolution in Table 3")
      ->capture_default_str()->check(CLI::Range(1, 1000));
  cmd->add_option("--backend", o->backend, runtime::kBackendHelp)->capture_default_str()->check(CLI::IsMember(runtime::backend_names()));
  cmd->add_option("--device", o->device, "Vulkan device name substring (default: HSI_VULKAN_DEVICE, else the best)");
  cmd->add_flag("--validation", o->validation, "Run with the Vulkan validation layer; fail on any message");
  cmd->callback([o] { run_compare(*o); });
}

}  // namespace hsi::cli
