// A video file's frame times: each video frame's presentation time on the container's clock, in
// display order, demuxed with libavformat (no decoding). What a video with a sidecar gyro log
// (a .gcsv) is stamped with, the log's times being on the same clock from the video's start.
//
// Errors throw std::runtime_error naming the file: one libavformat cannot open, no video
// stream, a frame without a time stamp.
#pragma once

#include <string>
#include <vector>

namespace rsd::formats {

std::vector<double> read_video_frame_times(const std::string& path);

}  // namespace rsd::formats
