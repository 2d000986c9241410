// hsi bake SCENE -o seq.hsib: interpolates a scene (or takes the frames of an earlier
// hsi interpolate) and bakes it for playback by the dependency-free runtime
// (engine/include/hsi/baked_runtime.h documents the format).
#include <unistd.h>

#include <cstdio>

#include "hsi/sample_limits.h"
#include "commands.h"
#include "hsi/baked.h"
#include "hsi/baked_runtime.h"
#include "hsi/scene_sequence.h"
#include "sequence_source.h"

namespace hsi::cli {

// Frames from FROM (a .hsif file or a folder holding frames.hsif), checked against the scene's cage.
FrameFile frames_from(const std::string& from, Scene& scene) {
  std::filesystem::path p(from);
  if (std::filesystem::is_directory(p)) p /= "frames.hsif";
  FrameFile ff = read_frames(p);
  const Cage cage = scene_cage(scene);
  if (ff.cage.loops != cage.loops || ff.cage.hole_points != cage.hole_points)
    throw InputError(p.string() + ": its cage is not the scene's (were these frames computed for another scene?)");
  return ff;
}

// Interpolates with a progress line on stderr; returns the sequence.
SceneSequence interpolate_with_progress(Scene& scene, const SceneSequenceOptions& o, const char* tag) {
  const bool tty = isatty(fileno(stderr));
  SceneSequence seq = interpolate_scene(scene, o, [&](const FrameResult& f, int i, int n) {
    if (tty)
      std::fprintf(stderr, "\r[%s] frame %d/%d  t = %.4f  %s%s   ", tag, i + 1, n, f.t, f.certified ? "certified" : "NOT CERTIFIED",
                   f.converged ? "" : ", NOT CONVERGED");
    else if ((i + 1) % std::max(1, n / 10) == 0 || i + 1 == n)
      std::fprintf(stderr, "[%s] frame %d/%d\n", tag, i + 1, n);
    if (!f.certified)
      std::fprintf(stderr, "%s[%s] frame %d (t = %.6f) NOT CERTIFIED: %s\n", tty ? "\n" : "", tag, i, f.t, f.certificate.reason.c_str());
    else if (!f.converged)
      std::fprintf(stderr, "%s[%s] frame %d (t = %.6f) NOT CONVERGED after %d iterations: %s\n", tty ? "\n" : "", tag, i, f.t,
                   f.iterations, f.message.c_str());
  });
  if (tty) std::fprintf(stderr, "\n");
  return seq;
}

void register_bake(CLI::App& app) {
  struct Opts {
    std::string scene, out = "sequence.hsib", from;
    int frames = 120, samples = 0, per_interval = 0;
    double ratio = 0;
    bool f64 = false, allow_unconverged = false;
    int max_iterations = 100;
    int blend_substeps = 4, mesh_vertices = 2000;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "bake",
      "Bake a scene's interpolation for playback in a game: a compact .hsib file (the cage once, then per frame the\n"
      "reduced coefficients and pose, a few KB) that the dependency-free runtime hsi/baked_runtime.h plays back on\n"
      "any mesh's vertices with one small matrix product per frame. Each frame's flags (certified, keyframe,\n"
      "converged) are stored in the file.\n" +
          std::string(kFlaggedFramesHelp));
  cmd->add_option("scene", o->scene, "Scene file (.json) with two or more keyframes")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->out, "Baked file to write")->capture_default_str();
  add_frame_options(cmd, o->frames, o->per_interval);
  cmd->add_option("--samples", o->samples, "Boundary samples |G| (default: the scene's)")->check(CLI::Range(kMinSamples, kMaxSamples));
  cmd->add_option("--ratio", o->ratio, "Hessian sample ratio r (default: the scene's)")->check(CLI::Range(1e-6, 1.0));
  cmd->add_option("--from", o->from, "Bake the frames of an earlier hsi interpolate (its folder or frames.hsif) instead");
  cmd->add_option("--max-iterations", o->max_iterations, "Newton iterations per frame at most")->capture_default_str()->check(CLI::Range(1, 1000000));
  cmd->add_flag("--allow-unconverged", o->allow_unconverged, "Exit 0 when certified frames did not converge (still flagged in the file)");
  cmd->add_option("--blend-substeps", o->blend_substeps,
                  "k: certify the blends of every two neighbouring certified frames at k-1 sub-steps, so the runtime may blend\n"
                  "there (0: nearest-frame playback only)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--mesh-vertices", o->mesh_vertices, "The shape's triangulation stored in the file, about this many vertices")
      ->capture_default_str()
      ->check(CLI::Range(16, 10000000));
  cmd->add_flag("--f64", o->f64, "Store per-frame coefficients as f64 (default f32, about 1e-7 of the shape's size)");
  cmd->callback([o] {
    Scene scene = load_scene(o->scene);
    FrameFile ff;
    if (!o->from.empty()) {
      ff = frames_from(o->from, scene);
    } else {
      SceneSequenceOptions so;
      so.frames = o->frames;
      so.frames_per_interval = o->per_interval;
      so.samples = o->samples;
      so.hessian_ratio = o->ratio;
      so.interpolation.max_iterations = o->max_iterations;
      ff = interpolate_with_progress(scene, so, "bake").frame_file();
    }
    BakeOptions bo;
    bo.single_precision = !o->f64;
    bo.blend_substeps = o->blend_substeps;
    bo.mesh_vertices = o->mesh_vertices;
    bo.certificate_samples = o->samples > 0 ? o->samples : scene.samples;
    bo.texture_rect = scene.texture_rect_or_bounds();
    const std::string bytes = encode_baked(scene.shape, ff, bo);
    write_file_atomic(o->out, bytes);
    int uncertified = 0, not_converged = 0, overlapping = 0;
    for (const StoredFrame& f : ff.frames) {
      uncertified += !f.certified;
      not_converged += !f.converged;
      overlapping += f.overlaps;
    }
    std::printf("wrote %s: %zu frames, %zu bytes (%.1f KB per frame), %d uncertified, %d not converged\n", o->out.c_str(),
                ff.frames.size(), bytes.size(),
                static_cast<double>(bytes.size()) / 1024.0 / static_cast<double>(std::max<size_t>(1, ff.frames.size())), uncertified,
                not_converged);
    // What the runtime will blend, read back from the file as a game reads it.
    if (o->blend_substeps >= 2 && ff.frames.size() >= 2) {
      int blendable = 0;
      hsib_sequence* seq = nullptr;
      if (hsib_open_memory(bytes.data(), bytes.size(), &seq, nullptr, 0) == HSIB_OK) {
        for (uint32_t i = 0; i + 1 < ff.frames.size(); ++i) {
          uint32_t flags = 0;
          hsib_frame_info(seq, i, nullptr, &flags);
          blendable += (flags & HSIB_FRAME_BLEND_CERTIFIED) != 0;
        }
        hsib_close(seq);
      }
      std::printf("blends certified at %d sub-steps in %d of %zu intervals (the runtime plays the nearest frame in the others)\n",
                  o->blend_substeps, blendable, ff.frames.size() - 1);
    }
    if (overlapping > 0)
      std::printf("WARNING: %d frame(s) overlap themselves (the image of the boundary crosses itself); flagged "
                  "HSIB_FRAME_OVERLAPS in the baked file\n",
                  overlapping);
    exit_for_flagged_frames(uncertified, not_converged, o->allow_unconverged, "they are flagged in the baked file");
  });
}

}  // namespace hsi::cli
