// libFuzzer harness: scene JSON (hsi::parse_scene). Any input must either load or be
// refused with hsi::InputError; anything else (a crash, a sanitizer report, another
// exception escaping) is a finding. A scene that loads must survive a round trip
// through scene_to_json and load again to the same shape.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "hsi/scene_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  hsi::Scene scene;
  try {
    scene = hsi::parse_scene(text, "/nonexistent", "fuzz.json");
  } catch (const hsi::InputError&) {
    return 0;  // refused with a message: the expected outcome for most inputs
  }
  // Accepted: what we write we must read back.
  const hsi::Scene again = hsi::parse_scene(hsi::scene_to_json(scene), "/nonexistent", "roundtrip.json");
  if (again.shape.outer != scene.shape.outer || again.shape.holes != scene.shape.holes ||
      again.keyframes.size() != scene.keyframes.size() || again.handles != scene.handles)
    std::abort();
  return 0;
}
