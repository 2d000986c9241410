// Presents to a GLFW window through compute/'s Vulkan context: the swapchain (recreated
// on resize, with its frames in flight), and a Dear ImGui renderer (draw lists, the
// font atlas, and one texture holding the frame the offscreen Renderer drew) that
// records into the swapchain image. Its GPU objects are compute/'s RAII types
// (Image, Sampler, RenderPass, Framebuffer, PipelineLayout, GraphicsPipeline), the same
// as the renderer's; Vulkan through volk like the rest of compute/, so the ImGui
// Vulkan backend that Debian compiles against libvulkan's prototypes is not used.
// Two frames in flight; main thread only.
#pragma once

#include <imgui.h>

#include <memory>

#include "hsi/png.h"
#include "hsi/compute/vulkan_context.h"

struct GLFWwindow;

namespace hsi::viewer {

class Presenter {
 public:
  Presenter(const compute::Context& context, GLFWwindow* window, bool vsync);
  ~Presenter();
  Presenter(const Presenter&) = delete;
  Presenter& operator=(const Presenter&) = delete;

  // Uploads ImGui's font atlas (call after the fonts are added, before the first frame).
  void upload_fonts();
  // The frame image (straight RGBA, as Renderer::render returns it), uploaded on the
  // next present(); frame_texture() is what ImGui::Image / AddImage draw it with.
  void set_frame_image(const RgbaImage& image);
  ImTextureID frame_texture() const;
  int frame_width() const;
  int frame_height() const;

  // Draws `data` into the next swapchain image and presents it. With `capture`, the
  // presented image is also read back (RGBA, alpha 255). Returns false when nothing
  // was presented (the window is minimised or the swapchain was out of date and has
  // been recreated): draw the frame again.
  bool present(ImDrawData* data, RgbaImage* capture = nullptr);
  // Waits for the GPU (before destroying what frames in flight use).
  void wait_idle() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hsi::viewer
