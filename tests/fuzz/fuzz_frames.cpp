// libFuzzer harness: interpolated frames files (.hsif, hsi::decode_frames). Any
// input must decode or be refused with hsi::InputError; a file that decodes must
// encode back to the same bytes.
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
  if (hsi::encode_frames(file) != bytes) std::abort();
  return 0;
}
