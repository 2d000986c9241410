// hsi keyframes SCENE: solves the keyframes posed by handle targets (CW17), certifies
// those given as coefficients, and writes the scene with their coefficients to -o (or,
// with --in-place, back over SCENE: an input is never overwritten unless asked).
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iterator>
#include <optional>
#include <sstream>

#include "commands.h"
#include "hsi/keyframes.h"
#include "hsi/png_import.h"
#include "hsi/scene_sequence.h"
#include "hsi/scene_texture.h"
#include "hsi/draw/plot.h"
#include "hsi/runtime/backend.h"

namespace hsi::cli {

namespace {

// "X,Y" (spaces allowed around the numbers).
cd parse_point(const std::string& text, const std::string& what) {
  std::istringstream in(text);
  double x = 0, y = 0;
  char comma = 0, extra = 0;
  if (!(in >> x >> comma >> y) || comma != ',' || (in >> extra) || !std::isfinite(x) || !std::isfinite(y))
    throw InputError(what + " '" + text.substr(0, 60) + "': expected a point X,Y (two finite numbers)");
  return {x, y};
}

// "T" or "T: X,Y X,Y ..." (targets separated by spaces or ';').
std::pair<double, std::vector<cd>> parse_keyframe(const std::string& text) {
  const size_t colon = text.find(':');
  std::istringstream tin(text.substr(0, colon));
  double t = 0;
  char extra = 0;
  if (!(tin >> t) || (tin >> extra) || !std::isfinite(t))
    throw InputError("--keyframe '" + text.substr(0, 60) + "': expected 'T' or 'T: X,Y X,Y ...' with a finite time T");
  std::vector<cd> targets;
  if (colon != std::string::npos) {
    std::string rest = text.substr(colon + 1);
    for (char& ch : rest)
      if (ch == ';') ch = ' ';
    std::istringstream in(rest);
    for (std::string p; in >> p;) targets.push_back(parse_point(p, "--keyframe target"));
    if (targets.empty()) throw InputError("--keyframe '" + text.substr(0, 60) + "': no targets after ':' (give 'T' alone for the rest pose)");
  }
  return {t, targets};
}

// Points as given (scene units), or with --pixels the texture's pixel (x right, y down
// from the top-left corner) mapped through texture_rect onto the scene (y up).
std::function<cd(cd)> pixel_mapping(const Scene& scene, bool pixels) {
  if (!pixels) return [](cd p) { return p; };
  if (scene.texture.empty()) throw InputError("--pixels needs the scene's texture (the scene has none)");
  std::ifstream in(scene.texture_path(), std::ios::binary);
  if (!in) throw InputError(scene.texture_path().string() + ": cannot open the texture for --pixels");
  const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto [w, h] = check_png_texture(bytes, scene.texture_path().string());
  const std::array<double, 4> r = scene.texture_rect_or_bounds();
  return [=](cd p) { return cd(r[0] + p.real() / w * (r[2] - r[0]), r[3] - p.imag() / h * (r[3] - r[1])); };
}

}  // namespace

using draw::MapPlot;
using draw::plot_map;

void register_keyframes(CLI::App& app) {
  struct Opts {
    std::string scene, out, png_dir;
    std::vector<std::string> handles, keyframes;
    bool force = false, verbose = false, in_place = false, allow_unreached = false, pixels = false;
    double lambda = 1e5;
    int stages = 8;
    int max_iterations = KeyframeOptions{}.newton.max_iterations;
    std::string backend = "auto";
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "keyframes",
      "Solve a scene's keyframes from handle targets (certified, locally injective) and write their coefficients back");
  cmd->add_option("scene", o->scene, "Scene file (.json)")->required()->check(CLI::ExistingFile);
  auto* output = cmd->add_option("-o,--output", o->out,
                                 "Write the solved scene here (without -o or --in-place nothing is written: a dry run)");
  cmd->add_flag("--in-place", o->in_place, "Write the solved scene back over SCENE")->excludes(output);
  cmd->add_flag("--allow-unreached", o->allow_unreached,
                "Exit 0 when some handle target could not be reached without folding (the closest certified map is written)");
  cmd->footer(
      "Exit status: 0 every keyframe certified and its targets reached; 1 error; 2 bad input (also a keyframe that cannot\n"
      "be made certified); 5 some keyframe's targets could not be reached without folding: the scene is written with the\n"
      "closest certified map (--allow-unreached: 0).");
  cmd->add_option("--handle", o->handles,
                  "Add a handle at rest point X,Y (scene units; repeatable); keyframes with coefficients keep their pose")
      ->take_all();
  cmd->add_option("--keyframe", o->keyframes,
                  "Add a keyframe 'T: X,Y X,Y ...' (one target per handle, in order) or 'T' (the rest pose); repeatable")
      ->take_all();
  cmd->add_flag("--pixels", o->pixels,
                "--handle and --keyframe points are pixels of the scene's texture (x right, y down from the image's "
                "top-left corner, as in an image editor), mapped through texture_rect");
  cmd->add_option("--png", o->png_dir, "Draw each keyframe to DIR/keyframe_K.png");
  cmd->add_flag("--force", o->force, "Re-solve keyframes that already have coefficients (if they have targets)");
  cmd->add_flag("-v,--verbose", o->verbose, "Print every Newton iteration (energy, gradient norm, step, backtracks, time)");
  cmd->add_option("--lambda", o->lambda, "Positional weight (relative to size^2)")->capture_default_str();
  cmd->add_option("--stages", o->stages, "Drag the handles to their targets in this many steps")->capture_default_str();
  cmd->add_option("--max-iterations", o->max_iterations, "Newton iterations of the last step at most")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--backend", o->backend, std::string(runtime::kBackendHelp) + " (the drag's Newton solves)")
      ->capture_default_str()
      ->check(CLI::IsMember(runtime::backend_names()));
  cmd->callback([o] {
    std::error_code ec;
    if (!o->out.empty() && std::filesystem::equivalent(o->scene, o->out, ec))
      throw InputError("-o " + o->out + " is the input scene; to overwrite it, use --in-place instead of -o");
    Scene scene = load_scene(o->scene);
    try {
      const auto to_scene = pixel_mapping(scene, o->pixels);
      for (const std::string& h : o->handles) {
        try {
          add_handle(scene, to_scene(parse_point(h, "--handle")));
        } catch (const InputError& e) {  // its place is checked before solving; name the pixel the user typed
          if (!o->pixels) throw;
          throw InputError("--handle " + h.substr(0, 60) + " (pixels of the texture): " + e.what());
        }
      }
      for (const std::string& k : o->keyframes) {
        auto [time, targets] = parse_keyframe(k);
        for (cd& q : targets) q = to_scene(q);
        const int index = add_keyframe(scene, time, targets);
        std::printf("added keyframe %d at t = %g (%s)\n", index, time, targets.empty() ? "the rest pose" : "targets given");
      }
    } catch (const InputError& e) {
      rethrow_in_scene(scene, e);
    }
    if (scene.keyframes.empty()) throw InputError(o->scene + ": the scene has no keyframes; " + kHowToAddKeyframes);
    // Coefficients are stored over a cage: keep the one they were solved with.
    const auto setup = scene_setup(scene);
    KeyframeOptions ko;
    ko.lambda = o->lambda;
    ko.stages = o->stages;
    ko.newton.max_iterations = o->max_iterations;
    const runtime::Backend backend = runtime::parse_backend(o->backend);
    ko.make_core = [&](const ShapeSetup& s) {  // once, for the scene's keyframes
      runtime::NewtonCoreChoice c = runtime::make_newton_core(s, backend);
      std::printf("Newton core: %s\n", runtime::describe(c.choice).c_str());
      return std::move(c.core);
    };
    std::optional<SceneTexture> tex;  // the keyframe pictures draw the sprite through each map
    if (!o->png_dir.empty()) {
      std::filesystem::create_directories(o->png_dir);
      if (!scene.texture.empty()) tex = scene_texture(scene, o->scene);
    }
    bool all_ok = true;
    int unreached = 0;  // keyframes whose targets could not be reached without folding
    int overlapping = 0;  // keyframes that are locally but not globally injective
    solve_scene_keyframes(scene, *setup, ko, o->force, [&](const SceneKeyframe& k) {
      const Keyframe& key = scene.keyframes[static_cast<size_t>(k.index)];
      const std::string label = "keyframe " + std::to_string(k.index) + " (t = " + std::to_string(key.time) + ")";
      if (!k.solved) {
        std::printf("%-28s given as coefficients: certified locally injective\n", label.c_str());
      } else {
        std::printf("%-28s %3d Newton iterations, %8.1f ms, energy %.4f, %s\n", label.c_str(), k.result.iterations,
                    k.result.ms, k.result.energy, k.result.message.c_str());
        all_ok = all_ok && k.result.reached;
        unreached += !k.result.reached;
        if (o->verbose)
          for (size_t i = 0; i < k.result.log.size(); ++i) {
            const NewtonIteration& it = k.result.log[i];
            std::printf("    it %3zu  energy %.8f  |grad| %.3e  step %.3g (safe %.3g)  backtracks %d (%d by the certificate)  %.1f ms\n",
                        i + 1, it.energy, it.gradient_norm, it.step, it.max_safe_step, it.backtracks,
                        it.certificate_rejections, it.ms);
          }
      }
      if (k.overlap.overlaps()) {
        ++overlapping;
        std::printf("WARNING: %s %s%s\n", label.c_str(), describe(k.overlap).c_str(), start_from_rest_hint(k).c_str());
      }
      if (!o->png_dir.empty()) {
        MapPlot extras;
        extras.overlaps = k.overlap.overlaps();
        extras.handles_image = map_points(setup->cage, *key.coefficients, scene.handles);
        extras.targets = key.targets;
        extras.title = scene.name + " " + label;
        extras.texture = tex ? &*tex : nullptr;
        plot_map(std::filesystem::path(o->png_dir) / ("keyframe_" + std::to_string(k.index) + ".png"), scene.shape,
                 setup->cage, *key.coefficients, extras);
      }
    });
    if (o->out.empty() && !o->in_place) {
      std::printf("scene not written (a dry run): give -o FILE to write the solved scene, or --in-place to update %s\n",
                  o->scene.c_str());
    } else {
      const std::filesystem::path out = o->in_place ? std::filesystem::path(o->scene) : std::filesystem::path(o->out);
      if (out.parent_path() != std::filesystem::path(o->scene).parent_path() && !scene.texture.empty() &&
          scene.texture.is_relative())
        scene.texture = std::filesystem::relative(scene.texture_path(), out.parent_path().empty() ? "." : out.parent_path());
      save_scene(scene, out);
      std::printf("wrote %s%s\n", out.string().c_str(), all_ok ? "" : " (some targets were not reached: see above)");
    }
    if (overlapping > 0)
      std::printf("WARNING: %d keyframe(s) overlap themselves (certified locally injective, but the image of the boundary "
                  "crosses itself)\n",
                  overlapping);
    if (unreached > 0 && !o->allow_unreached)
      throw FlaggedFrames(kExitUnreached, std::to_string(unreached) +
                                              " keyframe(s) did not reach their handle targets without folding (see above); the "
                                              "closest certified maps were kept (exit status 5; --allow-unreached accepts them)");
  });
}

}  // namespace hsi::cli
