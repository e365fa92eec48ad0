// Images recordings (formats/recording_v1.hpp, observations.kind: images): recording.yaml, its
// CSV files and a picture. The input's parts ("%%" lines between them) become the files below,
// in that order; a part not given is an empty file.
#include <array>
#include <filesystem>

#include "formats/recording_v1.hpp"
#include "tests/fuzz/fuzz_input.hpp"

namespace {
constexpr std::array<const char*, 7> kFiles = {"recording.yaml", "frames.csv", "images.csv",        "points.csv",
                                               "trajectory.csv", "gyro.csv",   "frames/000000.png"};
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool made = std::filesystem::create_directories(rsd::fuzz::scratch_dir() + "/frames") || true;
  (void)made;
  const auto parts = rsd::fuzz::split_parts(data, size);
  for (size_t i = 0; i < kFiles.size(); ++i) rsd::fuzz::write_file(kFiles[i], i < parts.size() ? parts[i] : "");
  try {
    rsd::formats::read_images_recording(rsd::fuzz::scratch_dir());
  } catch (const rsd::formats::RecordingError&) {
  }
  return 0;
}
