// hsi-viewer: the interactive viewer (GLFW window, Vulkan through compute/, Dear ImGui).
#pragma once

#include <string>

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

// Runs the viewer until the window closes (or a script exits). Returns the process
// exit code: 0, 3 when validation reported messages, 4 when a script step failed.
int run(const Options& options);

}  // namespace hsi::viewer
