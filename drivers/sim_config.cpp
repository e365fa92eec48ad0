// source.sim: the built-in simulated camera's section, read and printed by one visit.
#include <cmath>

#include "drivers/sim_source.hpp"
#include "dsp/core/input_limits.hpp"

namespace rsd::drivers {

void visit_config(formats::ConfigSection& c, SimSourceConfig& s) {
  int w = s.camera.width, h = s.camera.height;
  c.value("width", w);
  c.value("height", h);
  c.check(w >= 16 && h >= 16 && w <= dsp::limits::kMaxSide && h <= dsp::limits::kMaxSide, "width",
          "and height must be 16.." + std::to_string(dsp::limits::kMaxSide) + " pixels");
  c.value("hfov_deg", s.hfov_deg);
  c.check(s.hfov_deg > 1 && s.hfov_deg < 179, "hfov_deg", "must be between 1 and 179 degrees");
  if (!c.file().empty()) s.camera = dsp::CameraModel::from_hfov(w, h, s.hfov_deg * M_PI / 180.0);
  c.value("fps", s.fps);
  c.check(dsp::limits::kFrameRateHz.contains(s.fps), "fps", std::string("must be ") + dsp::limits::kFrameRateHz.text);
  c.value("line_delay_s", s.line_delay_s, "0: rows read over the whole frame period");
  c.check(s.line_delay_s >= 0 && s.line_delay_s * h <= 1.0 / s.fps, "line_delay_s", "must be >= 0 and line_delay_s x height <= 1/fps");
  c.choice("readout", s.readout, {{"top_to_bottom", dsp::Readout::TopToBottom}, {"bottom_to_top", dsp::Readout::BottomToTop}});
  c.value("exposure_s", s.exposure_s);
  c.pixel_format("format", s.format);  // rendered in RGB, then delivered as a camera would
  std::string why;
  c.check(dsp::size_fits(s.format, w, h, &why), "format", why);
  c.value("angular_rate_rad_s", s.angular_rate, "the camera's own motion, camera axes");
  c.value("velocity_m_s", s.velocity);
  c.value("wobble_rad_s", s.wobble_rad_s);
  c.value("wobble_hz", s.wobble_hz);
  c.check(s.wobble_hz > 0, "wobble_hz", "must be positive");
  c.value("wobble_axes", s.wobble_axes, "per axis: multiples of the wobble's amplitude");
  c.value("wobble_axes_hz", s.wobble_axes_hz, "per axis: multiples of its frequency");
  c.check((s.wobble_axes_hz.array() > 0).all(), "wobble_axes_hz", "must be positive");
  c.value("scene_depth_m", s.scene_depth_m, "a textured wall this far ahead");
  c.check(s.scene_depth_m > 0, "scene_depth_m", "must be positive");
  c.value("velocity_rate_hz", s.velocity_rate_hz, "the simulated IMU, published on velocity.channel");
  c.check(dsp::limits::kMotionRateHz.contains(s.velocity_rate_hz), "velocity_rate_hz", std::string("must be ") + dsp::limits::kMotionRateHz.text);
  c.value("velocity_noise", s.velocity_noise);
  c.value("velocity_latency_s", s.velocity_latency_s);
  c.value("gyro_bias_rad_s", s.gyro_bias, "hidden rig physics, IMU axes: w_measured = w_imu / gyro_scale + bias");
  c.value("gyro_scale", s.gyro_scale);
  c.check((s.gyro_scale.array() > 0).all(), "gyro_scale", "must be positive");
  c.value("imu_mount_rotation_rad", s.imu_mount_rotation_rad, "rotation vector r: w_camera = Exp(r) w_imu");
  c.value("imu_time_offset_s", s.imu_time_offset_s, "IMU stamps = camera clock + offset");
  c.check(dsp::limits::kTimeShiftS.contains(s.imu_time_offset_s), "imu_time_offset_s",
          std::string("must be ") + dsp::limits::kTimeShiftS.text);
  c.value("publish_velocity", s.publish_velocity);
  c.value("realtime", s.realtime);
  c.value("noise_grey", s.noise_grey);
}

SimSourceConfig embedded_default() {
  SimSourceConfig s;
  // Turning, not travelling: the wall 3 m ahead passing at 0.5 m/s would show a parallax that the
  // online calibration rightly refuses to take for a clock offset (it holds the estimate).
  s.velocity = Eigen::Vector3d::Zero();
  s.imu_time_offset_s = 0.0025;
  s.gyro_bias = Eigen::Vector3d(0.004, -0.003, 0.002);
  return s;
}

Driver sim_driver() {
  Driver d = make_driver<SimSource, SimSourceConfig>("sim", "the built-in simulated rolling-shutter camera", false, visit_config);
  d.defaults = [] { return std::any(embedded_default()); };
  d.own_camera = [](const std::any& c) { return std::optional<dsp::CameraModel>(std::any_cast<const SimSourceConfig&>(c).camera); };
  return d;
}

}  // namespace rsd::drivers
