// Vulkan context and RAII resources (see vulkan_context.h). Function pointers come
// from volk, loaded per instance only (no volkLoadDevice), so several contexts may
// live at once: device calls go through the loader's dispatch.
#include "hsi/compute/vulkan_context.h"

#include <dlfcn.h>

#include <algorithm>
#include <bit>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "hsi/compute/sync.h"

namespace hsi::compute {

namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

std::string version_string(uint32_t v) {
  return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
         std::to_string(VK_API_VERSION_PATCH(v));
}

VKAPI_ATTR VkBool32 VKAPI_CALL debug_callback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                              VkDebugUtilsMessageTypeFlagsEXT type,
                                              const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  ValidationMessage m{severity, type, data && data->pMessageIdName ? data->pMessageIdName : "",
                      data && data->pMessage ? data->pMessage : ""};
  if (const char* env = std::getenv("HSI_VULKAN_DEBUG"); env && *env && *env != '0')
    std::fprintf(stderr, "[vulkan] %s\n", m.text.c_str());
  static_cast<ValidationLog*>(user)->add(std::move(m));
  return VK_FALSE;  // never abort the call
}

VkDebugUtilsMessengerCreateInfoEXT messenger_info(ValidationLog* log) {
  VkDebugUtilsMessengerCreateInfoEXT info{};
  info.sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT;
  info.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  info.pfnUserCallback = debug_callback;
  info.pUserData = log;
  return info;
}

bool has_device_extension(VkPhysicalDevice d, const char* name) {
  uint32_t n = 0;
  if (vkEnumerateDeviceExtensionProperties(d, nullptr, &n, nullptr) != VK_SUCCESS) return false;
  std::vector<VkExtensionProperties> props(n);
  if (vkEnumerateDeviceExtensionProperties(d, nullptr, &n, props.data()) != VK_SUCCESS) return false;
  return std::any_of(props.begin(), props.end(),
                     [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

int type_rank(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
    default: return 4;
  }
}

}  // namespace

// --- errors ---------------------------------------------------------------------

VulkanError::VulkanError(const std::string& what, VkResult result) : std::runtime_error(what), result_(result) {}

const char* result_name(VkResult r) {
  switch (r) {
#define HSI_VK_CASE(x) \
  case x: return #x;
    HSI_VK_CASE(VK_SUCCESS)
    HSI_VK_CASE(VK_NOT_READY)
    HSI_VK_CASE(VK_TIMEOUT)
    HSI_VK_CASE(VK_INCOMPLETE)
    HSI_VK_CASE(VK_ERROR_OUT_OF_HOST_MEMORY)
    HSI_VK_CASE(VK_ERROR_OUT_OF_DEVICE_MEMORY)
    HSI_VK_CASE(VK_ERROR_INITIALIZATION_FAILED)
    HSI_VK_CASE(VK_ERROR_DEVICE_LOST)
    HSI_VK_CASE(VK_ERROR_MEMORY_MAP_FAILED)
    HSI_VK_CASE(VK_ERROR_LAYER_NOT_PRESENT)
    HSI_VK_CASE(VK_ERROR_EXTENSION_NOT_PRESENT)
    HSI_VK_CASE(VK_ERROR_FEATURE_NOT_PRESENT)
    HSI_VK_CASE(VK_ERROR_INCOMPATIBLE_DRIVER)
    HSI_VK_CASE(VK_ERROR_TOO_MANY_OBJECTS)
    HSI_VK_CASE(VK_ERROR_FORMAT_NOT_SUPPORTED)
    HSI_VK_CASE(VK_ERROR_FRAGMENTED_POOL)
    HSI_VK_CASE(VK_ERROR_OUT_OF_POOL_MEMORY)
    HSI_VK_CASE(VK_ERROR_UNKNOWN)
#undef HSI_VK_CASE
    default: return "VkResult(other)";
  }
}

void check(VkResult r, const char* what) {
  if (r != VK_SUCCESS)
    throw VulkanError(std::string("Vulkan: ") + what + " failed with " + result_name(r) + " (" +
                          std::to_string(static_cast<int>(r)) + ")",
                      r);
}

// --- validation log ---------------------------------------------------------------

size_t ValidationLog::count() const {
  std::lock_guard lock(mutex_);
  return messages_.size();
}

size_t ValidationLog::error_count() const {
  std::lock_guard lock(mutex_);
  return static_cast<size_t>(std::count_if(messages_.begin(), messages_.end(), [](const ValidationMessage& m) {
    return m.severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  }));
}

std::vector<ValidationMessage> ValidationLog::messages() const {
  std::lock_guard lock(mutex_);
  return messages_;
}

std::string ValidationLog::summary(size_t max_messages) const {
  std::lock_guard lock(mutex_);
  if (messages_.empty()) return "";
  std::ostringstream s;
  s << messages_.size() << " Vulkan validation/debug message(s):";
  for (size_t i = 0; i < messages_.size() && i < max_messages; ++i) {
    const ValidationMessage& m = messages_[i];
    s << "\n  [" << (m.severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT ? "error" : "warning") << "] "
      << m.text;
  }
  if (messages_.size() > max_messages) s << "\n  ... and " << messages_.size() - max_messages << " more";
  return s.str();
}

void ValidationLog::clear() {
  std::lock_guard lock(mutex_);
  messages_.clear();
}

void ValidationLog::add(ValidationMessage message) {
  std::lock_guard lock(mutex_);
  messages_.push_back(std::move(message));
}

std::string DeviceInfo::type_name() const {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
    default: return "other";
  }
}

// --- context ----------------------------------------------------------------------

#if defined(__SANITIZE_ADDRESS__)
// AddressSanitizer builds only: LeakSanitizer reports at exit, after the Vulkan loader
// has dlclose()d the driver and the layers, so what they keep until exit shows as
// "<unknown module>" and the suppressions by module (tests/sanitizers/lsan.supp)
// cannot match it. Loading them once with RTLD_NODELETE keeps them mapped. Names
// that do not exist on this machine are skipped.
void pin_vulkan_modules() {
  static const bool pinned = [] {
    for (const char* lib : {"libvulkan.so.1", "libvulkan_lvp.so", "libVkLayer_khronos_validation.so"})
      dlopen(lib, RTLD_NOW | RTLD_NODELETE);
    return true;
  }();
  (void)pinned;
}
#endif

Context::Context(const ContextOptions& options) {
#if defined(__SANITIZE_ADDRESS__)
  pin_vulkan_modules();
#endif
  try {
    create_instance(options);
    pick_device(options);
    create_device(options);
  } catch (...) {
    destroy();  // the destructor does not run for a constructor that throws
    throw;
  }
}

Context::~Context() { destroy(); }

void Context::destroy() noexcept {
  if (device_) {
    vkDeviceWaitIdle(device_);
    if (timestamps_) vkDestroyQueryPool(device_, timestamps_, nullptr);
    if (command_pool_) vkDestroyCommandPool(device_, command_pool_, nullptr);
    vkDestroyDevice(device_, nullptr);
  }
  if (surface_) vkDestroySurfaceKHR(instance_, surface_, nullptr);
  if (messenger_) vkDestroyDebugUtilsMessengerEXT(instance_, messenger_, nullptr);
  if (instance_) vkDestroyInstance(instance_, nullptr);
  timestamps_ = VK_NULL_HANDLE;
  command_pool_ = VK_NULL_HANDLE;
  device_ = VK_NULL_HANDLE;
  surface_ = VK_NULL_HANDLE;
  messenger_ = VK_NULL_HANDLE;
  instance_ = VK_NULL_HANDLE;
}

void Context::create_instance(const ContextOptions& options) {
  if (volkInitialize() != VK_SUCCESS)
    throw VulkanUnavailable(
        "Vulkan is not available: no Vulkan loader (libvulkan.so.1) could be loaded; install one and a driver "
        "(on Debian: libvulkan1 and mesa-vulkan-drivers for the lavapipe CPU device)",
        VK_ERROR_INITIALIZATION_FAILED);
  const uint32_t loader_version = volkGetInstanceVersion();
  if (loader_version < VK_API_VERSION_1_2)
    throw VulkanUnavailable("Vulkan is not available: the loader supports Vulkan " + version_string(loader_version) +
                                ", hsi needs 1.2",
                            VK_ERROR_INCOMPATIBLE_DRIVER);

  uint32_t n = 0;
  check(vkEnumerateInstanceExtensionProperties(nullptr, &n, nullptr), "vkEnumerateInstanceExtensionProperties");
  std::vector<VkExtensionProperties> available(n);
  check(vkEnumerateInstanceExtensionProperties(nullptr, &n, available.data()), "vkEnumerateInstanceExtensionProperties");
  std::vector<const char*> layers, extensions;
  bool portability = false, sync_validation = false;
  for (const VkExtensionProperties& e : available)
    if (std::strcmp(e.extensionName, VK_KHR_PORTABILITY_ENUMERATION_EXTENSION_NAME) == 0) portability = true;
  if (portability) extensions.push_back(VK_KHR_PORTABILITY_ENUMERATION_EXTENSION_NAME);
  for (const std::string& e : options.instance_extensions) {
    const bool have = std::any_of(available.begin(), available.end(), [&](const VkExtensionProperties& a) {
      return e == a.extensionName;
    });
    if (!have)
      throw VulkanUnavailable("Vulkan is not available for a window: the instance extension " + e +
                                  " is missing (no Vulkan driver for this display?)",
                              VK_ERROR_EXTENSION_NOT_PRESENT);
    if (std::none_of(extensions.begin(), extensions.end(), [&](const char* x) { return e == x; }))
      extensions.push_back(e.c_str());
  }

  if (options.validation) {
    check(vkEnumerateInstanceLayerProperties(&n, nullptr), "vkEnumerateInstanceLayerProperties");
    std::vector<VkLayerProperties> props(n);
    check(vkEnumerateInstanceLayerProperties(&n, props.data()), "vkEnumerateInstanceLayerProperties");
    const bool found = std::any_of(props.begin(), props.end(), [](const VkLayerProperties& p) {
      return std::strcmp(p.layerName, kValidationLayer) == 0;
    });
    if (!found)
      throw VulkanError(std::string("Vulkan validation was requested but the layer ") + kValidationLayer +
                            " is not installed (on Debian: vulkan-validationlayers)",
                        VK_ERROR_LAYER_NOT_PRESENT);
    layers.push_back(kValidationLayer);
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);  // provided by the validation layer
    if (options.synchronization_validation) {
      check(vkEnumerateInstanceExtensionProperties(kValidationLayer, &n, nullptr), "vkEnumerateInstanceExtensionProperties");
      std::vector<VkExtensionProperties> layer_ext(n);
      check(vkEnumerateInstanceExtensionProperties(kValidationLayer, &n, layer_ext.data()),
            "vkEnumerateInstanceExtensionProperties");
      sync_validation = std::any_of(layer_ext.begin(), layer_ext.end(), [](const VkExtensionProperties& e) {
        return std::strcmp(e.extensionName, VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME) == 0;
      });
      if (sync_validation) extensions.push_back(VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
    }
  }

  VkApplicationInfo app{};
  app.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO;
  app.pApplicationName = options.application_name.c_str();
  app.applicationVersion = VK_MAKE_API_VERSION(0, 0, 1, 0);
  app.pEngineName = "hsi";
  app.engineVersion = VK_MAKE_API_VERSION(0, 0, 1, 0);
  app.apiVersion = VK_API_VERSION_1_2;

  // The messenger in pNext also reports during vkCreateInstance / vkDestroyInstance.
  VkDebugUtilsMessengerCreateInfoEXT debug = messenger_info(log_.get());
  const VkValidationFeatureEnableEXT sync_feature = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
  VkValidationFeaturesEXT features{};
  features.sType = VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT;
  features.enabledValidationFeatureCount = 1;
  features.pEnabledValidationFeatures = &sync_feature;
  if (sync_validation) debug.pNext = &features;
  VkInstanceCreateInfo info{};
  info.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO;
  info.pNext = options.validation ? &debug : nullptr;
  info.flags = portability ? VK_INSTANCE_CREATE_ENUMERATE_PORTABILITY_BIT_KHR : 0;
  info.pApplicationInfo = &app;
  info.enabledLayerCount = static_cast<uint32_t>(layers.size());
  info.ppEnabledLayerNames = layers.data();
  info.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();
  const VkResult r = vkCreateInstance(&info, nullptr, &instance_);
  if (r == VK_ERROR_INCOMPATIBLE_DRIVER)
    throw VulkanUnavailable(
        "Vulkan is not available: the loader found no driver (ICD) supporting Vulkan 1.2 (on Debian: "
        "mesa-vulkan-drivers for the lavapipe CPU device)",
        r);
  check(r, "vkCreateInstance");
  volkLoadInstance(instance_);
  if (options.validation) {
    debug.pNext = nullptr;
    check(vkCreateDebugUtilsMessengerEXT(instance_, &debug, nullptr, &messenger_), "vkCreateDebugUtilsMessengerEXT");
  }
  if (options.make_surface) {
    surface_ = options.make_surface(instance_);
    if (!surface_) throw VulkanUnavailable("Vulkan: could not create a surface for the window", VK_ERROR_INITIALIZATION_FAILED);
  }
}

void Context::pick_device(const ContextOptions& options) {
  uint32_t n = 0;
  VkResult r = vkEnumeratePhysicalDevices(instance_, &n, nullptr);
  if (r == VK_ERROR_INITIALIZATION_FAILED) n = 0;
  else check(r, "vkEnumeratePhysicalDevices");
  std::vector<VkPhysicalDevice> devices(n);
  if (n) check(vkEnumeratePhysicalDevices(instance_, &n, devices.data()), "vkEnumeratePhysicalDevices");
  devices.resize(n);

  std::string wanted = options.device_name;
  if (wanted.empty())
    if (const char* env = std::getenv("HSI_VULKAN_DEVICE")) wanted = env;

  std::string seen;
  int best_rank = 1 << 30;
  for (VkPhysicalDevice d : devices) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(d, &p);
    seen += std::string(seen.empty() ? "" : ", ") + p.deviceName + " (Vulkan " + version_string(p.apiVersion) + ")";
    if (p.apiVersion < VK_API_VERSION_1_2) continue;
    if (!wanted.empty() && std::string(p.deviceName).find(wanted) == std::string::npos) continue;
    uint32_t qn = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(d, &qn, nullptr);
    std::vector<VkQueueFamilyProperties> families(qn);
    vkGetPhysicalDeviceQueueFamilyProperties(d, &qn, families.data());
    // A compute queue; one that can also draw first (later passes render offscreen).
    // With a surface: one that computes, draws and presents to it (and the device must
    // have VK_KHR_swapchain).
    auto presents = [&](uint32_t q) {
      if (!surface_) return true;
      VkBool32 ok = VK_FALSE;
      return vkGetPhysicalDeviceSurfaceSupportKHR(d, q, surface_, &ok) == VK_SUCCESS && ok == VK_TRUE;
    };
    if (surface_ && !has_device_extension(d, VK_KHR_SWAPCHAIN_EXTENSION_NAME)) continue;
    int family = -1;
    for (VkQueueFlags want : {VkQueueFlags(VK_QUEUE_COMPUTE_BIT | VK_QUEUE_GRAPHICS_BIT), VkQueueFlags(VK_QUEUE_COMPUTE_BIT)})
      for (uint32_t q = 0; q < qn && family < 0; ++q)
        if ((families[q].queueFlags & want) == want && families[q].queueCount > 0 && (!surface_ || (want & VK_QUEUE_GRAPHICS_BIT)) &&
            presents(q))
          family = static_cast<int>(q);
    if (family < 0) continue;
    const int rank = type_rank(p.deviceType);
    if (rank < best_rank) {
      best_rank = rank;
      physical_ = d;
      queue_family_ = static_cast<uint32_t>(family);
      info_.timestamp_valid_bits = families[static_cast<size_t>(family)].timestampValidBits;
      info_.queue_flags = families[static_cast<size_t>(family)].queueFlags;
      info_.queue_family = static_cast<uint32_t>(family);
    }
  }
  if (!physical_) {
    std::string msg = surface_ ? "Vulkan is not available: no device with Vulkan 1.2, VK_KHR_swapchain and a queue that "
                                 "computes, draws and presents to the window"
                               : "Vulkan is not available: no device with Vulkan 1.2 and a compute queue";
    if (!wanted.empty()) msg += " whose name contains \"" + wanted + "\"";
    msg += seen.empty() ? " (the loader found no devices; on Debian install mesa-vulkan-drivers for lavapipe)"
                        : " among: " + seen;
    throw VulkanUnavailable(msg, VK_ERROR_INITIALIZATION_FAILED);
  }

  VkPhysicalDeviceProperties p;
  vkGetPhysicalDeviceProperties(physical_, &p);
  VkPhysicalDeviceFeatures f;
  vkGetPhysicalDeviceFeatures(physical_, &f);
  info_.name = p.deviceName;
  info_.type = p.deviceType;
  info_.api_version = p.apiVersion;
  info_.driver_version = p.driverVersion;
  info_.vendor_id = p.vendorID;
  info_.float64 = options.want_float64 && f.shaderFloat64;
  for (int i = 0; i < 3; ++i) info_.max_workgroup_count[i] = p.limits.maxComputeWorkGroupCount[i];
  info_.max_workgroup_invocations = p.limits.maxComputeWorkGroupInvocations;
  info_.max_storage_buffer_range = p.limits.maxStorageBufferRange;
  info_.non_coherent_atom_size = std::max<VkDeviceSize>(1, p.limits.nonCoherentAtomSize);
  info_.timestamp_period_ns = p.limits.timestampPeriod;
  if (info_.timestamp_period_ns <= 0) info_.timestamp_valid_bits = 0;
  vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);
}

void Context::create_device(const ContextOptions&) {
  const float priority = 1.0f;
  VkDeviceQueueCreateInfo queue{};
  queue.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO;
  queue.queueFamilyIndex = queue_family_;
  queue.queueCount = 1;
  queue.pQueuePriorities = &priority;

  VkPhysicalDeviceFeatures features{};
  features.shaderFloat64 = info_.float64 ? VK_TRUE : VK_FALSE;

  std::vector<const char*> extensions;
  uint32_t n = 0;
  check(vkEnumerateDeviceExtensionProperties(physical_, nullptr, &n, nullptr), "vkEnumerateDeviceExtensionProperties");
  std::vector<VkExtensionProperties> available(n);
  check(vkEnumerateDeviceExtensionProperties(physical_, nullptr, &n, available.data()),
        "vkEnumerateDeviceExtensionProperties");
  for (const VkExtensionProperties& e : available)
    if (std::strcmp(e.extensionName, "VK_KHR_portability_subset") == 0) extensions.push_back("VK_KHR_portability_subset");
  if (surface_) extensions.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);

  VkDeviceCreateInfo info{};
  info.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO;
  info.queueCreateInfoCount = 1;
  info.pQueueCreateInfos = &queue;
  info.pEnabledFeatures = &features;
  info.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();
  check(vkCreateDevice(physical_, &info, nullptr, &device_), "vkCreateDevice");
  vkGetDeviceQueue(device_, queue_family_, 0, &queue_);

  VkCommandPoolCreateInfo pool{};
  pool.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
  pool.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT | VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pool.queueFamilyIndex = queue_family_;
  check(vkCreateCommandPool(device_, &pool, nullptr, &command_pool_), "vkCreateCommandPool");

  if (info_.timestamp_valid_bits > 0) {
    VkQueryPoolCreateInfo q{};
    q.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO;
    q.queryType = VK_QUERY_TYPE_TIMESTAMP;
    q.queryCount = 2 + kMaxMarks;
    check(vkCreateQueryPool(device_, &q, nullptr, &timestamps_), "vkCreateQueryPool");
  }
}

uint32_t Context::memory_type(uint32_t type_bits, VkMemoryPropertyFlags required,
                              VkMemoryPropertyFlags preferred) const {
  int best = -1, best_score = -1;
  for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
    const VkMemoryPropertyFlags flags = memory_.memoryTypes[i].propertyFlags;
    if (!(type_bits & (1u << i)) || (flags & required) != required) continue;
    const int score = std::popcount(static_cast<uint32_t>(flags & preferred));
    if (score > best_score) {
      best = static_cast<int>(i);
      best_score = score;
    }
  }
  if (best < 0)
    throw VulkanError("Vulkan: no memory type with the required properties (flags " + std::to_string(required) +
                      ") on " + info_.name);
  return static_cast<uint32_t>(best);
}

void Context::submit_and_wait(const std::function<void(VkCommandBuffer)>& record) const {
  VkCommandBufferAllocateInfo alloc{};
  alloc.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
  alloc.commandPool = command_pool_;
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  check(vkAllocateCommandBuffers(device_, &alloc, &cmd), "vkAllocateCommandBuffers");
  struct FreeCommandBuffer {
    VkDevice device;
    VkCommandPool pool;
    VkCommandBuffer cmd;
    ~FreeCommandBuffer() { vkFreeCommandBuffers(device, pool, 1, &cmd); }
  } guard{device_, command_pool_, cmd};

  VkCommandBufferBeginInfo begin{};
  begin.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");
  // A submission made while another is being recorded (an upload) keeps the outer one's marks.
  const uint32_t outer_marks = marks_;
  marks_ = 0;
  if (timestamps_) {
    vkCmdResetQueryPool(cmd, timestamps_, 0, 2 + kMaxMarks);
    vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, timestamps_, 0);
  }
  record(cmd);
  if (timestamps_) vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, timestamps_, 1);
  check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");

  const DeviceHandle<VkFence> fence = make_fence(*this);
  const VkFence raw_fence = fence.get();

  VkSubmitInfo submit{};
  submit.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  check(vkQueueSubmit(queue_, 1, &submit, fence.get()), "vkQueueSubmit");
  check(vkWaitForFences(device_, 1, &raw_fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
  last_device_ms_ = -1;
  last_marks_ms_.clear();
  if (timestamps_) {
    uint64_t ticks[2 + kMaxMarks] = {};
    const uint32_t n = 2 + marks_;
    if (vkGetQueryPoolResults(device_, timestamps_, 0, n, n * sizeof(uint64_t), ticks, sizeof(uint64_t),
                              VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) == VK_SUCCESS) {
      const uint64_t mask = info_.timestamp_valid_bits >= 64 ? ~uint64_t{0} : (uint64_t{1} << info_.timestamp_valid_bits) - 1;
      auto ms = [&](uint64_t t) { return static_cast<double>((t - ticks[0]) & mask) * info_.timestamp_period_ns * 1e-6; };
      last_device_ms_ = ms(ticks[1]);
      for (uint32_t k = 0; k < marks_; ++k) last_marks_ms_.push_back(ms(ticks[2 + k]));
    }
  }
  marks_ = outer_marks;
}

void Context::mark(VkCommandBuffer cmd) const {
  if (!timestamps_ || marks_ >= kMaxMarks) return;
  vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, timestamps_, 2 + marks_);
  ++marks_;
}

void memory_barrier(VkCommandBuffer cmd, VkPipelineStageFlags src_stage, VkAccessFlags src_access,
                    VkPipelineStageFlags dst_stage, VkAccessFlags dst_access) {
  VkMemoryBarrier b{};
  b.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER;
  b.srcAccessMask = src_access;
  b.dstAccessMask = dst_access;
  vkCmdPipelineBarrier(cmd, src_stage, dst_stage, 0, 1, &b, 0, nullptr, 0, nullptr);
}

void image_barrier(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to, VkAccessFlags src_access,
                   VkAccessFlags dst_access, VkPipelineStageFlags src_stage, VkPipelineStageFlags dst_stage,
                   uint32_t first_mip, uint32_t mips) {
  VkImageMemoryBarrier b{};
  b.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER;
  b.srcAccessMask = src_access;
  b.dstAccessMask = dst_access;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, first_mip, mips, 0, 1};
  vkCmdPipelineBarrier(cmd, src_stage, dst_stage, 0, 0, nullptr, 0, nullptr, 1, &b);
}

std::pair<uint32_t, uint32_t> split_dispatch(const Context& context, uint64_t groups) {
  const uint64_t max_x = context.info().max_workgroup_count[0], max_y = context.info().max_workgroup_count[1];
  if (groups == 0) return {0, 0};
  const uint64_t x = std::min<uint64_t>(groups, max_x);
  const uint64_t y = (groups + x - 1) / x;
  if (y > max_y) throw VulkanError("Vulkan: dispatch of " + std::to_string(groups) + " workgroups exceeds the device limits");
  return {static_cast<uint32_t>(x), static_cast<uint32_t>(y)};
}

// --- memory, buffer -----------------------------------------------------------------

DeviceHandle<VkDeviceMemory> allocate_memory(const Context& context, const VkMemoryRequirements& requirements,
                                             VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred,
                                             VkMemoryPropertyFlags* flags) {
  const uint32_t type = context.memory_type(requirements.memoryTypeBits, required, preferred);
  if (flags) *flags = context.memory_properties().memoryTypes[type].propertyFlags;
  VkMemoryAllocateInfo alloc{};
  alloc.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  alloc.allocationSize = requirements.size;
  alloc.memoryTypeIndex = type;
  VkDeviceMemory mem = VK_NULL_HANDLE;
  check(vkAllocateMemory(context.device(), &alloc, nullptr, &mem), "vkAllocateMemory");
  return DeviceHandle<VkDeviceMemory>(context.device(), mem, [](VkDevice d, VkDeviceMemory m) { vkFreeMemory(d, m, nullptr); });
}


Buffer::Buffer(const Context& context, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUse use)
    : context_(&context), size_(size) {
  const VkDevice dev = context.device();
  VkBufferCreateInfo info{};
  info.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
  info.size = std::max<VkDeviceSize>(size, 16);  // a zero-sized buffer is invalid
  info.usage = usage;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkBuffer raw = VK_NULL_HANDLE;
  check(vkCreateBuffer(dev, &info, nullptr, &raw), "vkCreateBuffer");
  buffer_ = DeviceHandle<VkBuffer>(dev, raw, [](VkDevice d, VkBuffer b) { vkDestroyBuffer(d, b, nullptr); });

  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(dev, raw, &req);
  VkMemoryPropertyFlags required = 0, preferred = 0;
  switch (use) {
    case MemoryUse::kDeviceLocal: required = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT; break;
    case MemoryUse::kUpload:
      required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
      preferred = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
      break;
    case MemoryUse::kReadback:
      required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT;
      preferred = VK_MEMORY_PROPERTY_HOST_CACHED_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
      break;
  }
  VkMemoryPropertyFlags flags = 0;
  memory_ = allocate_memory(context, req, required, preferred, &flags);
  flags_ = flags;
  const VkDeviceMemory mem = memory_.get();
  check(vkBindBufferMemory(dev, raw, mem, 0), "vkBindBufferMemory");
  // Device-local memory that happens to be host-visible (CPU devices, integrated
  // GPUs, resizable BAR) is mapped too, so callers can skip staging copies.
  if (flags & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT) {
    check(vkMapMemory(dev, mem, 0, VK_WHOLE_SIZE, 0, &mapped_), "vkMapMemory");
    coherent_ = (flags & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT) != 0;
  }
}

Buffer::Buffer(Buffer&& o) noexcept
    : context_(o.context_),
      memory_(std::move(o.memory_)),
      buffer_(std::move(o.buffer_)),
      mapped_(std::exchange(o.mapped_, nullptr)),
      coherent_(o.coherent_),
      flags_(o.flags_),
      size_(std::exchange(o.size_, 0)) {}

Buffer& Buffer::operator=(Buffer&& o) noexcept {
  if (this != &o) {
    release();
    context_ = o.context_;
    memory_ = std::move(o.memory_);
    buffer_ = std::move(o.buffer_);
    mapped_ = std::exchange(o.mapped_, nullptr);
    coherent_ = o.coherent_;
    flags_ = o.flags_;
    size_ = std::exchange(o.size_, 0);
  }
  return *this;
}

void Buffer::release() {
  if (mapped_ && memory_) vkUnmapMemory(context_->device(), memory_.get());
  mapped_ = nullptr;
  buffer_.reset();
  memory_.reset();
  size_ = 0;
}

void Buffer::check_range(VkDeviceSize bytes, VkDeviceSize offset, const char* op) const {
  if (!mapped_) throw VulkanError(std::string("Buffer::") + op + ": the buffer is not host-visible");
  if (offset > size_ || bytes > size_ - offset)
    throw VulkanError(std::string("Buffer::") + op + ": range [" + std::to_string(offset) + ", " +
                      std::to_string(offset + bytes) + ") exceeds the buffer's " + std::to_string(size_) + " bytes");
}

namespace {
// From the atom-aligned offset to the end of the allocation (always a valid range).
VkMappedMemoryRange atom_range(const Context& c, VkDeviceMemory memory, VkDeviceSize offset) {
  const VkDeviceSize atom = c.info().non_coherent_atom_size;
  VkMappedMemoryRange r{};
  r.sType = VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE;
  r.memory = memory;
  r.offset = offset / atom * atom;
  r.size = VK_WHOLE_SIZE;
  return r;
}
}  // namespace

void Buffer::write(const void* data, VkDeviceSize bytes, VkDeviceSize offset) {
  check_range(bytes, offset, "write");
  if (bytes == 0) return;
  std::memcpy(static_cast<std::byte*>(mapped_) + offset, data, static_cast<size_t>(bytes));
  if (!coherent_) {
    const VkMappedMemoryRange r = atom_range(*context_, memory_.get(), offset);
    check(vkFlushMappedMemoryRanges(context_->device(), 1, &r), "vkFlushMappedMemoryRanges");
  }
}

void Buffer::read(void* out, VkDeviceSize bytes, VkDeviceSize offset) const {
  check_range(bytes, offset, "read");
  if (bytes == 0) return;
  if (!coherent_) {
    const VkMappedMemoryRange r = atom_range(*context_, memory_.get(), offset);
    check(vkInvalidateMappedMemoryRanges(context_->device(), 1, &r), "vkInvalidateMappedMemoryRanges");
  }
  std::memcpy(out, static_cast<const std::byte*>(mapped_) + offset, static_cast<size_t>(bytes));
}

}  // namespace hsi::compute
