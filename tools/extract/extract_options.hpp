// rsd-extract's command line as one value: what the input is, where the nominal model comes
// from, and how features are tracked (tools/rsd_extract.cpp parses it; see docs/extract.md).
#pragma once

#include <optional>
#include <string>

#include "dsp/features/feature_tracks.hpp"
#include "tools/common/picture_observations.hpp"

namespace rsd::tools::extract {

struct Options {
  std::string log, out, nominal, intrinsics, intrinsics_camera, kind = "auto", target;
  std::string image_channel = "RSD_RAW", velocity_channel = "RSD_VELOCITY", pose_channel = "RSD_POSE";
  bool global_shutter = false;
  bool images = false;  // write an images recording (the pictures) instead of observations
  std::optional<double> line_delay_s, frame_rate_hz, time_offset_s, noise_px;
  std::string readout, imu_to_camera, lever_arm;
  // A video with its frames' times and gyro as text (a phone logger's files).
  std::string frame_times, gyro_csv, gyro_columns = "t,wx,wy,wz", time_unit = "s";
  long first_frame_index = 0;
  std::string gcsv;  // a video with gyroflow's .gcsv sidecar log
  dsp::TrackOptions track;
  int track_pairs = static_cast<int>(kTrackedPairs);  // frame pairs tracked at most (0: all)
};

}  // namespace rsd::tools::extract
