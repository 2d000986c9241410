// libFuzzer harness: PNG sprite import (hsi::import_png_alpha from memory) and the
// texture check used by exports (hsi::check_png_texture). Any input must import, or
// be refused with hsi::InputError naming the problem; anything else is a finding.
#include <cstdint>
#include <cstdlib>
#include <span>

#include "hsi/png_import.h"

namespace {
// Images above this many pixels are valid but slow to trace; the corpus tests cover
// the size limits, the fuzzer spends its time on decoding and small contours.
constexpr uint64_t kMaxFuzzPixels = 1u << 18;

uint32_t be32(const uint8_t* p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | uint32_t(p[3]);
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // IHDR is the first chunk: width and height at bytes 16..23.
  if (size >= 24 && uint64_t(be32(data + 16)) * uint64_t(be32(data + 20)) > kMaxFuzzPixels) return 0;
  const std::span<const unsigned char> bytes(data, size);
  try {
    const hsi::PngShape s = hsi::import_png_alpha(bytes, "fuzz.png");
    if (s.shape.outer.size() < 3 || s.width <= 0 || s.height <= 0) std::abort();  // accepted but invalid
    hsi::validate(s.shape);  // must hold for anything accepted
  } catch (const hsi::InputError&) {
  }
  try {
    const auto wh = hsi::check_png_texture(bytes, "fuzz.png");
    if (wh[0] <= 0 || wh[1] <= 0) std::abort();
  } catch (const hsi::InputError&) {
  }
  return 0;
}
