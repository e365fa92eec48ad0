// gyroflow's lens profiles: the JSON files of gyroflow's lens profile database and its lens
// calibrator (docs/formats/gyroflow-lens-profile.md). rsd reads the lens and the rolling
// shutter's readout from them:
//   calib_dimension {w, h}             the resolution the lens was calibrated at
//   fisheye_params.camera_matrix       K at that resolution, [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]
//   fisheye_params.distortion_coeffs   [k1, k2, k3, k4] of OpenCV's fisheye model: rsd's pinhole-equi
//   frame_readout_time                 the frame's readout in milliseconds, when measured (or null)
//   frame_readout_direction            TopToBottom (the default) or BottomToTop
// and refuses, naming the key, what it cannot represent: another lens model (use_opencv_standard,
// distortion_model other than opencv_fisheye), a stretched input (input_horizontal_stretch or
// input_vertical_stretch other than 1), a readout across the columns. Every other key (names,
// notes, gyroflow's own settings) is left alone.
#pragma once

#include <optional>
#include <string>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::formats {

struct GyroflowProfile {
  std::string name;                        // the profile's `name`, or the file's name
  dsp::CameraModel cam;                    // at calib_dimension
  std::optional<double> frame_readout_s;   // frame_readout_time, in seconds
  dsp::Readout readout = dsp::Readout::TopToBottom;
};

// Throws ConfigError naming the file, line and key.
GyroflowProfile read_gyroflow_profile(const std::string& file);

// The profile's camera at the resolution width x height of the same sensor mode (the same field
// of view, scaled): refused (ConfigError naming calib_dimension) when the aspect ratio differs by
// more than 1 %, which is another crop of the sensor and needs its own profile.
dsp::CameraModel profile_camera_at(const GyroflowProfile& p, const std::string& file, int width, int height);

}  // namespace rsd::formats
