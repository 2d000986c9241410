// Benchmark of the CPU interpolation (paper Tables 1, 2, 4): per bundled scene, a
// warm-started sequence (mean/max ms per frame, iterations, time per part of an
// iteration, and of a frame), the overlap check's crossing search alone (the hierarchy
// kept per checker against the reference made per call), a from-scratch solve at
// t = 0.5 for each Hessian projection, and the Hessian sample ratio sweep. Prints
// Markdown tables. Not a test: timings only.
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
  int frames = 500, sweep_frames = 100, samples = 10000, crossing_images = 20, crossing_reps = 20;
  bool skip_projection = false, skip_sweep = false, crossings_only = false;
  app.add_option("scenes", scenes, "Scene files with two or more keyframes")->required();
  app.add_option("--frames", frames, "Frames of the warm-started sequence")->capture_default_str();
  app.add_option("--sweep-frames", sweep_frames, "Frames per r in the ratio sweep")->capture_default_str();
  app.add_option("--samples", samples, "|G|")->capture_default_str();
  app.add_flag("--skip-projection", skip_projection, "Skip the Delete/FullProj/PartProj comparison");
  app.add_flag("--skip-sweep", skip_sweep, "Skip the r sweep");
  app.add_option("--crossing-images", crossing_images, "Frames' images the crossing search is timed on, per scene")
      ->capture_default_str();
  app.add_option("--crossing-reps", crossing_reps, "Timed searches per image")->capture_default_str();
  app.add_flag("--crossings-only", crossings_only,
               "Only the crossing search table (over a sequence of --frames frames; implies --skip-projection --skip-sweep)");
  CLI11_PARSE(app, argc, argv);
  if (crossings_only) skip_projection = skip_sweep = true;

  std::printf("CPU threads: %d; |G| = %d\n\n", omp_get_max_threads(), samples);
  if (!crossings_only) {
    std::printf("## Warm-started sequences (%d frames, r = 20%%, PartProj)\n\n", frames);
    std::printf("| scene | n | mean ms/frame | max ms/frame | mean iters/frame | uncertified | energy+grad ms/it | Hessian ms/it | "
                "solve ms/it | line search ms/it | certificate ms/it |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  }
  std::vector<Loaded> all;
  std::string parts_table =
      "\n## Where a frame's time goes (ms; FrameResult::parts; first: the first solved frame after set-up; the rest: "
      "means over the warm frames, every solved frame but the first; crossings: the search's own time, on the sequence's "
      "crossing thread beside the next solve; wait: what the sequence waited for it, counted in the frame; wall: the "
      "sequence's wall clock per solved frame)\n\n"
      "| scene | first frame | first: solve | first: image + crossings | warm frame | wall / frame | targets | solve | pose | "
      "image | crossings | crossings wait | distortion | rest |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  std::string crossing_table =
      "\n## The crossing search alone (ms per call, one thread; images of the sequence's frames: kept = the hierarchy kept "
      "by the checker and refit, check_points; reference = the polylines and hierarchy made per call, "
      "check_points_reference; on few cores run with OMP_WAIT_POLICY=passive: OpenMP threads left spinning after the "
      "sequence take cores from it)\n\n"
      "| scene | breakpoints | images (overlapping) | kept ms | reference ms | reference / kept | same results |\n"
      "|---|---|---|---|---|---|---|\n";
  for (const std::string& path : scenes) {
    all.push_back(load(path, samples, 0.2));
    Loaded& L = all.back();
    Interpolator interp(*L.setup, L.times, L.maps);
    const auto ts = std::chrono::steady_clock::now();
    const auto seq = interp.sequence(frames);
    const double seq_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - ts).count();
    {
      const bench::CrossingSearchTimes c = bench::time_crossing_search(*L.setup, seq, crossing_images, crossing_reps);
      char row[512];
      std::snprintf(row, sizeof row, "| %s | %d | %d (%d) | %.3f | %.3f | %.1f | %s |\n", L.name.c_str(), c.points, c.images,
                    c.overlapping, c.kept_ms, c.reference_ms, c.reference_ms / c.kept_ms, c.same ? "yes" : "NO");
      crossing_table += row;
      if (crossings_only) continue;
    }
    {
      const bench::FrameParts p = bench::frame_parts(seq, seq_ms);
      char row[512];
      std::snprintf(row, sizeof row,
                    "| %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.3f | %.2f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n",
                    L.name.c_str(), p.first_ms, p.first.solve, p.first.image + p.first.crossings, p.mean_ms, p.wall_ms,
                    p.mean.targets, p.mean.solve, p.mean.pose, p.mean.image, p.mean.crossings, p.mean.crossings_wait,
                    p.mean.distortion, p.rest());
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
      t += f.timing;
    }
    const double its = std::max(1.0, it);
    std::printf("| %s | %d | %.1f | %.1f | %.2f | %d | %.1f | %.1f | %.1f | %.1f | %.1f |\n", L.name.c_str(), L.setup->map_space.n(),
                ms / solved, mx, it / solved, bad, t.energy_gradient / its, t.hessian / its, t.solve / its, t.line_search / its,
                t.certificate / its);
    std::fflush(stdout);
  }
  if (!crossings_only) std::printf("%s", parts_table.c_str());
  std::printf("%s", crossing_table.c_str());
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
