// The Vulkan side of hsi: a device context (instance, one compute-capable device and
// queue, optional validation layer whose messages are recorded), RAII owners for
// device handles and buffers, one-shot command submission and barriers. The other
// GPU objects have a header each: image.h, sampler.h, render_pass.h, framebuffer.h,
// shader_module.h, pipeline_layout.h, descriptor_set.h, compute_pipeline.h,
// graphics_pipeline.h (whose fixed-function state is pipeline_state.h),
// command_buffer.h and sync.h (fences, semaphores).
//
// Vulkan is loaded at run time through volk (VK_NO_PROTOTYPES): a machine without a
// Vulkan loader or device gets a VulkanUnavailable exception, not a link error.
// Not thread-safe: use one Context (and everything made from it) from one thread.
#pragma once

#include <volk.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace hsi::compute {

// A Vulkan call failed; result() is the VkResult (VK_SUCCESS where none applies).
class VulkanError : public std::runtime_error {
 public:
  VulkanError(const std::string& what, VkResult result = VK_SUCCESS);
  VkResult result() const { return result_; }

 private:
  VkResult result_;
};

// No Vulkan loader, no Vulkan 1.2 instance, or no device with a compute queue (or
// none matching the requested name). Callers that can do without the GPU catch this.
class VulkanUnavailable : public VulkanError {
 public:
  using VulkanError::VulkanError;
};

// Throws VulkanError naming `what` and the result unless r == VK_SUCCESS.
void check(VkResult r, const char* what);
const char* result_name(VkResult r);

struct ContextOptions {
  // Enables VK_LAYER_KHRONOS_validation and a debug messenger that records every
  // warning and error (see ValidationLog). Throws VulkanError if the layer is missing.
  bool validation = false;
  // With validation: also enable the layer's synchronization validation (missing
  // barriers, hazards) where the layer offers VK_EXT_validation_features.
  bool synchronization_validation = true;
  // Picks the first device whose name contains this (case-sensitive), e.g.
  // "llvmpipe". Empty: the environment variable HSI_VULKAN_DEVICE if set, else the
  // best device (discrete GPU > integrated > virtual > CPU, e.g. lavapipe).
  std::string device_name;
  // Enables shaderFloat64 when the device has it (DeviceInfo::float64 says whether).
  bool want_float64 = true;
  std::string application_name = "hsi";
  // Presenting to a window (the viewer): extra instance extensions (e.g. VK_KHR_surface
  // and the platform's, from glfwGetRequiredInstanceExtensions), and a function that
  // makes the window's surface once the instance exists. With make_surface the context
  // owns the surface (destroyed before the instance), picks a queue family that can
  // also present to it, and enables VK_KHR_swapchain on the device.
  std::vector<std::string> instance_extensions;
  std::function<VkSurfaceKHR(VkInstance)> make_surface;
};

struct ValidationMessage {
  VkDebugUtilsMessageSeverityFlagBitsEXT severity;
  VkDebugUtilsMessageTypeFlagsEXT type;
  std::string id;    // e.g. "VUID-vkCmdDispatch-None-02697"
  std::string text;
};

// Every validation/debug message (severity warning or error) seen by the messenger,
// including those emitted while the instance and device are destroyed: hold the
// shared_ptr past the Context to check that teardown was clean (no leaked objects).
class ValidationLog {
 public:
  size_t count() const;
  size_t error_count() const;
  std::vector<ValidationMessage> messages() const;
  std::string summary(size_t max_messages = 5) const;  // "" when empty
  void clear();
  void add(ValidationMessage message);

 private:
  mutable std::mutex mutex_;
  std::vector<ValidationMessage> messages_;
};

struct DeviceInfo {
  std::string name;
  VkPhysicalDeviceType type = VK_PHYSICAL_DEVICE_TYPE_OTHER;
  uint32_t api_version = 0, driver_version = 0, vendor_id = 0;
  bool float64 = false;  // shaderFloat64 available and enabled
  uint32_t max_workgroup_count[3] = {0, 0, 0};
  uint32_t max_workgroup_invocations = 0;
  VkDeviceSize max_storage_buffer_range = 0;
  VkDeviceSize non_coherent_atom_size = 1;
  // Timestamp queries on the chosen queue: nanoseconds per tick, valid bits (0: none).
  double timestamp_period_ns = 0;
  uint32_t timestamp_valid_bits = 0;
  // The chosen queue family's VkQueueFlags and index.
  VkQueueFlags queue_flags = 0;
  uint32_t queue_family = 0;
  bool can_draw() const { return (queue_flags & VK_QUEUE_GRAPHICS_BIT) != 0; }
  bool is_cpu() const { return type == VK_PHYSICAL_DEVICE_TYPE_CPU; }
  std::string type_name() const;
};

class Context {
 public:
  explicit Context(const ContextOptions& options = {});
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  VkInstance instance() const { return instance_; }
  VkPhysicalDevice physical_device() const { return physical_; }
  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  uint32_t queue_family() const { return queue_family_; }
  VkSurfaceKHR surface() const { return surface_; }  // VK_NULL_HANDLE without make_surface
  const DeviceInfo& info() const { return info_; }
  const VkPhysicalDeviceMemoryProperties& memory_properties() const { return memory_; }

  bool validation_enabled() const { return messenger_ != VK_NULL_HANDLE; }
  const std::shared_ptr<ValidationLog>& validation_log() const { return log_; }

  // Index of a memory type allowed by type_bits with all `required` flags, the one
  // with the most `preferred` flags first. Throws VulkanError if none.
  uint32_t memory_type(uint32_t type_bits, VkMemoryPropertyFlags required,
                       VkMemoryPropertyFlags preferred = 0) const;

  // Records commands into a fresh primary command buffer, submits it to the queue
  // and waits for it to finish.
  void submit_and_wait(const std::function<void(VkCommandBuffer)>& record) const;
  // GPU execution time of the last submit_and_wait, by timestamps written at its
  // command buffer's start and end (what the device spent, without the host's
  // recording, submission and wake-up); negative where the queue has no timestamps.
  double last_device_ms() const { return last_device_ms_; }
  // Inside a submit_and_wait's recording: writes a timestamp once everything recorded
  // so far has finished, so a submission can be split into timed parts. After the
  // submission, last_device_marks()[k] is the time of mark k since the start in ms
  // (empty without timestamps). At most kMaxMarks per submission (more are ignored).
  static constexpr uint32_t kMaxMarks = 16;
  void mark(VkCommandBuffer cmd) const;
  const std::vector<double>& last_device_marks() const { return last_marks_ms_; }

 private:
  void create_instance(const ContextOptions& options);
  void pick_device(const ContextOptions& options);
  void create_device(const ContextOptions& options);
  void destroy() noexcept;

  std::shared_ptr<ValidationLog> log_ = std::make_shared<ValidationLog>();
  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkSurfaceKHR surface_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queue_family_ = 0;
  VkCommandPool command_pool_ = VK_NULL_HANDLE;
  VkQueryPool timestamps_ = VK_NULL_HANDLE;  // start, end of a submit_and_wait, then its marks
  mutable double last_device_ms_ = -1;
  mutable uint32_t marks_ = 0;  // marks recorded in the submission being recorded
  mutable std::vector<double> last_marks_ms_;
  DeviceInfo info_;
  VkPhysicalDeviceMemoryProperties memory_{};
};

// Move-only owner of one device-level handle: destroy(device, handle) runs once, in
// the destructor or reset(). Everything below is built from these, so no logic
// calls vkDestroy* itself.
template <class T>
class DeviceHandle {
 public:
  using Destroy = void (*)(VkDevice, T);
  DeviceHandle() = default;
  DeviceHandle(VkDevice device, T handle, Destroy destroy) : device_(device), handle_(handle), destroy_(destroy) {}
  DeviceHandle(DeviceHandle&& o) noexcept
      : device_(o.device_), handle_(std::exchange(o.handle_, T(VK_NULL_HANDLE))), destroy_(o.destroy_) {}
  DeviceHandle& operator=(DeviceHandle&& o) noexcept {
    if (this != &o) {
      reset();
      device_ = o.device_;
      handle_ = std::exchange(o.handle_, T(VK_NULL_HANDLE));
      destroy_ = o.destroy_;
    }
    return *this;
  }
  DeviceHandle(const DeviceHandle&) = delete;
  DeviceHandle& operator=(const DeviceHandle&) = delete;
  ~DeviceHandle() { reset(); }

  T get() const { return handle_; }
  explicit operator bool() const { return handle_ != T(VK_NULL_HANDLE); }
  void reset() {
    if (handle_ != T(VK_NULL_HANDLE) && destroy_) destroy_(device_, handle_);
    handle_ = T(VK_NULL_HANDLE);
  }

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  T handle_ = T(VK_NULL_HANDLE);
  Destroy destroy_ = nullptr;
};

// Memory for a resource with `requirements`: of a type allowed by them with all
// `required` flags, the one with the most `preferred` flags first. `flags` receives
// the chosen type's flags. Throws VulkanError if none fits or the allocation fails.
DeviceHandle<VkDeviceMemory> allocate_memory(const Context& context, const VkMemoryRequirements& requirements,
                                             VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred,
                                             VkMemoryPropertyFlags* flags = nullptr);

// Where a buffer's memory lives.
enum class MemoryUse {
  kDeviceLocal,  // fastest for the GPU; may or may not be host-visible
  kUpload,       // host-visible, coherent, mapped; written by the CPU, read by the GPU
  kReadback,     // host-visible, mapped, cached when possible; written by the GPU
};

// A VkBuffer with its own VkDeviceMemory (one allocation per buffer: the passes here
// use a handful of large buffers). Host-visible memory stays mapped for its lifetime.
class Buffer {
 public:
  Buffer() = default;
  Buffer(const Context& context, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUse use);
  Buffer(Buffer&& o) noexcept;
  Buffer& operator=(Buffer&& o) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  ~Buffer() { release(); }

  VkBuffer handle() const { return buffer_.get(); }
  VkDeviceSize size() const { return size_; }
  bool host_visible() const { return mapped_ != nullptr; }
  void* mapped() const { return mapped_; }
  VkMemoryPropertyFlags memory_flags() const { return flags_; }
  explicit operator bool() const { return static_cast<bool>(buffer_); }

  // Copy to/from the mapped memory (flushing/invalidating non-coherent memory).
  // Throws VulkanError if the buffer is not host-visible or the range is out of bounds.
  void write(const void* data, VkDeviceSize bytes, VkDeviceSize offset = 0);
  void read(void* out, VkDeviceSize bytes, VkDeviceSize offset = 0) const;

 private:
  void release();  // unmap, destroy the buffer, then free its memory
  void check_range(VkDeviceSize bytes, VkDeviceSize offset, const char* op) const;

  const Context* context_ = nullptr;
  DeviceHandle<VkDeviceMemory> memory_;
  DeviceHandle<VkBuffer> buffer_;
  void* mapped_ = nullptr;
  bool coherent_ = true;
  VkMemoryPropertyFlags flags_ = 0;
  VkDeviceSize size_ = 0;
};

// Number of workgroups along x and y to cover `groups` groups without exceeding the
// device's per-dimension limit; shaders flatten (x, y) back to a linear index.
std::pair<uint32_t, uint32_t> split_dispatch(const Context& context, uint64_t groups);

// A global memory barrier: `src_access` by `src_stage` before `dst_access` by `dst_stage`.
void memory_barrier(VkCommandBuffer cmd, VkPipelineStageFlags src_stage, VkAccessFlags src_access,
                    VkPipelineStageFlags dst_stage, VkAccessFlags dst_access);
// A colour image's barrier and layout transition `from` -> `to` over mip levels
// [first_mip, first_mip + mips): `src_access` by `src_stage` before `dst_access` by `dst_stage`.
void image_barrier(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to, VkAccessFlags src_access,
                   VkAccessFlags dst_access, VkPipelineStageFlags src_stage, VkPipelineStageFlags dst_stage,
                   uint32_t first_mip = 0, uint32_t mips = 1);

}  // namespace hsi::compute
