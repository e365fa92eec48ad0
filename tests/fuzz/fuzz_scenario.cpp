// rsd-sim scenario files (formats/scenario_file.hpp).
#include "formats/scenario_file.hpp"
#include "formats/yaml_map.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    rsd::formats::load_scenario(rsd::fuzz::write_file("scenario.yaml", data, size));
  } catch (const rsd::formats::ConfigError&) {
  }
  return 0;
}
