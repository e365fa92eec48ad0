// rsd-extract's video inputs: a video whose gyro comes with it (a GoPro MP4's GPMF track, a
// phone logger's text files, gyroflow's .gcsv sidecar) written as an images recording whose
// pictures stay in the video (observations.video), for rsd-diagnose and rsd --replay.
#pragma once

#include <string>

#include "tools/extract/extract_options.hpp"

namespace rsd::tools::extract {

// An MP4 (ISO base media file: "ftyp" at byte 4).
bool looks_like_mp4(const std::string& path);

// rsd-extract CLIP.mp4 OUT: a GoPro clip (its GPMF gyro) as an images recording.
int run_on_gopro_clip(const Options& o);

// rsd-extract VIDEO OUT --frame-times F --gyro-csv G: a phone logger's video with its frames' times
// and its gyro as text (formats/sensor_csv.hpp); video frame k is line first_frame_index + k of F.
int run_on_video_with_csv(const Options& o);

// rsd-extract VIDEO OUT --gcsv LOG: a video with gyroflow's sidecar gyro log (formats/gcsv.hpp).
// The log's times count from the video's first frame on the same clock (as gyroflow's format
// asks of a camera); rsd-diagnose's time_offset measures what they do not. Its readout time and
// direction are the nominal timing unless options or --nominal say otherwise.
int run_on_video_with_gcsv(const Options& o);

}  // namespace rsd::tools::extract
