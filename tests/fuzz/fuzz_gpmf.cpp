// GoPro's GPMF payloads (formats/gpmf.hpp): the input is one payload, as the MP4's metadata track
// holds it. Seeds: GoPro's four sample payloads (tests/data/real/gpmf).
#include <stdexcept>

#include "formats/gpmf.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    rsd::formats::read_gpmf_gyro(data, size, "payload");
  } catch (const std::runtime_error&) {  // the reader's documented error, naming the byte and key
  }
  return 0;
}
