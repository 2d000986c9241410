// How a scene's texture is sampled where it is drawn: bilinear (smooth, the default) or
// nearest (each texel a crisp square: pixel art drawn large). One value for the scene
// file ("texture_filter"), the CPU drawings (draw/), the Vulkan renderers (compute/'s
// sampler, both rasterizers), the viewer and the glTF export's sampler.
#pragma once

#include <optional>
#include <string_view>

namespace hsi {

enum class TextureFilter {
  Linear,   // bilinear within a mip level, trilinear across levels
  Nearest,  // the nearest texel of the nearest mip level
};

inline const char* texture_filter_name(TextureFilter f) { return f == TextureFilter::Nearest ? "nearest" : "linear"; }

// "linear" or "nearest"; anything else: nullopt.
inline std::optional<TextureFilter> parse_texture_filter(std::string_view s) {
  if (s == "linear") return TextureFilter::Linear;
  if (s == "nearest") return TextureFilter::Nearest;
  return std::nullopt;
}

}  // namespace hsi
