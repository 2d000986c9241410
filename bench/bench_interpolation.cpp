// Benchmark of the CPU interpolation (paper Tables 1, 2, 4): per bundled scene, a
// warm-started sequence (mean/max ms per frame, iterations, time per part of an
// iteration), a from-scratch solve at t = 0.5 for each Hessian projection, and the
// Hessian sample ratio sweep. Prints Markdown tables. Not a test: timings only.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <string>
#include <omp.h>

#include "bench_scenes.h"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"

using namespace hsi;

namespace {

using bench::Loaded;
using bench::load;

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hsi interpolation benchmark (CPU): prints Markdown tables"};
  std::vector<std::string> scenes;
  int frames = 500, sweep_frames = 100, samples = 10000;
  bool skip_projection = false, skip_sweep = false;
  app.add_option("scenes", scenes, "Scene files with two or more keyframes")->required();
  app.add_option("--frames", frames, "Frames of the warm-started sequence")->capture_default_str();
  app.add_option("--sweep-frames", sweep_frames, "Frames per r in the ratio sweep")->capture_default_str();
  app.add_option("--samples", samples, "|G|")->capture_default_str();
  app.add_flag("--skip-projection", skip_projection, "Skip the Delete/FullProj/PartProj comparison");
  app.add_flag("--skip-sweep", skip_sweep, "Skip the r sweep");
  CLI11_PARSE(app, argc, argv);

  std::printf("CPU threads: %d; |G| = %d\n\n", omp_get_max_threads(), samples);
  std::printf("## Warm-started sequences (%d frames, r = 20%%, PartProj)\n\n", frames);
  std::printf("| scene | n | mean ms/frame | max ms/frame | mean iters/frame | uncertified | energy+grad ms/it | Hessian ms/it | "
              "solve ms/it | line search ms/it | certificate ms/it |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::vector<Loaded> all;
  std::string parts_table =
      "\n## Where a frame's time goes (ms; FrameResult::parts; first: the first solved frame after set-up; the rest: "
      "means over the warm frames, every solved frame but the first)\n\n"
      "| scene | first frame | first: solve | first: image + crossings | warm frame | targets | solve | pose | image | "
      "crossings | distortion | rest |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& path : scenes) {
    all.push_back(load(path, samples, 0.2));
    Loaded& L = all.back();
    Interpolator interp(*L.setup, L.times, L.maps);
    const auto seq = interp.sequence(frames);
    {
      const bench::FrameParts p = bench::frame_parts(seq);
      char row[512];
      std::snprintf(row, sizeof row, "| %s | %.2f | %.2f | %.2f | %.2f | %.3f | %.2f | %.3f | %.3f | %.3f | %.3f | %.3f |\n",
                    L.name.c_str(), p.first_ms, p.first.solve, p.first.image + p.first.crossings, p.mean_ms, p.mean.targets,
                    p.mean.solve, p.mean.pose, p.mean.image, p.mean.crossings, p.mean.distortion, p.rest());
      parts_table += row;
    }
    double ms = 0, mx = 0, it = 0;
    int solved = 0, bad = 0;
    NewtonResult::Timing t;
    for (const FrameResult& f : seq) {
      bad += !f.certified;
      if (f.keyframe) continue;
      ++solved;
      ms += f.ms;
      mx = std::max(mx, f.ms);
      it += f.iterations;
      t.energy_gradient += f.timing.energy_gradient;
      t.hessian += f.timing.hessian;
      t.solve += f.timing.solve;
      t.line_search += f.timing.line_search;
      t.certificate += f.timing.certificate;
    }
    const double its = std::max(1.0, it);
    std::printf("| %s | %d | %.1f | %.1f | %.2f | %d | %.1f | %.1f | %.1f | %.1f | %.1f |\n", L.name.c_str(), L.setup->map_space.n(),
                ms / solved, mx, it / solved, bad, t.energy_gradient / its, t.hessian / its, t.solve / its, t.line_search / its,
                t.certificate / its);
    std::fflush(stdout);
  }
  std::printf("%s", parts_table.c_str());
  std::fflush(stdout);
  if (!skip_projection) {
    std::printf("\n## From scratch at t = 0.5 from keyframe 0 (paper Table 1)\n\n");
    std::printf("| scene | Delete iters | Delete s | FullProj iters | FullProj s | PartProj iters | PartProj s |\n|---|---|---|---|---|---|---|\n");
    for (Loaded& L : all) {
      std::printf("| %s |", L.name.c_str());
      const double t = (L.times[0] + L.times[1]) / 2;
      for (HessianProjection p : {HessianProjection::Delete, HessianProjection::FullProj, HessianProjection::PartProj}) {
        InterpolationOptions o;
        o.projection = p;
        Interpolator interp(*L.setup, L.times, L.maps, o);
        const FrameResult f = interp.frame(t);
        std::printf(" %d%s | %.3f |", f.iterations, f.converged ? "" : " (not converged)", f.ms / 1000);
      }
      std::printf("\n");
      std::fflush(stdout);
    }
  }
  if (!skip_sweep) {
    std::printf("\n## Hessian sample ratio r (paper Table 2), %d warm-started frames: mean ms / mean iterations per frame\n\n", sweep_frames);
    const double ratios[] = {1.0, 0.5, 0.2, 0.1, 0.05};
    std::printf("| scene | r = 100%% | r = 50%% | r = 20%% | r = 10%% | r = 5%% |\n|---|---|---|---|---|---|\n");
    for (const std::string& path : scenes) {
      std::printf("| %s |", all[static_cast<size_t>(&path - scenes.data())].name.c_str());
      for (double r : ratios) {
        Loaded L = load(path, samples, r);
        Interpolator interp(*L.setup, L.times, L.maps);
        const auto seq = interp.sequence(sweep_frames);
        double ms = 0, it = 0;
        int solved = 0, bad = 0;
        for (const FrameResult& f : seq) {
          bad += !f.certified;
          if (f.keyframe) continue;
          ++solved;
          ms += f.ms;
          it += f.iterations;
        }
        std::printf(" %.1f / %.2f%s |", ms / solved, it / solved, bad ? " (uncertified!)" : "");
        std::fflush(stdout);
      }
      std::printf("\n");
    }
  }
  return 0;
}
