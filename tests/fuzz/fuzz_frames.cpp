// libFuzzer harness: interpolated frames files (.hsif, hsi::decode_frames). Any
// input must decode or be refused with hsi::InputError; a file that decodes must
// encode back to the same bytes (a version 1 file: to the same file in the current
// version, which then round-trips itself).
#include <cstdint>
#include <cstdlib>
#include <string>

#include "hsi/domain.h"
#include "hsi/frames_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  hsi::FrameFile file;
  try {
    file = hsi::decode_frames(bytes, "fuzz.hsif");
  } catch (const hsi::InputError&) {
    return 0;
  }
  const std::string again = hsi::encode_frames(file);
  if (bytes[4] == static_cast<char>(hsi::kFramesVersion)) {
    if (again != bytes) std::abort();
  } else {  // version 1: the same layout but for the version and the stop codes in flag bits 8..15
    if (again.size() != bytes.size() || hsi::encode_frames(hsi::decode_frames(again, "fuzz.hsif")) != again) std::abort();
  }
  return 0;
}
