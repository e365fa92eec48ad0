// A phone or logger's gyro columns and frame times (formats/sensor_csv.hpp): the input's first
// part is the column spec, the second the gyro file, the third the frame times ("%%" lines apart).
// Seeds: the phone recording's files' first lines (tests/data/real/phone-cc9) and hand-made ones.
#include <stdexcept>
#include <string>

#include "formats/sensor_csv.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string dir = rsd::fuzz::write_parts(data, size, {"columns", "gyro.csv", "frames.txt"});
  const auto parts = rsd::fuzz::split_parts(data, size);
  rsd::formats::GyroColumns columns;
  try {
    columns = rsd::formats::parse_gyro_columns(parts.empty() ? std::string() : std::string(parts[0]));
  } catch (const std::invalid_argument&) {  // the spec's documented error, naming the column
  }
  try {
    rsd::formats::read_gyro_csv(dir + "/gyro.csv", columns, 1e-3);
  } catch (const std::runtime_error&) {  // the reader's documented error, naming file, line and column
  }
  try {
    rsd::formats::read_frame_times(dir + "/frames.txt", 1e-9);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
