// hsi-viewer SCENE: plays a scene's interpolation live and edits its keyframes. The
// command line, then the window (GLFW), Vulkan context and ImGui around App's frames.
#include <CLI/CLI.hpp>
#include <imgui.h>
#include <volk.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>

#include <cstdio>
#include <exception>
#include <stdexcept>

#include "hsi/sample_limits.h"
#include "app.h"
#include "hsi/compute/vulkan_context.h"
#include "hsi/domain.h"
#include "hsi/runtime/backend.h"
#include "hsi/scene_io.h"

namespace hsi::viewer {

int run(const Options& o) {
  glfwSetErrorCallback([](int code, const char* text) { std::fprintf(stderr, "hsi-viewer: GLFW error %d: %s\n", code, text); });
  if (!glfwInit()) throw std::runtime_error("hsi-viewer: cannot initialise GLFW (no display? run under X11/Wayland or xvfb-run)");
  struct GlfwGuard {
    ~GlfwGuard() { glfwTerminate(); }
  } glfw_guard;
  if (!glfwVulkanSupported()) throw compute::VulkanUnavailable("hsi-viewer: GLFW finds no Vulkan loader/driver for windows");
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  glfwWindowHint(GLFW_SCALE_TO_MONITOR, GLFW_TRUE);
  GLFWwindow* window = glfwCreateWindow(o.width, o.height, "hsi viewer", nullptr, nullptr);
  if (!window) throw std::runtime_error("hsi-viewer: cannot open a window");
  struct WindowGuard {
    GLFWwindow* w;
    ~WindowGuard() { glfwDestroyWindow(w); }
  } window_guard{window};

  compute::ContextOptions co;
  co.validation = o.validation;
  co.device_name = o.device;
  co.application_name = "hsi-viewer";
  uint32_t n = 0;
  const char** ext = glfwGetRequiredInstanceExtensions(&n);
  for (uint32_t i = 0; i < n; ++i) co.instance_extensions.emplace_back(ext[i]);
  co.make_surface = [window](VkInstance instance) {
    VkSurfaceKHR surface = VK_NULL_HANDLE;
    const VkResult r = glfwCreateWindowSurface(instance, window, nullptr, &surface);
    if (r != VK_SUCCESS) throw compute::VulkanError(std::string("glfwCreateWindowSurface failed with ") + compute::result_name(r), r);
    return surface;
  };
  std::shared_ptr<compute::ValidationLog> log;
  int status = 0;
  {
    compute::Context ctx(co);
    log = ctx.validation_log();
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini next to the user's files
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForVulkan(window, true);
    struct ImGuiGuard {
      ~ImGuiGuard() {
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
      }
    } imgui_guard;
    {
      App app(o, window, ctx);
      std::printf("hsi-viewer: %s on %s (%s); press H for the keys\n", o.scene.c_str(), ctx.info().name.c_str(),
                  ctx.info().type_name().c_str());
      std::fflush(stdout);
      while (true) {
        glfwPollEvents();
        int w = 0, h = 0;
        glfwGetFramebufferSize(window, &w, &h);
        if (w == 0 || h == 0) {  // minimised
          glfwWaitEvents();
          continue;
        }
        if (!app.frame()) break;
      }
      status = app.script_status();
    }
  }
  if (log && log->count() > 0) {
    std::fprintf(stderr, "hsi-viewer: %s\n", log->summary(20).c_str());
    return 3;
  }
  return status;
}

}  // namespace hsi::viewer

int main(int argc, char** argv) {
  hsi::viewer::Options o;
  CLI::App app("hsi-viewer: real-time playback of a scene's harmonic shape interpolation, and keyframe editing "
               "(press H in the window for the keys)");
  app.add_option("scene", o.scene, "Scene file (.json)")->required()->check(CLI::ExistingFile);
  app.add_option("-o,--output", o.output, "Where Ctrl+S saves the scene (default: the scene file itself)");
  app.add_option("--width", o.width, "Window width (screen coordinates; scaled on high-DPI monitors)")->capture_default_str()
      ->check(CLI::Range(320, 16384));
  app.add_option("--height", o.height, "Window height")->capture_default_str()->check(CLI::Range(240, 16384));
  app.add_option("--rate", o.rate, "Timeline frames per unit of scene time")->capture_default_str()->check(CLI::Range(1.0, 1000.0));
  app.add_option("--speed", o.speed, "Playback speed")->capture_default_str()->check(CLI::Range(0.125, 8.0));
  app.add_flag("!--no-loop", o.loop, "Stop at the end instead of looping");
  app.add_flag("!--paused", o.play, "Start paused");
  app.add_option("--backend", o.backend, hsi::runtime::kBackendHelp)
      ->capture_default_str()->check(CLI::IsMember(hsi::runtime::backend_names()));
  app.add_option("--samples", o.samples, "Boundary samples |G| (default: the scene's)")->check(CLI::Range(hsi::kMinSamples, hsi::kMaxSamples));
  app.add_option("--mesh-vertices", o.mesh_vertices, "Render mesh size")->capture_default_str()->check(CLI::Range(100, 2000000));
  app.add_option("--overlays", o.overlays,
                 "Overlays on at start, comma-separated: distortion, boundary, cage, handles, status, help, none")
      ->capture_default_str();
  app.add_flag("--validation", o.validation,
               "Run under the Vulkan validation layer; any validation message makes the exit code 3");
  app.add_flag("!--no-vsync", o.vsync, "Present as fast as possible (mailbox/immediate where available)");
  app.add_option("--device", o.device, "Vulkan device whose name contains this (default: the best one)");
  app.add_option("--script", o.script,
                 "Run a script (one command per line: play, pause, frames N, seek F, key K, add-handle X Y, "
                 "remove-handle H, drag H X Y, undo, redo, save PATH, screenshot PATH, expect-certified, exit)")
      ->check(CLI::ExistingFile);
  app.add_option("--screenshot-after", o.screenshot_after,
                 "Play N timeline frames (each solved, one per drawn frame), then pause and take the --screenshot")
      ->check(CLI::Range(0, 1000000));
  app.add_option("--screenshot", o.screenshot, "Write the window to this PNG (and PATH.json: viewport, frame, certified)");
  app.add_flag("--exit", o.exit_after, "Quit after the screenshot");
  app.add_flag("--lockstep", o.lockstep, "Play one solved frame per drawn frame instead of in real time");
  CLI11_PARSE(app, argc, argv);
  try {
    // A scene that does not load is refused before any window or GPU work, so the
    // message is the scene's problem, not a missing display's.
    (void)hsi::load_scene(o.scene);
    return hsi::viewer::run(o);
  } catch (const hsi::compute::VulkanUnavailable& e) {
    std::fprintf(stderr, "hsi-viewer: needs Vulkan for a window: %s\n", e.what());
    return 1;
  } catch (const hsi::InputError& e) {
    std::fprintf(stderr, "hsi-viewer: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hsi-viewer: %s\n", e.what());
    return 1;
  }
}
