// What this build has, and the reasons worded once for every message of runtime/
// (private). HSI_RUNTIME_CUDA / HSI_RUNTIME_VULKAN come from runtime/CMakeLists.txt.
#pragma once

namespace hsi::runtime::built {

inline constexpr const char* kNoCuda = "this hsi was built without CUDA (HSI_WITH_CUDA=OFF or no nvcc)";
inline constexpr const char* kNoVulkan = "this hsi was built without Vulkan (HSI_WITH_VULKAN=OFF or no Vulkan SDK)";

}  // namespace hsi::runtime::built
