// rsd's configuration file (daemon::load_config): every key, driver section and file it names.
#include "daemon/config.hpp"
#include "formats/recording_v1.hpp"
#include "formats/yaml_map.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    rsd::daemon::load_config(rsd::fuzz::write_file("rsd.yaml", data, size));
  } catch (const rsd::formats::ConfigError&) {
  } catch (const rsd::formats::RecordingError&) {  // a recording driver's directory
  }
  return 0;
}
