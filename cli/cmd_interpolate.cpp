// hsi interpolate SCENE --frames F -o OUT/: the paper's method end to end, with the
// frames file, a per-frame report (JSON and table), plots and drawings of frames.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "hsi/sample_limits.h"
#include "commands.h"
#include "hsi/frames_io.h"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/draw/plot.h"
#include "hsi/scene_sequence.h"
#include "hsi/scene_texture.h"
#include "hsi/runtime/backend.h"

namespace hsi::cli {

using draw::MapPlot;
using draw::plot_map;
using draw::plot_series;
using draw::PlotSpec;
using draw::Series;

void register_interpolate(CLI::App& app) {
  struct Opts {
    std::string scene, out = "out";
    int frames = 500, samples = 0, png_count = 16, max_iterations = 100, per_interval = 0;
    double ratio = 0, tolerance = 5e-8, chord_decrement_stop = InterpolationOptions{}.chord_decrement_stop;
    std::string projection = "fullproj";
    std::string exact_samples = to_string(InterpolationOptions{}.exact_samples);
    std::string backend = "auto";
    std::string timing;  // empty: the scene's keyframe timings
    std::string predict_start = to_string(InterpolationOptions{}.predict_start);
    bool projected_only = false, gauged_rotation = false, no_chord = false, no_carry = false;
    bool allow_unconverged = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "interpolate",
      "Interpolate a scene's keyframes: every frame a certified locally injective harmonic map.\n"
      "Writes OUT/frames.hsif (coefficients), OUT/report.json and OUT/report.txt (per frame: iterations,\n"
      "energy, time, certified, converged, distortion sampled at the certificate's breakpoints and its certified\n"
      "bound, each against the keyframes'), plots (energy.png, iterations.png, distortion.png) and drawings of\n"
      "some frames (OUT/frames/frame_NNNN.png). Frames not certified (red) or not converged (orange) are flagged.\n" +
          std::string(kFlaggedFramesHelp));
  cmd->add_option("scene", o->scene, "Scene file (.json) with two or more keyframes")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->out, "Output folder")->capture_default_str();
  add_frame_options(cmd, o->frames, o->per_interval);
  cmd->add_option("--samples", o->samples, "Boundary samples |G| (default: the scene's, 10000)")->check(CLI::Range(kMinSamples, kMaxSamples));
  cmd->add_option("--ratio", o->ratio, "Hessian sample ratio r (default: the scene's, 0.2)")->check(CLI::Range(1e-6, 1.0));
  cmd->add_option("--tolerance", o->tolerance, "Stop a frame when its energy decreases by less than this fraction of itself (and not in a slow linear crawl)")->capture_default_str();
  cmd->add_option("--max-iterations", o->max_iterations, "Newton iterations per frame at most")->capture_default_str();
  cmd->add_option("--projection", o->projection, "Hessian PSD projection: fullproj, partproj (the paper's) or delete")->capture_default_str();
  cmd->add_option("--exact-samples", o->exact_samples,
                  "The samples the exact Newton systems' Hessians sum over: subset (H, r|G|, as the projected ones), "
                  "subset-then-all (H, then all of G where H's is not positive definite), all (G: fewer iterations, a "
                  "dearer Hessian on the CPU) or auto (the core's choice: subset on the CPU, all on CUDA)")
      ->capture_default_str()
      ->check(CLI::IsMember(exact_samples_names()));
  cmd->add_option("--timing", o->timing,
                  "How every keyframe interval is travelled: linear (the paper's), smooth (C1 through the keyframes), ease "
                  "(in and out) or hold (default: each keyframe's \"timing\" in the scene, else linear)")
      ->check(CLI::IsMember({"linear", "smooth", "ease", "hold"}));
  cmd->add_flag("--projected-only", o->projected_only,
                "Always use the projected Hessian (the paper's method), not the exact one where it is positive definite, and never switch to FullProj in a long solve");
  cmd->add_flag("--gauged-rotation", o->gauged_rotation,
                "Keep the global rotation pinned by its gauge in projected systems instead of solving for it (the paper's method)");
  cmd->add_flag("--no-chord", o->no_chord,
                "Build every frame's Newton systems at its own points: no chord step solved with the previous frame's last "
                "exact system (slower; the same frames within the tolerance)");
  cmd->add_option("--chord-decrement-stop", o->chord_decrement_stop,
                  "After a frame's full chord step, stop it when the kept system's decrement (scaled by that step's model "
                  "error) is below this share of the tolerance, with no exact system of its own (0: never)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_flag("--no-carry-all-samples", o->no_carry,
                "Start every frame's Hessians on the subset H, even after an earlier frame's solve moved them to all of G "
                "(by default a sequence carries that move on the CUDA core)");
  add_predict_start_option(cmd, o->predict_start);
  cmd->add_option("--backend", o->backend, runtime::kBackendHelp)
      ->capture_default_str()
      ->check(CLI::IsMember(runtime::backend_names()));
  cmd->add_option("--png-frames", o->png_count, "Draw this many evenly spaced frames (0: none)")->capture_default_str();
  cmd->add_flag("--allow-unconverged", o->allow_unconverged,
                "Exit 0 when certified frames did not converge (still flagged in every output)");
  cmd->callback([o] {
    using Clock = std::chrono::steady_clock;
    Scene scene = load_scene(o->scene);
    if (scene.keyframes.size() < 2) throw InputError(o->scene + ": interpolation needs at least two keyframes (it has " + std::to_string(scene.keyframes.size()) + "); " + kHowToAddKeyframes);
    const std::shared_ptr<const ShapeSetup> setup = scene_setup(scene, o->samples, o->ratio);
    std::printf("scene %s: %d loops, cage %d vertices, n = %d, |G| = %zu, |H| = %zu\n", scene.name.c_str(),
                scene.shape.loop_count(), setup->cage.vertex_count(), setup->map_space.n(), setup->G.size(), setup->H.size());
    // One core for both: keyframes given by targets are authored on the core that then
    // interpolates (lent to the authoring), so its set-up is paid once.
    runtime::NewtonCoreChoice core = runtime::make_newton_core(*setup, runtime::parse_backend(o->backend));
    KeyframeOptions ko;
    ko.make_core = [&](const ShapeSetup&) { return borrow_core(*core.core); };
    solve_scene_keyframes(scene, *setup, ko, false, [&](const SceneKeyframe& k) {
      if (k.solved)
        std::printf("keyframe %d solved from targets: %s\n", k.index, k.result.message.c_str());
      else
        std::printf("keyframe %d: certified locally injective\n", k.index);
      // Locally injective is not globally injective: say so when its outline crosses itself.
      if (k.overlap.overlaps())
        std::printf("WARNING: keyframe %d %s%s\n", k.index, describe(k.overlap).c_str(), start_from_rest_hint(k).c_str());
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
    if (o->projected_only) io.escalate_after_iterations = 0;  // the chosen projection throughout
    io.free_rotation = !o->gauged_rotation;
    io.chord_steps = !o->no_chord;
    io.chord_decrement_stop = o->chord_decrement_stop;
    if (o->no_carry) io.carry_all_samples = AllSamplesCarry::Off;
    io.exact_samples = parse_exact_samples(o->exact_samples);
    io.predict_start = parse_predict_start(o->predict_start);
    io.timing = o->timing.empty() ? scene_timings(scene) : std::vector<KeyTiming>{*parse_key_timing(o->timing)};
    std::printf("Newton core: %s\n", runtime::describe(core.choice).c_str());
    Interpolator interp(*setup, times, maps, io, std::move(core.core), std::move(core.boundary));

    const std::filesystem::path out(o->out);
    std::filesystem::create_directories(out);
    const bool tty = isatty(fileno(stderr));
    const auto t0 = Clock::now();
    bool prev_overlaps = false;
    auto progress = [&](const FrameResult& f, int i, int n) {
      const double el = std::chrono::duration<double>(Clock::now() - t0).count();
      const double eta = el / (i + 1) * (n - i - 1);
      if (tty)
        std::fprintf(stderr, "\r[interpolate] frame %d/%d  t = %.4f  %d it  %.1f ms  %s%s  ETA %.0f s   ", i + 1, n, f.t,
                     f.iterations, f.ms, f.certified ? "certified" : "NOT CERTIFIED", f.converged ? "" : ", NOT CONVERGED", eta);
      else if ((i + 1) % std::max(1, n / 20) == 0 || i + 1 == n)
        std::fprintf(stderr, "[interpolate] frame %d/%d (%.0f%%), %.1f s elapsed, ETA %.0f s\n", i + 1, n, 100.0 * (i + 1) / n, el, eta);
      if (!f.certified) std::fprintf(stderr, "%s[interpolate] frame %d (t = %.6f) NOT CERTIFIED: %s\n", tty ? "\n" : "", i, f.t,
                                     f.certificate.reason.c_str());
      else if (!f.converged)
        std::fprintf(stderr, "%s[interpolate] frame %d (t = %.6f) NOT CONVERGED after %d iterations: %s\n", tty ? "\n" : "", i, f.t,
                     f.iterations, f.message.c_str());
      if (f.overlap.overlaps() && (i == 0 || !prev_overlaps))  // the first frame of each overlapping run
        std::fprintf(stderr, "%s[interpolate] frame %d (t = %.6f) %s\n", tty ? "\n" : "", i, f.t, describe(f.overlap).c_str());
      prev_overlaps = f.overlap.overlaps();
      if (tty && i + 1 == n) std::fprintf(stderr, "\n");
    };

    SceneSequence seq{setup, interp.sequence(sequence_times(times, o->frames, o->per_interval), progress), 0.0, io};
    const int key_frames = static_cast<int>(std::count_if(seq.frames.begin(), seq.frames.end(), [](const FrameResult& f) { return f.keyframe; }));
    if (key_frames < static_cast<int>(times.size()))
      std::printf("note: %d of %zu keyframe times are frames (--frames-per-interval K makes every keyframe time a frame)\n",
                  key_frames, times.size());
    seq.total_s = std::chrono::duration<double>(Clock::now() - t0).count();
    const std::vector<FrameResult>& frames = seq.frames;
    write_frames(out / "frames.hsif", seq.frame_file());
    write_file_atomic(out / "report.json", report_json(scene, seq, o->scene));

    // The table and the plots' series.
    std::vector<double> ts, energy, iters, kappa, kappa_b, s1, s1b, s2, s2b, flagged, unconverged;
    std::vector<double> kappa_c, kappa_cb, s1c, s1cb, s2c, s2cb;  // certified bounds (NaN: not certified)
    // Columns: the solve, the distortion sampled at the certificate's breakpoints and
    // the certified bounds (σ2's a lower bound), each with its excess over the keyframes'.
    std::string table;
    {
      char h[512];
      std::snprintf(h, sizeof h, "%5s %8s  %8s  %9s  %9s  %5s  %9s  %6s  %11s %11s  %13s  %12s  %12s  %12s  %11s  %12s  %8s\n", "frame", "t",
                    "keyframe", "certified", "converged", "iters", "energy", "ms", "sigma1_max", "sigma2_min", "conformal_max",
                    "bound_excess", "sigma1_max<=", "sigma2_min>=", "conformal<=", "bound_excess", "overlaps");
      const std::string cols = h;
      const size_t certified_at = cols.find("sigma1_max<=") - 2, sampled_at = cols.find("sigma1_max") - 1;
      std::string groups(sampled_at, ' ');
      auto group = [](const std::string& name, size_t width) {
        const size_t dashes = width > name.size() + 4 ? width - name.size() - 4 : 2;
        return "|" + std::string(dashes / 2, '-') + " " + name + " " + std::string(dashes - dashes / 2, '-') + "|";
      };
      groups += group("sampled at breakpoints", certified_at - sampled_at);
      groups += "  " + group("certified bounds", cols.find("overlaps") - 2 - certified_at - 4);
      table = groups + "\n" + cols;
    }
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
      kappa_c.push_back(f.distortion_certified.conformal_max);
      kappa_cb.push_back(f.certified_bound.conformal_max);
      s1c.push_back(f.distortion_certified.sigma1_max);
      s1cb.push_back(f.certified_bound.sigma1_max);
      s2c.push_back(f.distortion_certified.sigma2_min);
      s2cb.push_back(f.certified_bound.sigma2_min);
      if (!f.certified) flagged.push_back(f.t);
      if (!f.converged) unconverged.push_back(f.t);
      char line[320];
      std::snprintf(line, sizeof line, "%5zu %8.5f  %8s  %9s  %9s  %5d  %9.6f  %6.1f  %11.5f %11.5f  %13.5f  %12.3e", i, f.t,
                    f.keyframe ? "yes" : "", f.certified ? "yes" : "NO", f.converged ? "yes" : "NO", f.iterations, f.energy, f.ms,
                    f.distortion.sigma1_max, f.distortion.sigma2_min, f.distortion.conformal_max, f.bound_excess);
      table += line;
      if (f.certified)
        std::snprintf(line, sizeof line, "  %12.5f  %12.5f  %11.5f  %12.3e", f.distortion_certified.sigma1_max,
                      f.distortion_certified.sigma2_min, f.distortion_certified.conformal_max, f.certified_bound_excess);
      else
        std::snprintf(line, sizeof line, "  %12s  %12s  %11s  %12s", "-", "-", "-", "-");
      table += line;
      table += f.overlap.overlaps() ? "       YES\n" : "\n";
    }
    const SequenceSummary sum = summarize(frames, seq.total_s);
    // Why the unconverged frames stopped (each frame's message and stop are in report.json
    // and the message on the progress line), counted for the summary.
    std::string why_unconverged;
    if (sum.not_converged > 0) {
      auto count = [&](NewtonStop stop) { return sum.stops[static_cast<size_t>(stop)]; };
      const int other = count(NewtonStop::NoDecrease) + count(NewtonStop::NotFactored) + count(NewtonStop::StartFolds) +
                        count(NewtonStop::StartNotCertified);
      auto add = [&](int n, const std::string& what) {
        if (n == 0) return;
        why_unconverged += (why_unconverged.empty() ? " (" : ", ") + std::to_string(n) + " " + what;
      };
      add(count(NewtonStop::IterationLimit), "at the iteration limit " + std::to_string(o->max_iterations));
      add(count(NewtonStop::Stagnated), "stagnated");
      add(count(NewtonStop::CertificateRefused), "where the certificate refused every further step: the map nears a fold between samples");
      add(other, "with no certified decrease, no factorable system or an uncertified start");
      why_unconverged += ")";
    }
    char head[1536];
    // Certified means locally injective; a frame can still overlap itself (overlap.h).
    char overlap_line[320] = "";
    if (sum.overlapping > 0)
      std::snprintf(overlap_line, sizeof overlap_line,
                    "WARNING: %d frame(s) overlap themselves (the image of the boundary crosses itself: locally but not "
                    "globally injective; sampled at the boundary breakpoints)\n",
                    sum.overlapping);
    std::snprintf(head, sizeof head,
                  "hsi interpolate %s: %zu frames, %d certified locally injective, %d NOT certified, %d NOT CONVERGED%s, %d overlapping themselves\n%s"
                  "mean %.2f Newton iterations and %.1f ms per solved frame (max %.1f ms), %.1f s in all\n"
                  "%d frames within the keyframes' sampled distortion (sampled at the certificate's breakpoints), largest excess %.3g (relative)\n"
                  "%d frames within the keyframes' certified bounds (certified bound against certified bounds), largest excess %.3g (relative)\n\n",
                  o->scene.c_str(), frames.size(), sum.certified, sum.uncertified, sum.not_converged, why_unconverged.c_str(),
                  sum.overlapping, overlap_line, sum.mean_iterations, sum.mean_ms, sum.max_ms, sum.total_s, sum.within_bounds,
                  sum.max_bound_excess, sum.within_certified_bounds, sum.max_certified_bound_excess);
    write_file_atomic(out / "report.txt", std::string(head) + table);

    auto plot = [&](const std::string& file, const std::string& title, std::vector<Series> series, const std::string& note = "",
                    int height = 420) {
      PlotSpec spec;
      spec.title = title;
      spec.xlabel = "t";
      spec.x = ts;
      spec.series = std::move(series);
      spec.flagged = flagged;
      spec.unconverged = unconverged;
      spec.note = note;
      spec.height_px = height;
      plot_series(out / file, spec);
    };
    plot("energy.png", scene.name + ": energy per frame (2 = metric reproduced exactly)", {{"energy", energy, 0.1, 0.3, 0.7}});
    plot("iterations.png", scene.name + ": Newton iterations per frame", {{"iterations", iters, 0.2, 0.5, 0.2}});
    // Sampled values (solid, thin dashed: the keyframes' sampled envelope) and the
    // certificate's bounds (thick, light; dotted: the keyframes' certified envelope).
    auto light = [](double c) { return 0.45 + 0.55 * c; };
    std::vector<Series> ds{{"conformal max (sampled)", kappa, 0.8, 0.2, 0.1},
                           {"keyframes (sampled)", kappa_b, 0.8, 0.2, 0.1, true},
                           {"conformal max (certified bound)", kappa_c, light(0.8), light(0.2), light(0.1), false, false, 3.2},
                           {"keyframes (certified)", kappa_cb, light(0.8), light(0.2), light(0.1), true, false, 3.2},
                           {"sigma1 max (sampled)", s1, 0.1, 0.3, 0.7},
                           {"keyframes (sampled)", s1b, 0.1, 0.3, 0.7, true},
                           {"sigma1 max (certified bound)", s1c, light(0.1), light(0.3), light(0.7), false, false, 3.2},
                           {"keyframes (certified)", s1cb, light(0.1), light(0.3), light(0.7), true, false, 3.2},
                           {"sigma2 min (sampled)", s2, 0.2, 0.55, 0.2},
                           {"keyframes (sampled)", s2b, 0.2, 0.55, 0.2, true},
                           {"sigma2 min (certified lower bound)", s2c, light(0.2), light(0.55), light(0.2), false, false, 3.2},
                           {"keyframes (certified)", s2cb, light(0.2), light(0.55), light(0.2), true, false, 3.2}};
    // Draw the wide certified-bound lines first, under the sampled ones.
    std::stable_partition(ds.begin(), ds.end(), [](const Series& s) { return s.width > 3; });
    plot("distortion.png", scene.name + ": distortion on the boundary vs the keyframes'", std::move(ds),
         "sampled: at the certificate's breakpoints; certified: the certificate's bounds over the boundary (so over the shape); "
         "no certified bound for an uncertified frame",
         500);
    if (o->png_count > 0) {
      std::filesystem::create_directories(out / "frames");
      // The drawings show the sprite through each frame's map, as `hsi keyframes --png` does.
      std::optional<SceneTexture> tex;
      if (!scene.texture.empty()) tex = scene_texture(scene, o->scene);
      const int count = std::min<int>(o->png_count, static_cast<int>(frames.size()));
      for (int k = 0; k < count; ++k) {
        const size_t i = count == 1 ? 0 : static_cast<size_t>(k) * (frames.size() - 1) / static_cast<size_t>(count - 1);
        const FrameResult& f = frames[i];
        MapPlot extras;
        char title[160];
        std::snprintf(title, sizeof title, "%s  frame %zu  t = %.3f  %d it  conformal %.3f (sampled)", scene.name.c_str(), i, f.t,
                      f.iterations, f.distortion.conformal_max);
        extras.title = title;
        extras.uncertified = !f.certified;
        extras.overlaps = f.overlap.overlaps();
        extras.not_converged = !f.converged;
        extras.texture = tex ? &*tex : nullptr;
        char name[64];
        std::snprintf(name, sizeof name, "frame_%04zu.png", i);
        plot_map(out / "frames" / name, scene.shape, setup->cage, f.map, extras, 640);
      }
    }
    std::printf("%s", head);
    std::printf("wrote %s{frames.hsif, report.json, report.txt, energy.png, iterations.png, distortion.png%s}\n",
                (out.lexically_normal() / "").string().c_str(), o->png_count > 0 ? ", frames/" : "");
    exit_for_flagged_frames(sum.uncertified, sum.not_converged, o->allow_unconverged, "see " + (out / "report.txt").string());
  });
}

}  // namespace hsi::cli
