// Writes a simulated camera run as a standard LCM log (lcm-logplayer, lcm-spy and rsd's
// replay read it): raw frames as bot_core.image_t with per-row timing in the metadata, and
// the camera's true velocity as rsd.velocity_t — the messages the daemon consumes.
#pragma once

#include <functional>
#include <string>

#include "dsp/camera_motion.hpp"
#include "dsp/image.hpp"
#include "dsp/row_timing.hpp"

namespace rsd::tools {

inline constexpr const char* kRawChannel = "RSD_RAW";
inline constexpr const char* kVelocityChannel = "RSD_VELOCITY";

struct SimLogSpec {
  std::string path;
  dsp::RowTiming timing;     // true per-row timing of the simulated sensor
  double velocity_rate_hz = 200;
};

// Frame k (first row read at frame_times[k], seconds) is produced by `render(k, view)`.
// `motion` maps world to camera at a time in seconds; the log's clock is those seconds as
// microseconds. Throws std::runtime_error naming the file on I/O failure.
void write_sim_lcm_log(const SimLogSpec& spec, const std::vector<double>& frame_times, int width, int height,
                       dsp::PixelFormat format, const std::function<void(size_t, const dsp::ImageView&)>& render,
                       const dsp::CameraMotion& motion);

// The camera's own angular and linear velocity in its axes at time t (central differences
// of the world-to-camera motion).
void camera_velocity(const dsp::CameraMotion& motion, double t, Eigen::Vector3d& w, Eigen::Vector3d& v);

}  // namespace rsd::tools
