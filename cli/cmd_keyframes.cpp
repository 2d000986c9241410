// hsi keyframes SCENE: solves the keyframes posed by handle targets (CW17), certifies
// those given as coefficients, and writes the coefficients back into the scene.
#include <cstdio>

#include "commands.h"
#include "hsi/keyframes.h"
#include "hsi/scene_sequence.h"
#include "hsi/draw/plot.h"

namespace hsi::cli {

using draw::MapPlot;
using draw::plot_map;

void register_keyframes(CLI::App& app) {
  struct Opts {
    std::string scene, out, png_dir;
    bool force = false, verbose = false;
    double lambda = 1e5;
    int stages = 8;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "keyframes",
      "Solve a scene's keyframes from handle targets (certified, locally injective) and write their coefficients back");
  cmd->add_option("scene", o->scene, "Scene file (.json)")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->out, "Write the solved scene here (default: overwrite SCENE)");
  cmd->add_option("--png", o->png_dir, "Draw each keyframe to DIR/keyframe_K.png");
  cmd->add_flag("--force", o->force, "Re-solve keyframes that already have coefficients (if they have targets)");
  cmd->add_flag("-v,--verbose", o->verbose, "Print every Newton iteration (energy, gradient norm, step, backtracks, time)");
  cmd->add_option("--lambda", o->lambda, "Positional weight (relative to size^2)")->capture_default_str();
  cmd->add_option("--stages", o->stages, "Drag the handles to their targets in this many steps")->capture_default_str();
  cmd->callback([o] {
    Scene scene = load_scene(o->scene);
    if (scene.keyframes.empty()) throw InputError(o->scene + ": the scene has no keyframes");
    // Coefficients are stored over a cage: keep the one they were solved with.
    const auto setup = scene_setup(scene);
    KeyframeOptions ko;
    ko.lambda = o->lambda;
    ko.stages = o->stages;
    if (!o->png_dir.empty()) std::filesystem::create_directories(o->png_dir);
    bool all_ok = true;
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
        std::printf("WARNING: %s %s\n", label.c_str(), describe(k.overlap).c_str());
      }
      if (!o->png_dir.empty()) {
        MapPlot extras;
        extras.overlaps = k.overlap.overlaps();
        extras.handles_image = map_points(setup->cage, *key.coefficients, scene.handles);
        extras.targets = key.targets;
        extras.title = scene.name + " " + label;
        plot_map(std::filesystem::path(o->png_dir) / ("keyframe_" + std::to_string(k.index) + ".png"), scene.shape,
                 setup->cage, *key.coefficients, extras);
      }
    });
    const std::filesystem::path out = o->out.empty() ? std::filesystem::path(o->scene) : std::filesystem::path(o->out);
    if (out.parent_path() != std::filesystem::path(o->scene).parent_path() && !scene.texture.empty() &&
        scene.texture.is_relative())
      scene.texture = std::filesystem::relative(scene.texture_path(), out.parent_path().empty() ? "." : out.parent_path());
    save_scene(scene, out);
    std::printf("wrote %s%s\n", out.string().c_str(), all_ok ? "" : " (some targets were not reached: see above)");
    if (overlapping > 0)
      std::printf("WARNING: %d keyframe(s) overlap themselves (certified locally injective, but the image of the boundary "
                  "crosses itself)\n",
                  overlapping);
  });
}

}  // namespace hsi::cli
