// GPU playback of baked sequences as a compute pass (hsi/compute/hsib_playback.h).
#include "hsi/compute/hsib_playback.h"

#include <array>
#include <span>
#include <string>

#include "hsi/compute/spirv/hsib_playback_probe.h"
#include "hsi/compute/spirv/hsib_playback_sigma_probe.h"
#include "hsi/domain.h"

namespace hsi::compute {
namespace {
constexpr uint32_t kMaxRows = 1024;  // HSIB_MAX_ROWS in shaders/hsib_playback_probe.comp
constexpr uint32_t kWorkgroupSize = 64;
// rows, uniforms, positions; then, for distortion, derivative rows and sigmas
// (the bindings of shaders/hsib_playback_probe.comp).
constexpr std::array<VkDescriptorType, 5> kBindings = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
                                                       VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                                       VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};
struct Push {
  uint32_t vertex_count, total;
};
}  // namespace

HsibPlayback::HsibPlayback(const Context& context, const hsib_binding* binding, uint32_t instances, MemoryUse positions, bool distortion)
    : context_(&context), instances_(instances), distortion_(distortion) {
  if (!binding || instances == 0) throw InputError("GPU playback: no binding or no instances");
  if (distortion && !(hsib_binding_flags(binding) & HSIB_BIND_DERIVATIVES))
    throw InputError("GPU playback: distortion needs a binding with derivative rows (hsib_bind_flags with HSIB_BIND_DERIVATIVES)");
  vertices_ = static_cast<uint32_t>(hsib_binding_vertex_count(binding));
  sequence_ = hsib_binding_sequence(binding);
  hsib_info info;
  hsib_get_info(sequence_, &info);
  row_length_ = info.row_length;
  if (row_length_ > kMaxRows)
    throw InputError("GPU playback: rows of " + std::to_string(row_length_) + " floats; the shader takes at most " + std::to_string(kMaxRows));
  if (vertices_ == 0) throw InputError("GPU playback: the binding has no vertices");
  if (static_cast<uint64_t>(vertices_) * instances_ > 0xFFFFFFFFull)
    throw InputError("GPU playback: " + std::to_string(vertices_) + " vertices x " + std::to_string(instances_) + " instances exceed 2^32");
  // One line of texels per vertex would do for a buffer; the runtime's layout with
  // width = T texels is exactly that (texel v*T + q).
  const uint32_t T = hsib_gpu_texels_per_vertex(sequence_);
  std::vector<float> texels(hsib_gpu_rows_floats(binding, T));
  if (hsib_gpu_rows(binding, T, texels.data()) != HSIB_OK) throw InputError("GPU playback: hsib_gpu_rows failed");
  rows_ = Buffer(context, texels.size() * sizeof(float), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kUpload);
  rows_.write(texels.data(), texels.size() * sizeof(float));
  uniforms_ = Buffer(context, 16ull * (2 + kMaxRows), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, MemoryUse::kUpload);
  positions_ = Buffer(context, 8ull * vertices_ * instances_, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, positions);
  if (distortion) {
    std::vector<float> derivatives(hsib_gpu_derivative_rows_floats(binding, 2 * T));
    if (hsib_gpu_derivative_rows(binding, 2 * T, derivatives.data()) != HSIB_OK)
      throw InputError("GPU playback: hsib_gpu_derivative_rows failed");
    derivative_rows_ = Buffer(context, derivatives.size() * sizeof(float), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kUpload);
    derivative_rows_.write(derivatives.data(), derivatives.size() * sizeof(float));
    sigmas_ = Buffer(context, 8ull * vertices_ * instances_, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, positions);
    pipeline_ = ComputePipeline(context, hsib_playback_sigma_probe, kBindings, sizeof(Push));
  } else {
    pipeline_ = ComputePipeline(context, hsib_playback_probe, std::span(kBindings).first(3), sizeof(Push));
  }
  set_ = DescriptorSet(context, pipeline_.layout());
  set_.bind(0, rows_);
  set_.bind(1, uniforms_);
  set_.bind(2, positions_);
  if (distortion) {
    set_.bind(3, derivative_rows_);
    set_.bind(4, sigmas_);
  }
  set_blend(hsib_blend{0, 0, 0.0f, 0});
}

void HsibPlayback::set_blend(const hsib_blend& blend) {
  std::vector<float> u(4 * (2 + static_cast<size_t>(kMaxRows)), 0.0f);
  if (hsib_gpu_uniforms(sequence_, &blend, u.data()) != HSIB_OK)
    throw InputError("GPU playback: frames " + std::to_string(blend.frame0) + ", " + std::to_string(blend.frame1) + " at s = " +
                     std::to_string(blend.s) + " are not a blend of this sequence");
  uniforms_.write(u.data(), u.size() * sizeof(float));
}

double HsibPlayback::run() {
  const uint64_t total = static_cast<uint64_t>(vertices_) * instances_;
  const Push push{vertices_, static_cast<uint32_t>(total)};
  context_->submit_and_wait([&](VkCommandBuffer cmd) {
    pipeline_.bind(cmd, set_);
    pipeline_.push(cmd, &push, sizeof push);
    const auto [gx, gy] = split_dispatch(*context_, (total + kWorkgroupSize - 1) / kWorkgroupSize);
    vkCmdDispatch(cmd, gx, gy, 1);
  });
  return context_->last_device_ms();
}

std::vector<float> HsibPlayback::positions() const {
  if (!positions_.host_visible()) throw InputError("GPU playback: the positions live in device memory; construct with kReadback");
  std::vector<float> out(2ull * vertices_ * instances_);
  positions_.read(out.data(), out.size() * sizeof(float));
  return out;
}

std::vector<float> HsibPlayback::sigmas() const {
  if (!distortion_) throw InputError("GPU playback: no singular values; construct with distortion = true");
  if (!sigmas_.host_visible()) throw InputError("GPU playback: the singular values live in device memory; construct with kReadback");
  std::vector<float> out(2ull * vertices_ * instances_);
  sigmas_.read(out.data(), out.size() * sizeof(float));
  return out;
}

}  // namespace hsi::compute
