// Observation recordings on disk: ../shared/formats/recording-v1.md, exactly.
//
// write_recording() writes the directory; read_recording() reads one back, checking every
// header, field and reference, and throws RecordingError naming the file, line and column
// of the first problem ("frames.csv:12:7: field 't': 'abc' is not a number").
#pragma once

#include <stdexcept>
#include <string>

#include "dsp/recording.hpp"

namespace rsd::tools {

struct RecordingError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void write_recording(const std::string& dir, const dsp::Recording& rec);
dsp::Recording read_recording(const std::string& dir);

}  // namespace rsd::tools
