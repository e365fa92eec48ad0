// Gyroflow's gyro log, `.gcsv` (docs/formats/gcsv.md): a text sidecar of a video that a camera
// or a logger writes. A first line `GYROFLOW IMU LOG` or `CAMERA IMU LOG`, then `key,value`
// lines (version, id, orientation, tscale, gscale, and optional ones such as
// frame_readout_time in ms and frame_readout_direction), then a column header starting with
// `t,gx,gy,gz` and the samples: time t x tscale in seconds, rate g x gscale in rad/s about the
// log's own axes (which the orientation string names in Gyroflow's convention; rsd does not
// interpret it: rsd-diagnose --imu-axes search finds the axes from the pictures).
//
// Errors throw std::runtime_error naming the file and line (and the key or column): a first line
// that is not one of the two, a missing or non-positive tscale or gscale, a readout time outside
// 0..1000 ms, a column header that does not start
// with t,gx,gy,gz, a field that is not a number, a time that goes back, a readout direction
// other than 0..3, fewer than two samples.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "dsp/observation/observation_model.hpp"

namespace rsd::formats {

struct GcsvLog {
  std::string version, id, orientation, vendor, videofilename, lensprofile;
  std::optional<double> frame_readout_s;       // frame_readout_time, converted from ms
  // frame_readout_direction: 0 top to bottom, 1 bottom to top, 2 left to right, 3 right to left.
  std::optional<int> readout_direction;
  std::vector<dsp::GyroSample> gyro;           // s and rad/s, the log's axes
};

GcsvLog read_gcsv(const std::string& path);

}  // namespace rsd::formats
