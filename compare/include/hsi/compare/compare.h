// hsi compare as a library: the paper's claims reproduced on one scene against the
// baselines (issues #11, #24), measured in one run. The pipeline, stage by stage: runs.h
// (ours, ARAP, FFMP, GE, CCW16, timings), alignment.h (Fig. 8), figures.h (panels, plots),
// tables.h (Tables 1–4), claims.h (the paper's claims decided on the scene), report.h
// (report.json, report.md). What is picked per machine (the Newton
// core, the GPU dense evaluation) comes from the caller in Backends: no choice is made here.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hsi/mesh_evaluator.h"
#include "hsi/newton.h"
#include "hsi/shape_setup.h"

namespace hsi::compute {
class Context;
}

namespace hsi::compare {

// f of a map at many points on a GPU (Table 3's GPU column); returns how many values it made.
using DenseEval = std::function<std::size_t(const Cage&, const HarmonicMap&, std::span<const cd>)>;

struct Backends {
  // The Newton core for our solves at a setup; null: the CPU reference (make_cpu_newton_core).
  std::function<std::unique_ptr<NewtonCore>(const ShapeSetup&)> newton_core;
  // The Vulkan context the side-by-side panels are rendered with; required (its
  // validation log, where enabled, fails the run before any report is written).
  compute::Context* vulkan = nullptr;
  // Table 3's column of f at the mesh's vertices on the GPU; null: not available, and
  // `dense_eval_unavailable` is the reason the report prints in its place.
  DenseEval dense_eval;
  std::string dense_eval_unavailable = "no GPU dense evaluation was given";
  // f at a mesh's vertices from cached basis rows (Tables 3–4: ours = solve + f at the
  // vertices), on the Newton core's backend; null: the CPU evaluator (which Table 3
  // also times at every resolution).
  std::function<std::unique_ptr<MeshEvaluator>(const Cage&, std::span<const cd>)> mesh_evaluator;
  // The GPU's clocks now, one line (hsi::runtime::gpu_clocks); null or empty: no GPU.
  std::function<std::string()> gpu_clocks;
};

// Progress, one line per phase and per run within a phase; `transient` lines are
// per-frame counters a terminal may overwrite in place (the CLI drops them elsewhere).
using Progress = std::function<void(std::string_view line, bool transient)>;

struct Options {
  std::string scene;                // scene file (.json), two or more keyframes
  std::filesystem::path out;        // output folder
  int frames = 100;                 // over the keyframes' range, for the distortion plots
  int table_frames = 40;            // each sequence of Tables 1 and 2
  int mesh_vertices = 10000;        // about, the mesh the baselines run on and the figures use
  int samples = 0;                  // |G|; 0: the scene's
  int timing_frames = 3;            // frames timed per resolution in Table 3
  int segment = 0;                  // keyframe interval of the side-by-side figures
  int panel = 420;                  // longer side of each side-by-side panel, pixels (96..4096)
  double ccw16_memory_mb = 128;     // most the CCW16 boundary-metric variant may hold in basis rows
  std::vector<double> ratios = {1.0, 0.5, 0.2, 0.1, 0.05};   // Table 2's Hessian sample ratios r
  std::vector<int> table3_vertices = {8000, 80000, 800000};  // Table 3's mesh resolutions (about)
  bool no_800k = false;             // skip Table 3's rows of 800k vertices or more
  int ge_max_vertices = 200'000;    // Table 3 runs GE up to this many vertices; above, the row says why not and estimates it
  Backends backends;
  Progress progress;                // null: silent
};

// Runs every stage and writes the PNGs, report.json and report.md (last) into
// options.out; returns report.md's path. Bad options or a scene that cannot be compared:
// InputError naming it, before any work. A run that fails removes what it wrote.
std::filesystem::path run(const Options& options);

}  // namespace hsi::compare
