// Whether this build renders (the Vulkan offscreen renderer of compute/): asked by
// front-ends that offer rendering (hsi render, the C API's hsi_render_available), so
// that the reason is worded once.
#pragma once

#include <string>

namespace hsi::runtime {

// Empty where compute/ is built (a Vulkan device is still needed at run time);
// otherwise why rendering is not available.
std::string rendering_unavailable_reason();

}  // namespace hsi::runtime
