// Subcommands of the hsi tool. Each registers itself on the app and runs from
// its callback; errors surface as exceptions that main() turns into a message.
#pragma once

#include <CLI/CLI.hpp>
#include <stdexcept>
#include <string>

#include "hsi/interpolation.h"
#include "hsi/keyframes.h"

namespace hsi::cli {

// Exit status of hsi (README "Exit status"). hsi interpolate / bake / export write
// everything they can, flag the frames, and then exit with:
//   0  every frame certified and converged
//   1  an error (nothing or only part written)
//   2  bad input (scene, file, option value)
//   3  some frame could not be certified (locally injective not proved): never good
//   4  every frame certified, but some Newton solve stopped without converging (its
//      iteration limit, stagnation, or no certified decrease left): the frame is
//      injective but not the interpolation's minimiser. --allow-unconverged makes this 0.
// hsi keyframes writes the scene (the closest certified maps) and then exits with:
//   5  some keyframe's handle targets could not be reached without folding;
//      --allow-unreached makes this 0.
// CLI11's own parse errors keep CLI11's codes (105 a bad option value, 106 a missing one, ...).
enum ExitStatus { kExitOk = 0, kExitError = 1, kExitBadInput = 2, kExitUncertified = 3, kExitNotConverged = 4, kExitUnreached = 5 };

// Thrown once a command has written its outputs when frames are flagged; main() prints
// the message (as an error for 3, a warning for 4) and exits with `status`.
struct FlaggedFrames : std::runtime_error {
  FlaggedFrames(int status_, const std::string& what) : std::runtime_error(what), status(status_) {}
  int status;
};
// Throws FlaggedFrames for `uncertified` > 0 (3), else for `not_converged` > 0 unless
// allowed (4); `what` names the command's output for the message.
inline void exit_for_flagged_frames(int uncertified, int not_converged, bool allow_unconverged, const std::string& what) {
  if (uncertified > 0)
    throw FlaggedFrames(kExitUncertified, std::to_string(uncertified) + " frame(s) could not be certified; " + what + " (exit status 3)");
  if (not_converged > 0 && !allow_unconverged)
    throw FlaggedFrames(kExitNotConverged, std::to_string(not_converged) +
                                              " frame(s) NOT CONVERGED: certified, but the Newton solve stopped before its tolerance "
                                              "(iteration limit, stagnation, or no certified decrease: each frame says which); " + what +
                                              " (exit status 4; --allow-unconverged accepts them; a higher --max-iterations or more "
                                              "--samples may help, as the reasons say)");
}
// The exit-status paragraph of --help for interpolate / bake / export.
inline constexpr const char* kFlaggedFramesHelp =
    "Exit status: 0 all frames certified and converged; 1 error; 2 bad input; 3 some frame not certified;\n"
    "4 some frame did not converge (certified, but Newton stopped before its tolerance; --allow-unconverged: 0).";

// --frames N and --frames-per-interval K (exclusive) for interpolate, bake and export;
// the frame times are then sequence_times(keys, frames, per_interval) (interpolation.h).
inline void add_frame_options(CLI::App* cmd, int& frames, int& per_interval) {
  auto* frames_opt = cmd->add_option("--frames", frames, "Number of frames over the keyframes' time range")
                         ->capture_default_str()
                         ->check(CLI::Range(2, 1000000));
  cmd->add_option("--frames-per-interval", per_interval,
                  "Instead of --frames: this many equal steps between neighbouring keyframes, so every keyframe time is a frame")
      ->check(CLI::Range(1, 1000000))
      ->excludes(frames_opt);
}

// --predict-start off|always|auto for interpolate, bake and export: where each frame's
// Newton solve starts (InterpolationOptions::predict_start); `name` holds the choice,
// parse it with parse_predict_start.
inline void add_predict_start_option(CLI::App* cmd, std::string& name) {
  cmd->add_option("--predict-start", name,
                  "Where each frame's solve starts: off (the previous frame's solution), always (the secant through the\n"
                  "interval's last two solved frames, extrapolated to the frame's time) or auto (the secant after a frame\n"
                  "of more than one iteration). auto took 7-9 % fewer Newton iterations per frame over the stress corpus at\n"
                  "100 frames per interval, but a predicted frame builds a system where a chord step builds none, so it is\n"
                  "no faster. A predicted solve that ends not certified or not converged is solved again from the previous frame")
      ->capture_default_str()
      ->check(CLI::IsMember(predict_start_names()));
}

// A hint after a keyframe authored from the previous keyframe's pose is found to overlap
// itself (a pose far from the previous one can end folded over itself although the same
// targets from rest give an undistorted map); empty where it does not apply.
inline std::string start_from_rest_hint(const SceneKeyframe& k) {
  if (!k.solved || k.from_rest || k.index == 0 || !k.overlap.overlaps()) return "";
  return "  (authored from keyframe " + std::to_string(k.index - 1) + "'s pose; if this pose is not meant to carry that one's " +
         "turns, \"start\": \"rest\" in keyframe " + std::to_string(k.index) + " authors it from the rest pose)";
}

// hsi render's description (cmd_render.cpp, or cmd_render_unavailable.cpp in a build without Vulkan).
inline constexpr const char* kRenderHelp =
    "Render the frames of 'hsi interpolate' offscreen (Vulkan; lavapipe on a machine without a GPU):\n"
    "the deformed shape with its texture, clipped at its outline and holes, anti-aliased, with optional\n"
    "overlays. Writes OUT/frame_NNNN.png per frame and OUT/contact_sheet.png. Frames that could not be\n"
    "certified are tinted red, bordered in red and labelled; frames whose solve did not converge are labelled\n"
    "NOT CONVERGED in orange; frames that overlap themselves (the image of the boundary crosses itself,\n"
    "frames.hsif flag 8) get an amber border and label.";

void register_info(CLI::App& app);
void register_import_png(CLI::App& app);
void register_import_glyph(CLI::App& app);
void register_keyframes(CLI::App& app);
void register_eval(CLI::App& app);
void register_interpolate(CLI::App& app);
void register_bake(CLI::App& app);
void register_export(CLI::App& app);
void register_render(CLI::App& app);
void register_compare(CLI::App& app);

}  // namespace hsi::cli
