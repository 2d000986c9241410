// hsi export SCENE --gltf out.glb --png OUT/ --json report.json --csv report.csv:
// a scene's interpolation (run now, or an earlier one with --from) as an animated
// glTF 2.0 binary (textured triangulation, morph targets), a PNG sequence with a
// contact sheet (the Vulkan renderer, through hsi render), and the report.
#include <algorithm>
#include <cstdio>

#include "hsi/sample_limits.h"
#include "commands.h"
#include "hsi/gltf_export.h"
#include "sequence_source.h"

namespace hsi::cli {

void register_export(CLI::App& app) {
  struct Opts {
    std::string scene, from, gltf, png, json, csv;
    int frames = 120, samples = 0, per_interval = 0;
    double ratio = 0;
    int gltf_frames = 61, gltf_vertices = 2000;
    double seconds = 1;
    bool step = false, allow_unconverged = false;
    int max_iterations = 100;
    std::string size = "512";
    int every = 1;
    std::string predict_start = to_string(InterpolationOptions{}.predict_start);
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "export",
      "Export a scene's interpolation: --gltf an animated glTF 2.0 binary (.glb: the shape's triangulation with its\n"
      "texture, one morph target per sampled frame, a weights animation), --png a PNG sequence and contact sheet\n"
      "(Vulkan renderer), --json / --csv the per-frame report. Frames that are not certified are never exported as good;\n"
      "the glTF animation's extras list each sampled frame's flags (certified, keyframe, converged) and why its Newton\n"
      "solve stopped (stop).\n" +
          std::string(kFlaggedFramesHelp));
  cmd->add_option("scene", o->scene, "Scene file (.json) with two or more keyframes")->required()->check(CLI::ExistingFile);
  cmd->add_option("--gltf", o->gltf, "Write an animated glTF binary (.glb)");
  cmd->add_option("--png", o->png, "Write OUT/frame_NNNN.png, OUT/contact_sheet.png (and OUT/frames.hsif)");
  cmd->add_option("--json", o->json, "Write the report as JSON");
  cmd->add_option("--csv", o->csv, "Write the report as CSV (one line per frame)");
  cmd->add_option("--from", o->from, "Use the frames of an earlier hsi interpolate (its folder or frames.hsif); glTF and PNG only");
  add_frame_options(cmd, o->frames, o->per_interval);
  cmd->add_option("--samples", o->samples, "Boundary samples |G| (default: the scene's)")->check(CLI::Range(kMinSamples, kMaxSamples));
  cmd->add_option("--ratio", o->ratio, "Hessian sample ratio r (default: the scene's)")->check(CLI::Range(1e-6, 1.0));
  cmd->add_option("--max-iterations", o->max_iterations, "Newton iterations per frame at most")->capture_default_str()->check(CLI::Range(1, 1000000));
  add_predict_start_option(cmd, o->predict_start);
  cmd->add_flag("--allow-unconverged", o->allow_unconverged, "Exit 0 when certified frames did not converge (still flagged in the outputs)");
  cmd->add_option("--gltf-frames", o->gltf_frames, "Frames sampled into the glTF animation (morph targets + 1)")
      ->capture_default_str()->check(CLI::Range(2, 4096));
  cmd->add_option("--gltf-vertices", o->gltf_vertices, "Vertices of the glTF mesh (about)")->capture_default_str()->check(CLI::Range(16, 2000000));
  cmd->add_option("--seconds-per-unit", o->seconds, "Animation seconds per unit of scene time")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_flag("--step", o->step, "STEP keys instead of LINEAR (no blending between sampled frames)");
  cmd->add_option("--size", o->size, "PNG size: S or WxH (as hsi render)")->capture_default_str();
  cmd->add_option("--every", o->every, "Render every K-th frame to PNG")->capture_default_str()->check(CLI::Range(1, 1000000));
  cmd->callback([o] {
    if (o->gltf.empty() && o->png.empty() && o->json.empty() && o->csv.empty())
      throw InputError("hsi export: nothing to export; give --gltf, --png, --json and/or --csv");
    if (!o->from.empty() && (!o->json.empty() || !o->csv.empty()))
      throw InputError("hsi export: --json and --csv need the interpolation's report; run without --from (or use that run's report.json)");
    Scene scene = load_scene(o->scene);
    FrameFile ff;
    int uncertified = 0;
    if (!o->from.empty()) {
      ff = frames_from(o->from, scene);
    } else {
      SceneSequenceOptions so;
      so.frames = o->frames;
      so.frames_per_interval = o->per_interval;
      so.samples = o->samples;
      so.hessian_ratio = o->ratio;
      so.interpolation.max_iterations = o->max_iterations;
      so.interpolation.predict_start = parse_predict_start(o->predict_start);
      const SceneSequence seq = interpolate_with_progress(scene, so, "export");
      ff = seq.frame_file();
      if (!o->json.empty()) {
        write_file_atomic(o->json, report_json(scene, seq, o->scene));
        std::printf("wrote %s\n", o->json.c_str());
      }
      if (!o->csv.empty()) {
        write_file_atomic(o->csv, report_csv(seq));
        std::printf("wrote %s\n", o->csv.c_str());
      }
    }
    int not_converged = 0;
    for (const StoredFrame& f : ff.frames) {
      uncertified += !f.certified;
      not_converged += !f.converged;
    }
    const std::string why = stop_counts(ff.frames);  // why the frames that did not converge stopped
    std::printf("%zu frames: %d uncertified, %d not converged%s\n", ff.frames.size(), uncertified, not_converged,
                why.empty() ? "" : (" (" + why + ")").c_str());
    if (!o->gltf.empty()) {
      GltfOptions go;
      go.mesh_vertices = o->gltf_vertices;
      go.max_frames = o->gltf_frames;
      go.seconds_per_time_unit = o->seconds;
      go.step = o->step;
      GltfStats st;
      write_glb(o->gltf, scene, ff, go, &st);
      std::printf("wrote %s: %d vertices, %d triangles, %d morph targets, %s, %zu bytes\n", o->gltf.c_str(), st.vertices, st.triangles,
                  st.targets,
                  st.textured ? (std::string("textured, ") + texture_filter_name(scene.texture_filter) + " texture filtering").c_str()
                              : "untextured",
                  st.bytes);
    }
    if (!o->png.empty()) {
      // The frames go next to the images, then hsi render draws them (same code path).
      std::filesystem::create_directories(o->png);
      write_frames(std::filesystem::path(o->png) / "frames.hsif", ff);
      CLI::App render{"render"};
      register_render(render);
      std::vector<std::string> args{"render", o->scene, o->png, "-o", o->png, "--size", o->size, "--every", std::to_string(o->every)};
      std::reverse(args.begin(), args.end());  // CLI11 takes the arguments last first
      render.parse(args);
    }
    exit_for_flagged_frames(uncertified, not_converged, o->allow_unconverged,
                            "see the report" + std::string(uncertified > 0 ? "; glTF export refuses them" : ""));
  });
}

}  // namespace hsi::cli
