// rsd-calibration/1 files (formats/calibration_v1.hpp).
#include "formats/calibration_v1.hpp"
#include "formats/yaml_map.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    rsd::formats::read_calibration(rsd::fuzz::write_file("cal.yaml", data, size));
  } catch (const rsd::formats::ConfigError&) {
  }
  return 0;
}
