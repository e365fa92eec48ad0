// Observation recordings on disk: docs/formats/recording-v1.md, exactly.
//
// write_recording() writes the directory; read_recording() reads one back, checking every
// header, field and reference, and throws RecordingError naming the file, line and column
// of the first problem ("frames.csv:12:7: field 't': 'abc' is not a number").
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "dsp/observation/recording.hpp"

namespace rsd::formats {

struct RecordingError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void write_recording(const std::string& dir, const dsp::Recording& rec);
dsp::Recording read_recording(const std::string& dir);
// A pose file in trajectory.csv's format (t,x,y,z,qw,qx,qy,qz), checked the same way.
std::vector<dsp::PoseSample> read_trajectory_csv(const std::string& path);

}  // namespace rsd::formats
