// See rendering.h. HSI_RUNTIME_VULKAN is set by runtime/CMakeLists.txt when compute/ is built.
#include "hsi/runtime/rendering.h"

#include "built.h"

namespace hsi::runtime {

std::string rendering_unavailable_reason() {
#if HSI_RUNTIME_VULKAN
  return "";
#else
  return built::kNoVulkan;
#endif
}

}  // namespace hsi::runtime
