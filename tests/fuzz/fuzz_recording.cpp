// rsd-recording/1 directories (formats/recording_v1.hpp): recording.yaml and its CSV files.
// The input's parts ("%%" lines between them) become the files below, in that order; a part
// not given is an empty file.
#include <array>

#include "formats/recording_v1.hpp"
#include "tests/fuzz/fuzz_input.hpp"

namespace {
constexpr std::array<const char*, 7> kFiles = {"recording.yaml", "frames.csv",  "observations.csv", "points.csv",
                                               "matches.csv",    "gyro.csv",    "trajectory.csv"};
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto parts = rsd::fuzz::split_parts(data, size);
  for (size_t i = 0; i < kFiles.size(); ++i) rsd::fuzz::write_file(kFiles[i], i < parts.size() ? parts[i] : "");
  try {
    rsd::formats::read_recording(rsd::fuzz::scratch_dir());
  } catch (const rsd::formats::RecordingError&) {
  }
  return 0;
}
