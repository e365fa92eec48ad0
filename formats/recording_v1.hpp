// Observation recordings on disk: docs/formats/recording-v1.md, exactly.
//
// write_recording() writes the directory; read_recording() reads one back, checking every
// header, field and reference, and throws RecordingError naming the file, line and column
// of the first problem ("frames.csv:12:7: field 't': 'abc' is not a number").
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "dsp/observation/recording.hpp"
#include "dsp/sim/calibration_target.hpp"

namespace rsd::formats {

struct RecordingError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void write_recording(const std::string& dir, const dsp::Recording& rec);
// Throws RecordingError for an images recording (its observations are still to be made:
// read_images_recording).
dsp::Recording read_recording(const std::string& dir);

// An images recording (observations.kind: images): the header, frames and motion, and the
// pictures from which a tool makes its own observations. `rec.kind` is what the pictures make:
// matches (gyro motion, by tracking features) or landmarks (trajectory motion, by detecting
// `target`, whose corners are rec.points); rec.matches and rec.observations are empty.
struct ImagesRecording {
  dsp::Recording rec;
  // The picture of each of rec.frames (same order): a file (images.csv, path resolved against
  // the directory) or, with a video, the frame's index among the decoded frames.
  std::vector<std::string> files;
  std::string video;  // observations.video, resolved; empty with images.csv
  std::optional<dsp::TargetSpec> target;
};

// Whether dir's recording.yaml says observations.kind: images (false if it cannot be read).
bool is_images_recording(const std::string& dir);
ImagesRecording read_images_recording(const std::string& dir);
// Writes the header, frames, motion and images.csv. `files` and `video` are paths as the reader
// gives them (usable from the working directory); the files hold them relative to dir. The
// pictures themselves are the caller's to write.
void write_images_recording(const std::string& dir, const ImagesRecording& r);
// A pose file in trajectory.csv's format (t,x,y,z,qw,qx,qy,qz), checked the same way.
std::vector<dsp::PoseSample> read_trajectory_csv(const std::string& path);

}  // namespace rsd::formats
