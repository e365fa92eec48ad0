// Writes a simulated camera run as a standard LCM log (lcm-logplayer, lcm-spy and rsd's
// replay read it): raw frames as bot_core.image_t with per-row timing in the metadata, and
// the camera's true velocity as rsd.velocity_t — the messages the daemon consumes — and
// optionally the tracked body's pose as bot_core.pose_t (motion capture, for rsd-extract).
#pragma once

#include <functional>
#include <string>

#include "dsp/geometry/camera_motion.hpp"
#include "dsp/core/image.hpp"
#include "dsp/observation/recording.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::tools {

inline constexpr const char* kRawChannel = "RSD_RAW";
inline constexpr const char* kVelocityChannel = "RSD_VELOCITY";
inline constexpr const char* kPoseChannel = "RSD_POSE";

struct SimLogSpec {
  std::string path;
  dsp::RowTiming timing;     // true per-row timing of the simulated sensor
  double velocity_rate_hz = 200;
};

// Body poses (world-from-body, motion clock) written as bot_core.pose_t on `channel`, utime =
// the sample's time, like motion capture; none: no pose channel. rotation_rate and vel are the
// body's rates in body axes (libbot2's convention), from the neighbouring samples.
struct SimPoseLog {
  std::vector<dsp::PoseSample> poses;
  std::string channel = kPoseChannel;
};

// Frame k (first row read at frame_times[k], seconds) is produced by `render(k, view)`.
// `motion` maps world to camera at a time in seconds; the log's clock is those seconds as
// microseconds. Throws std::runtime_error naming the file on I/O failure.
void write_sim_lcm_log(const SimLogSpec& spec, const std::vector<double>& frame_times, int width, int height,
                       dsp::PixelFormat format, const std::function<void(size_t, const dsp::ImageView&)>& render,
                       const dsp::CameraMotion& motion, const SimPoseLog& poses = {});

// The camera's own angular and linear velocity in its axes at time t (central differences
// of the world-to-camera motion).
void camera_velocity(const dsp::CameraMotion& motion, double t, Eigen::Vector3d& w, Eigen::Vector3d& v);

}  // namespace rsd::tools
