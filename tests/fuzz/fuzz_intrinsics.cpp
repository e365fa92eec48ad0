// Kalibr camchain and ROS camera_info files (formats/intrinsics_file.hpp), cam0 and a named one.
#include "formats/intrinsics_file.hpp"
#include "formats/yaml_map.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = rsd::fuzz::write_file("camchain.yaml", data, size);
  for (const char* camera : {"", "cam1"}) {
    try {
      rsd::formats::load_intrinsics(path, camera);
    } catch (const rsd::formats::ConfigError&) {
    }
  }
  return 0;
}
