// Gyroflow's .gcsv gyro logs (formats/gcsv.hpp): the input is the log. Seeds: a hand-made log
// with every optional key, and the phone recording's gyro as tests/tools/phone_gcsv.sh writes it.
#include <stdexcept>

#include "formats/gcsv.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    rsd::formats::read_gcsv(rsd::fuzz::write_file("log.gcsv", data, size));
  } catch (const std::runtime_error&) {  // the reader's documented error, naming file, line and key
  }
  return 0;
}
