// A GoPro MP4's gyro and frame times (docs/formats/gpmf.md): the metadata track (codec tag
// `gpmd`) demuxed with libavformat, each payload read with formats/gpmf, and its samples spread
// evenly over the payload's time span on the MP4's clock, as GoPro documents; the video track's
// presentation times, in order, are the frames' times on the same clock.
//
// Errors throw std::runtime_error naming the file (and the payload, by index and time): a file
// libavformat cannot open, no video or no GPMF track, a payload formats/gpmf refuses, a payload
// without a gyro stream, or one whose gyro stream changes its axis order.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace rsd::formats {

struct GpmfVideo {
  int width = 0, height = 0;
  std::vector<double> frame_t_s;  // each video frame's presentation time, s, in display order
  // The gyro: times on the MP4's clock (s), rates (rad/s) in the stream's axis order (`orin`).
  std::vector<double> gyro_t_s;
  std::vector<Eigen::Vector3d> gyro_rad_s;
  std::string orin;    // "" when the camera writes none (HERO5-7: documented, docs/formats/gpmf.md)
  std::string device;  // DVNM of the gyro's device, e.g. "Camera", "Hero6 Black"
  std::string firmware;  // the MP4's firmware tag, e.g. "HD5.02.02.00.00" ("" when absent): the model
  int payloads = 0;
};

GpmfVideo read_gpmf_video(const std::string& path);

}  // namespace rsd::formats
