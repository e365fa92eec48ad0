// rsd-recording/1 directories (formats/recording_v1.hpp): recording.yaml and its CSV files.
// The input's parts ("%%" lines between them) become the files below, in that order; a part
// not given is an empty file.

#include <string>
#include <vector>

#include "formats/recording_v1.hpp"
#include "tests/fuzz/fuzz_input.hpp"

namespace {
const std::vector<std::string> kFiles = {"recording.yaml", "frames.csv", "observations.csv", "points.csv",
                                         "matches.csv", "gyro.csv", "trajectory.csv"};
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string dir = rsd::fuzz::write_parts(data, size, kFiles);
  try {
    rsd::formats::read_recording(dir);
  } catch (const rsd::formats::RecordingError&) {
  }
  return 0;
}
