// The renderer's graphics passes (private): one render pass over the frame's target
// image drawing the textured mesh (graphics rasterizer: into an MSAA image resolved
// into the target), the boundary as lines and the handles as discs. After the
// compute rasterizer it draws only the lines and discs, single-sampled, onto the
// target as the compute passes left it.
#pragma once

#include <cstdint>

#include "hsi/compute/descriptor_set.h"
#include "hsi/compute/framebuffer.h"
#include "hsi/compute/graphics_pipeline.h"
#include "hsi/compute/image.h"
#include "hsi/compute/pipeline_layout.h"
#include "hsi/compute/render_pass.h"
#include "render_frame.h"

namespace hsi::compute::render {

class GraphicsRaster {
 public:
  // samples: the MSAA samples of the graphics rasterizer; after_compute: draw over
  // the compute rasterizer's target (then single-sampled, no mesh); f64: the
  // vertex shaders read f in double precision.
  GraphicsRaster(const Context& context, const Image& target, VkSampleCountFlagBits samples, bool after_compute, bool f64);

  // Records the pass: the mesh unless after_compute (with the red border of an
  // uncertified frame, border_px wide), then the lines and discs asked for.
  void record(VkCommandBuffer cmd, const FrameInputs& in, const RenderStyle& style, RenderPush pc, uint32_t border_px,
              bool lines, bool discs);

 private:
  bool after_compute_;
  RenderPass pass_;
  Image msaa_;  // empty with one sample
  Framebuffer framebuffer_;
  PipelineLayout layout_;
  DescriptorSet set_;
  GraphicsPipeline mesh_, line_, disc_;  // mesh_: graphics rasterizer only
};

}  // namespace hsi::compute::render
