// GPU playback of a baked sequence (.hsib) under Vulkan: the basis rows of a bound
// mesh in a storage buffer, a blend's uniforms in a uniform buffer, and
// shaders/hsib_playback.glsl (the same function a game's vertex shader calls) run as
// a compute pass over `instances` copies of the mesh, writing every position and,
// optionally, every vertex's singular values (sigma1, sigma2: hsib_singular_values,
// from the derivative rows of a binding made with HSIB_BIND_DERIVATIVES). For tests
// against the C runtime and for bench_hsib_gpu; a game draws with its own vertex
// shader instead.
#pragma once

#include <vector>

#include "hsi/baked_runtime.h"
#include "hsi/compute/compute_pipeline.h"
#include "hsi/compute/descriptor_set.h"
#include "hsi/compute/vulkan_context.h"

namespace hsi::compute {

class HsibPlayback {
 public:
  // positions: where the output lives (the singular values too); kReadback lets
  // positions() and sigmas() read it back. distortion: also write sigma1, sigma2 per
  // vertex (the binding must carry derivative rows, else InputError).
  HsibPlayback(const Context& context, const hsib_binding* binding, uint32_t instances,
               MemoryUse positions = MemoryUse::kReadback, bool distortion = false);
  // The uniforms of `blend` (hsib_gpu_uniforms); throws InputError for an invalid blend.
  void set_blend(const hsib_blend& blend);
  // Runs the pass and waits; returns its GPU time in ms by timestamps (negative where
  // the queue has none).
  double run();
  // x, y per vertex, instance after instance (only with MemoryUse::kReadback).
  std::vector<float> positions() const;
  // sigma1, sigma2 per vertex, as positions() (only when constructed with distortion).
  std::vector<float> sigmas() const;
  uint32_t row_length() const { return row_length_; }
  bool distortion() const { return distortion_; }

 private:
  const Context* context_;
  const hsib_sequence* sequence_;
  uint32_t vertices_, instances_, row_length_;
  bool distortion_;
  Buffer rows_, uniforms_, positions_, derivative_rows_, sigmas_;
  ComputePipeline pipeline_;
  DescriptorSet set_;
};

}  // namespace hsi::compute
