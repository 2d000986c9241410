// The renderer's GPU state (private to renderer.cpp and render_recording.cpp): the
// target image every frame ends in, the mesh and texture it draws, and the passes of
// the chosen rasterizer. Members are destroyed in reverse order: the passes (whose
// framebuffer and descriptor sets refer to the images) before the images.
#pragma once

#include <optional>

#include "hsi/compute/image.h"
#include "hsi/compute/renderer.h"
#include "hsi/compute/sampler.h"
#include "raster_compute.h"
#include "raster_graphics.h"
#include "render_frame.h"

namespace hsi::compute {

struct Renderer::Impl {
  Image target;     // the single-sample frame: resolved into, or written by the compute passes; copied out
  Buffer readback;  // the frame copied to the host
  Sampler sampler;
  Image white, texture;  // white: the 1 × 1 placeholder without a texture
  Buffer uv, index, segments;
  // Given geometry (render(positions, kappa, ...)): the layouts of the evaluation's
  // f and fields outputs, host-written.
  Buffer given_f, given_fields;
  size_t given_capacity = 0;  // points they hold
  // The graphics passes (the whole frame, or the lines and discs over the compute
  // rasterizer's target), and the compute rasterizer if chosen.
  std::optional<render::GraphicsRaster> graphics;
  std::optional<render::ComputeRaster> compute;
};

}  // namespace hsi::compute
