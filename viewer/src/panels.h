// The viewer's ImGui panels: the viewport's overlays (cage, handles, the certificate's
// badge or banner, the distortion legend), the side panel (scene, performance, the
// frame's numbers, overlay switches, keyframes and editing), the timeline and the help.
#pragma once

#include <imgui.h>

#include <chrono>
#include <string>

#include "hsi/overlap.h"
#include "hsi/scene_edit.h"
#include "playback.h"
#include "solver.h"
#include "view.h"

namespace hsi::viewer {

// What is drawn on top of the rendered frame, and which panels are open.
struct Overlays {
  uint32_t render = 0;  // the renderer's overlays (compute::kOverlayDistortion, compute::kOverlayBoundary)
  bool cage = false, handles = true, status = true, help = false;
  bool nearest = false;  // texture filtering: nearest texels, else linear (starts as the scene's texture_filter)
};
// --overlays (comma-separated names); InputError naming an unknown one.
Overlays parse_overlays(const std::string& list);

// The map on screen and what it is.
struct Shown {
  const HarmonicMap* map = nullptr;
  bool certified = true;
  std::string reason;  // why not certified
  bool is_key = false;  // a keyframe (or a pose being dragged)
};

// A note or an error for the user, shown for a few seconds.
struct Message {
  std::string text;
  bool error = false;
  std::chrono::steady_clock::time_point time;
};

// Everything the panels show.
struct PanelContext {
  const SceneEditor& editor;
  const std::string& scene_file;
  const Cage& cage;
  const Solver& solver;
  const std::string& device;  // the Vulkan device's name
  Playback& playback;
  Overlays& overlays;
  const View& view;
  ImTextureID frame_texture;  // the rendered frame
  const Shown& shown;
  const SolvedFrame* frame;         // the solved frame shown, when it is the current frame and no keyframe
  const OverlapResult* overlap;     // of the map shown
  double render_ms = 0, dist_hi = 2;
  int hover_handle = -1;
  bool releasing = false;           // a pose's final solve is running
  const Message& message;
};

// What the side panel's buttons ask for this frame.
struct PanelRequests {
  bool add_keyframe = false, remove_keyframe = false, undo = false, redo = false, save = false;
  int timing_keyframe = -1;  // ≥ 0: set the timing of the interval leaving this keyframe to `timing`
  KeyTiming timing = KeyTiming::Linear;
};

void draw_viewport_overlays(const PanelContext& c);
PanelRequests draw_side_panel(const PanelContext& c);
// The timeline also offers each keyframe interval's timing (right click on it).
PanelRequests draw_timeline(const PanelContext& c);
void draw_help(Overlays& overlays, const View& view);

}  // namespace hsi::viewer
