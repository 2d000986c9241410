// The renderer's compute rasterizer (private; Rasterizer::kCompute, shaders/raster*.comp):
// the mesh's triangles into a visibility buffer of triangle ids per sample, then one
// shading per pixel and triangle, blended over the background and resolved straight
// into the frame's target image (left in GENERAL layout).
#pragma once

#include <cstdint>

#include "hsi/compute/compute_pipeline.h"
#include "hsi/compute/descriptor_set.h"
#include "hsi/compute/image.h"
#include "render_frame.h"

namespace hsi::compute::render {

class ComputeRaster {
 public:
  // Bytes of the visibility buffer for width × height pixels of `samples` samples.
  static uint64_t visibility_bytes(uint32_t width, uint32_t height, uint32_t samples) {
    return uint64_t{width} * height * samples * sizeof(uint32_t);
  }

  ComputeRaster(const Context& context, uint32_t width, uint32_t height, uint32_t samples, bool f64);

  // The queue of large triangles for a mesh of `triangles` triangles.
  void set_triangles(size_t triangles);
  // Records the passes; border_px: the uncertified frame's red border (0: none).
  void record(VkCommandBuffer cmd, const FrameInputs& in, const Image& target, const RenderStyle& style, const RenderPush& g,
              uint32_t border_px);

 private:
  const Context* context_;
  uint32_t width_, height_, samples_;
  // The visibility buffer (a triangle id per sample), the queue of large triangles
  // (count, indices), the two passes' pipelines and their descriptor sets.
  Buffer vis_, large_;
  ComputePipeline raster_, resolve_;
  DescriptorSet raster_set_, resolve_set_;
};

}  // namespace hsi::compute::render
