// Images recordings (formats/recording_v1.hpp, observations.kind: images): recording.yaml, its
// CSV files and a picture. The input's parts ("%%" lines between them) become the files below,
// in that order; a part not given is an empty file.

#include <string>
#include <vector>

#include "formats/recording_v1.hpp"
#include "tests/fuzz/fuzz_input.hpp"

namespace {
const std::vector<std::string> kFiles = {"recording.yaml", "frames.csv", "images.csv", "points.csv",
                                         "trajectory.csv", "gyro.csv", "frames/000000.png"};
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string dir = rsd::fuzz::write_parts(data, size, kFiles);
  try {
    rsd::formats::read_images_recording(dir);
  } catch (const rsd::formats::RecordingError&) {
  }
  return 0;
}
