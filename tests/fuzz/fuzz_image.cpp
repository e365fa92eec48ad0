// PNG and PGM pictures (formats/image_file.hpp): the first byte picks the file name's suffix
// (the PGM reader is chosen by it as well as by the magic), the rest is the file.
#include <stdexcept>

#include "formats/image_file.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  try {
    rsd::formats::read_image(rsd::fuzz::write_file(data[0] % 2 ? "frame.pgm" : "frame.png", data + 1, size - 1));
  } catch (const std::runtime_error&) {  // the reader's documented error, naming the file
  }
  return 0;
}
