// hsi-viewer: the interactive viewer (GLFW window, Vulkan through compute/, Dear ImGui).
// App is the wiring: it loads the scene, owns the solver thread, the renderer and the
// presenter, and routes each frame's input to the view (view.h), playback
// (playback.h), the scene editor (hsi/scene_edit.h: the editing rules), the panels
// (panels.h) and a script (script.h).
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "hsi/compute/renderer.h"
#include "hsi/compute/vulkan_context.h"
#include "hsi/inverse_map.h"
#include "hsi/scene_edit.h"
#include "panels.h"
#include "playback.h"
#include "presenter.h"
#include "script.h"
#include "solver.h"
#include "view.h"

struct GLFWwindow;

namespace hsi::viewer {

struct Options {
  std::string scene;
  std::string output;            // where Ctrl+S saves (default: the scene file)
  int width = 1280, height = 800;  // window size in screen coordinates (scaled by the monitor's content scale)
  double rate = 30;              // timeline frames per unit of scene time
  double speed = 1;              // playback speed
  bool loop = true, play = true;
  std::string backend = "auto";  // Newton core: auto (CUDA when present), cpu, cuda
  int samples = 0;               // |G| override (0: the scene's)
  int mesh_vertices = 12000;     // render mesh size
  std::string overlays = "boundary,handles,status";
  bool validation = false;       // Vulkan validation layer; any message makes the exit code 3
  bool vsync = true;
  std::string device;            // Vulkan device name filter
  // Scripted runs (tests, recordings): a script file, or the shortcut
  // --screenshot-after N --screenshot PATH --exit.
  std::string script;
  int screenshot_after = -1;
  std::string screenshot;
  bool exit_after = false;
  bool lockstep = false;         // playback advances one solved frame per drawn frame (implied by scripts)
};

// The viewer's state for one window.
class App final : public ScriptHost {
 public:
  App(const Options& o, GLFWwindow* window, compute::Context& ctx);
  ~App() override;
  bool frame();  // one UI frame; false: quit
  int script_status() const { return script_.failed() ? 4 : 0; }

  // What a script drives (script.h).
  bool playing() const override { return playback_->playing(); }
  void toggle_play() override { playback_->toggle_play(); }
  void pause() override { playback_->pause(); }
  int played_frames() const override { return playback_->played_frames(); }
  int current_frame() const override { return playback_->current(); }
  void seek(int frame) override { playback_->seek(frame); }
  void press_key(int glfw_key) override;
  void add_handle_at(cd world) override;
  void remove_handle(int h) override;
  std::string drag(int h, cd target) override;
  bool dragging() const override { return editor_->pose() != nullptr; }
  std::string undo_redo(bool undo) override;
  std::string set_timing(int k, KeyTiming timing) override;
  bool save(const std::string& path) override;
  bool shown_certified(std::string* reason) override;
  bool current_frame_drawn() override;

 private:
  // --- scene and editing (the rules are the SceneEditor's) ---
  void load();
  void keyframes_changed();  // pushes the keyframes to the solver, recomputes the view box
  void message(const std::string& m, bool error = false);
  void show(const EditOutcome& o) {
    if (!o.message.empty()) message(o.message, o.error);
  }
  EditFrame edit_frame() const;  // the current frame, for the editor (without its solved map)
  void add_keyframe();
  void remove_keyframe();
  bool begin_drag(int handle, const EditFrame& at);
  void drag_to(cd world);
  void end_drag();
  void request_pose(bool final);
  void poll_pose_results();
  std::string output_path() const { return o_.output.empty() ? o_.scene : o_.output; }

  // --- display ---
  Shown shown();  // the map on screen
  // Whether a map's boundary image crosses itself (hsi/overlap.h), cached by its coefficients.
  const OverlapResult& overlap_of(const HarmonicMap& map);
  void render();
  void handle_input();
  void handle_keys();
  void draw_panels();
  void write_capture(const RgbaImage& shot);

  Options o_;
  GLFWwindow* window_;
  compute::Context& ctx_;
  Overlays overlays_;
  View view_;
  ScriptRunner script_;
  std::unique_ptr<SceneEditor> editor_;
  std::shared_ptr<const ShapeSetup> setup_;
  OverlapResult overlap_;           // of the map with coefficients overlap_phi_, overlap_psi_
  VectorXcd overlap_phi_, overlap_psi_;
  std::unique_ptr<Solver> solver_;
  std::unique_ptr<Playback> playback_;
  std::unique_ptr<Presenter> presenter_;
  std::unique_ptr<compute::Renderer> renderer_;
  std::unique_ptr<InverseMap> inverse_;  // picking: the rest point under the mouse
  TriMesh mesh_;
  BasisRows probe_rows_;
  RgbaImage texture_;
  std::array<double, 4> texture_rect_{};
  TextureFilter texture_filter_ = TextureFilter::Linear;  // the scene's texture_filter
  bool title_dirty_ = false, quit_ = false;
  double dist_hi_ = 2;
  std::chrono::steady_clock::time_point last_time_ = std::chrono::steady_clock::now();

  // the frame shown and the rendering cache
  int shown_index_ = -1;
  std::shared_ptr<const SolvedFrame> shown_;
  double render_ms_ = 0;
  const void* rendered_map_ = nullptr;
  uint64_t rendered_sig_ = 0;
  bool frame_ready_ = false;  // the presenter holds the image of the current state

  // a drag in progress (the pose itself is the editor's)
  int hover_handle_ = -1;
  struct Drag {
    bool releasing = false;  // the final solve was asked for
    uint64_t final_id = 0;
  } drag_;
  uint64_t pose_id_ = 0;
  Message message_;
};

// Runs the viewer until the window closes (or a script exits). Returns the process
// exit code: 0, 3 when validation reported messages, 4 when a script step failed.
int run(const Options& options);

}  // namespace hsi::viewer
