// hsi interpolate SCENE --frames F -o OUT/: the paper's method end to end, with the
// frames file, a per-frame report (JSON and table), plots and drawings of frames.
#include <unistd.h>

#include <chrono>
#include <cstdio>

#include "commands.h"
#include "hsi/frames_io.h"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/scene_sequence.h"
#include "plot.h"
#ifdef HSI_WITH_CUDA
#include "hsi/cuda/newton_core.h"
#endif

namespace hsi::cli {

void register_interpolate(CLI::App& app) {
  struct Opts {
    std::string scene, out = "out";
    int frames = 500, samples = 0, png_count = 16, max_iterations = 100;
    double ratio = 0, tolerance = 5e-8;
    std::string projection = "partproj";
    std::string backend = "auto";
    bool projected_only = false, gauged_rotation = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "interpolate",
      "Interpolate a scene's keyframes: every frame a certified locally injective harmonic map.\n"
      "Writes OUT/frames.hsif (coefficients), OUT/report.json and OUT/report.txt (per frame: iterations,\n"
      "energy, time, certified, distortion against the keyframes' bounds), plots (energy.png,\n"
      "iterations.png, distortion.png) and drawings of some frames (OUT/frames/frame_NNNN.png).");
  cmd->add_option("scene", o->scene, "Scene file (.json) with two or more keyframes")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->out, "Output folder")->capture_default_str();
  cmd->add_option("--frames", o->frames, "Number of frames over the keyframes' time range")->capture_default_str()->check(CLI::Range(2, 1000000));
  cmd->add_option("--samples", o->samples, "Boundary samples |G| (default: the scene's, 10000)")->check(CLI::Range(100, 10000000));
  cmd->add_option("--ratio", o->ratio, "Hessian sample ratio r (default: the scene's, 0.2)")->check(CLI::Range(1e-6, 1.0));
  cmd->add_option("--tolerance", o->tolerance, "Stop a frame when its energy decreases by less than this fraction of itself (and not in a slow linear crawl)")->capture_default_str();
  cmd->add_option("--max-iterations", o->max_iterations, "Newton iterations per frame at most")->capture_default_str();
  cmd->add_option("--projection", o->projection, "Hessian PSD projection: partproj, fullproj or delete")->capture_default_str();
  cmd->add_flag("--projected-only", o->projected_only,
                "Always use the projected Hessian (the paper's method), not the exact one where it is positive definite");
  cmd->add_flag("--gauged-rotation", o->gauged_rotation,
                "Keep the global rotation pinned by its gauge in projected systems instead of solving for it (the paper's method)");
  cmd->add_option("--backend", o->backend, "Newton core: cpu, cuda, or auto (CUDA when a device is present)")
      ->capture_default_str()
      ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
  cmd->add_option("--png-frames", o->png_count, "Draw this many evenly spaced frames (0: none)")->capture_default_str();
  cmd->callback([o] {
    using Clock = std::chrono::steady_clock;
    Scene scene = load_scene(o->scene);
    if (scene.keyframes.size() < 2) throw InputError(o->scene + ": interpolation needs at least two keyframes");
    const std::shared_ptr<const ShapeSetup> setup = scene_setup(scene, o->samples, o->ratio);
    std::printf("scene %s: %d loops, cage %d vertices, n = %d, |G| = %zu, |H| = %zu\n", scene.name.c_str(),
                scene.shape.loop_count(), setup->cage.vertex_count(), setup->map_space.n(), setup->G.size(), setup->H.size());
    solve_scene_keyframes(scene, *setup, {}, false, [&](const SceneKeyframe& k) {
      if (k.solved)
        std::printf("keyframe %d solved from targets: %s\n", k.index, k.result.message.c_str());
      else
        std::printf("keyframe %d: certified locally injective\n", k.index);
      // Locally injective is not globally injective: say so when its outline crosses itself.
      if (k.overlap.overlaps()) std::printf("WARNING: keyframe %d %s\n", k.index, describe(k.overlap).c_str());
    });
    std::vector<double> times;
    std::vector<HarmonicMap> maps;
    for (const Keyframe& k : scene.keyframes) {
      times.push_back(k.time);
      maps.push_back(*k.coefficients);
    }
    InterpolationOptions io;
    io.tolerance = o->tolerance;
    io.max_iterations = o->max_iterations;
    io.projection = parse_projection(o->projection);
    io.exact_hessian_when_definite = !o->projected_only;
    io.free_rotation = !o->gauged_rotation;
    // The Newton core: the CUDA twin where asked for (or, with auto, where a device
    // is present), the CPU reference otherwise.
    std::unique_ptr<NewtonCore> core;
    std::string why = "this hsi was built without CUDA";
#ifdef HSI_WITH_CUDA
    if (o->backend != "cpu" && hsi::cuda::device_available(&why)) core = hsi::cuda::make_newton_core(*setup);
#endif
    if (!core && o->backend == "cuda") throw std::runtime_error("--backend cuda: no CUDA device (" + why + ")");
    if (!core) core = make_cpu_newton_core(setup->D_G, setup->H);
    std::printf("Newton core: %s\n", core->name());
    Interpolator interp(*setup, times, maps, io, std::move(core));

    const std::filesystem::path out(o->out);
    std::filesystem::create_directories(out);
    const bool tty = isatty(fileno(stderr));
    const auto t0 = Clock::now();
    bool prev_overlaps = false;
    auto progress = [&](const FrameResult& f, int i, int n) {
      const double el = std::chrono::duration<double>(Clock::now() - t0).count();
      const double eta = el / (i + 1) * (n - i - 1);
      if (tty)
        std::fprintf(stderr, "\r[interpolate] frame %d/%d  t = %.4f  %d it  %.1f ms  %s  ETA %.0f s   ", i + 1, n, f.t,
                     f.iterations, f.ms, f.certified ? "certified" : "NOT CERTIFIED", eta);
      else if ((i + 1) % std::max(1, n / 20) == 0 || i + 1 == n)
        std::fprintf(stderr, "[interpolate] frame %d/%d (%.0f%%), %.1f s elapsed, ETA %.0f s\n", i + 1, n, 100.0 * (i + 1) / n, el, eta);
      if (!f.certified) std::fprintf(stderr, "%s[interpolate] frame %d (t = %.6f) NOT CERTIFIED: %s\n", tty ? "\n" : "", i, f.t,
                                     f.certificate.reason.c_str());
      if (f.overlap.overlaps() && (i == 0 || !prev_overlaps))  // the first frame of each overlapping run
        std::fprintf(stderr, "%s[interpolate] frame %d (t = %.6f) %s\n", tty ? "\n" : "", i, f.t, describe(f.overlap).c_str());
      prev_overlaps = f.overlap.overlaps();
      if (tty && i + 1 == n) std::fprintf(stderr, "\n");
    };

    SceneSequence seq{setup, interp.sequence(o->frames, progress), 0.0, io};
    seq.total_s = std::chrono::duration<double>(Clock::now() - t0).count();
    const std::vector<FrameResult>& frames = seq.frames;
    write_frames(out / "frames.hsif", seq.frame_file());
    write_file_atomic(out / "report.json", report_json(scene, seq, o->scene));

    // The table and the plots' series.
    std::vector<double> ts, energy, iters, kappa, kappa_b, s1, s1b, s2, s2b, flagged;
    std::string table =
        "frame        t  keyframe  certified  iters     energy      ms   sigma1_max  sigma2_min  conformal_max  bound_excess  overlaps\n";
    for (size_t i = 0; i < frames.size(); ++i) {
      const FrameResult& f = frames[i];
      ts.push_back(f.t);
      energy.push_back(f.energy);
      iters.push_back(f.iterations);
      kappa.push_back(f.distortion.conformal_max);
      kappa_b.push_back(f.bound.conformal_max);
      s1.push_back(f.distortion.sigma1_max);
      s1b.push_back(f.bound.sigma1_max);
      s2.push_back(f.distortion.sigma2_min);
      s2b.push_back(f.bound.sigma2_min);
      if (!f.certified) flagged.push_back(f.t);
      char line[256];
      std::snprintf(line, sizeof line, "%5zu %8.5f  %8s  %9s  %5d  %9.6f  %6.1f  %11.5f %11.5f  %13.5f  %12.3e  %8s\n", i, f.t,
                    f.keyframe ? "yes" : "", f.certified ? "yes" : "NO", f.iterations, f.energy, f.ms,
                    f.distortion.sigma1_max, f.distortion.sigma2_min, f.distortion.conformal_max, f.bound_excess,
                    f.overlap.overlaps() ? "YES" : "");
      table += line;
    }
    const SequenceSummary sum = summarize(frames, seq.total_s);
    char head[1024];
    // Certified means locally injective; a frame can still overlap itself (overlap.h).
    char overlap_line[320] = "";
    if (sum.overlapping > 0)
      std::snprintf(overlap_line, sizeof overlap_line,
                    "WARNING: %d frame(s) overlap themselves (the image of the boundary crosses itself: locally but not "
                    "globally injective; sampled at the boundary breakpoints)\n",
                    sum.overlapping);
    std::snprintf(head, sizeof head,
                  "hsi interpolate %s: %zu frames, %d certified locally injective, %d NOT certified, %d overlapping themselves\n%s"
                  "mean %.2f Newton iterations and %.1f ms per solved frame (max %.1f ms), %.1f s in all\n"
                  "%d frames within the keyframes' distortion bounds, largest excess %.3g (relative)\n\n",
                  o->scene.c_str(), frames.size(), sum.certified, sum.uncertified, sum.overlapping, overlap_line, sum.mean_iterations, sum.mean_ms, sum.max_ms,
                  sum.total_s, sum.within_bounds, sum.max_bound_excess);
    write_file_atomic(out / "report.txt", std::string(head) + table);

    plot_series(out / "energy.png", scene.name + ": energy per frame (2 = metric reproduced exactly)", "t", ts,
                {{"energy", energy, 0.1, 0.3, 0.7}}, flagged);
    plot_series(out / "iterations.png", scene.name + ": Newton iterations per frame", "t", ts,
                {{"iterations", iters, 0.2, 0.5, 0.2}}, flagged);
    plot_series(out / "distortion.png", scene.name + ": distortion on the boundary vs the keyframes' bounds", "t", ts,
                {{"conformal max", kappa, 0.8, 0.2, 0.1},
                 {"bound", kappa_b, 0.8, 0.2, 0.1, true},
                 {"sigma1 max", s1, 0.1, 0.3, 0.7},
                 {"bound", s1b, 0.1, 0.3, 0.7, true},
                 {"sigma2 min", s2, 0.2, 0.55, 0.2},
                 {"bound", s2b, 0.2, 0.55, 0.2, true}},
                flagged);
    if (o->png_count > 0) {
      std::filesystem::create_directories(out / "frames");
      const int count = std::min<int>(o->png_count, static_cast<int>(frames.size()));
      for (int k = 0; k < count; ++k) {
        const size_t i = count == 1 ? 0 : static_cast<size_t>(k) * (frames.size() - 1) / static_cast<size_t>(count - 1);
        const FrameResult& f = frames[i];
        MapPlot extras;
        char title[160];
        std::snprintf(title, sizeof title, "%s  frame %zu  t = %.3f  %d it  conformal %.3f", scene.name.c_str(), i, f.t,
                      f.iterations, f.distortion.conformal_max);
        extras.title = title;
        extras.uncertified = !f.certified;
        extras.overlaps = f.overlap.overlaps();
        char name[64];
        std::snprintf(name, sizeof name, "frame_%04zu.png", i);
        plot_map(out / "frames" / name, scene.shape, setup->cage, f.map, extras, 640);
      }
    }
    std::printf("%s", head);
    std::printf("wrote %s/{frames.hsif, report.json, report.txt, energy.png, iterations.png, distortion.png%s}\n",
                out.string().c_str(), o->png_count > 0 ? ", frames/" : "");
    if (sum.uncertified > 0) throw std::runtime_error(std::to_string(sum.uncertified) + " frame(s) could not be certified (see the report)");
  });
}

}  // namespace hsi::cli
