// What an LCM log of a rig says about its motion and its frames: every raw frame's capture
// time, size and row timing (the bot_core.image_t codec's rules), the gyro (rsd.velocity_t)
// and the poses (bot_core.pose_t), in time order. rsd-extract's first pass; anything that
// turns a log into an observation recording starts here.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dsp/geometry/row_timing.hpp"
#include "dsp/observation/recording.hpp"

namespace rsd::formats {

struct LogFrame {
  double t;                              // first row's capture time, s
  std::optional<double> line_delay_s;    // from the frame's metadata
  std::optional<dsp::Readout> readout;   // from the frame's metadata
  int width, height;
};

struct MotionLog {
  std::vector<LogFrame> frames;
  std::vector<dsp::GyroSample> gyro;
  std::optional<int> gyro_frame;  // rsd::velocity_t::FRAME_*, the one all samples share
  std::vector<dsp::PoseSample> poses;
  std::map<std::string, int> channels;  // every channel with its event count (for errors)
  int events = 0;
  int malformed = 0;  // velocity or pose messages that did not decode or made no sense
  // Velocity messages that carry translation (has_linear, a finite linear velocity), and the
  // median and largest speed among them (m/s): a rotation-only matches recording of such a
  // log sees parallax wherever the scene is near.
  int with_translation = 0;
  double median_speed_m_s = 0, max_speed_m_s = 0;
};

struct MotionLogChannels {
  std::string image = "RSD_RAW", velocity = "RSD_VELOCITY", pose = "RSD_POSE";
};

// Throws std::runtime_error naming the log, the event and its channel for a frame that does
// not decode, a frame size that changes, or velocity axes that change within the log.
// `progress(read, size)`, if given, after every frame and at the end: the bytes read so far and
// the log's size (ten minutes of 1080p are 37 GB, a minute's reading).
MotionLog read_motion_log(const std::string& path, const MotionLogChannels& channels,
                          const std::function<void(uint64_t read, uint64_t size)>& progress = {});

// "RSD_RAW (20), RSD_VELOCITY (400)", for messages.
std::string channel_list(const MotionLog& log);

}  // namespace rsd::formats
