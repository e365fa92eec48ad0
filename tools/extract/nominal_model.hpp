// rsd-extract's nominal model: what the user says the camera is (options, --nominal,
// --intrinsics, the log's metadata, in that precedence), with a note of where each value came
// from; and the frames whose readout the motion covers under it.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

#include "dsp/observation/recording.hpp"
#include "formats/motion_log.hpp"
#include "tools/extract/extract_options.hpp"

namespace rsd::tools::extract {

// What the user says the camera is, with where each value came from (printed on stderr).
struct Nominal {
  dsp::NominalModel model;
  bool have_camera = false;
  std::optional<Eigen::Matrix3d> imu_to_camera;
  std::vector<std::string> notes;
};

// The nominal model for the log `s` (its first frame's size, median frame interval and timing
// metadata) with the files and options of `o` over it. Throws UsageError when no intrinsics are
// given or they disagree with the frames' size.
Nominal nominal_model(const Options& o, const formats::MotionLog& s);

// Whether the motion (gyro, or else poses) covers each frame's readout under `n`.
std::vector<bool> covered(const formats::MotionLog& s, const Nominal& n, bool by_gyro);

// The frames whose readout the motion covers, as the recording's frames (numbered by their place
// in the input); none is an error naming `input`.
std::vector<dsp::FrameStamp> covered_frames(const formats::MotionLog& s, const std::vector<bool>& ok, const std::string& input);

}  // namespace rsd::tools::extract
