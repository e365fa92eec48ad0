// source.sim: the built-in simulated camera's section, read and printed by one visit.
#include <cmath>
#include <cstdio>
#include <string>

#include "drivers/sim_source.hpp"
#include "dsp/core/input_limits.hpp"

namespace rsd::drivers {

namespace {

void visit_lens(formats::ConfigSection& l, dsp::Distortion& d) {
  l.choice("model", d.model, {{"pinhole-radtan", dsp::LensModel::PinholeRadtan}, {"pinhole-equi", dsp::LensModel::PinholeEqui}});
  l.value("k1", d.k1);
  l.value("k2", d.k2);
  if (d.model == dsp::LensModel::PinholeRadtan) {
    l.value("p1", d.p1);
    l.value("p2", d.p2);
  } else {
    l.check(!l.has("p1") && !l.has("p2"), "p1", "and p2 are pinhole-radtan's: pinhole-equi has no tangential terms");
  }
  l.value("k3", d.k3);
  if (d.model == dsp::LensModel::PinholeEqui) l.value("k4", d.k4);
  else l.check(!l.has("k4"), "k4", "is pinhole-equi's: pinhole-radtan has k1, k2, p1, p2, k3");
}

// The lens within rsd's limits, and a ray for every pixel: a radtan polynomial past its monotonic
// range, or an equidistant lens whose field ends inside the image, cannot be rendered.
void check_lens(formats::ConfigSection& c, const dsp::CameraModel& cam) {
  const dsp::CameraOutOfRange bad = dsp::out_of_range(cam);
  c.check(bad.part == dsp::CameraOutOfRange::None, "lens", bad.why);
  const double w = cam.width - 1, h = cam.height - 1;
  for (const Eigen::Vector2d& px : {Eigen::Vector2d(0, 0), Eigen::Vector2d(w, 0), Eigen::Vector2d(0, h), Eigen::Vector2d(w, h),
                                    Eigen::Vector2d(0, h / 2), Eigen::Vector2d(w, h / 2)})
    if (!cam.ray(px)) {
      char where[64];
      std::snprintf(where, sizeof where, "(%g, %g)", px.x(), px.y());
      c.check(false, "lens", std::string("has no ray through pixel ") + where +
                                 ": its field ends inside the image at this hfov_deg (the equidistant model ends at 90 "
                                 "degrees off the axis)");
      return;
    }
}

}  // namespace

void visit_config(formats::ConfigSection& c, SimSourceConfig& s) {
  int w = s.camera.width, h = s.camera.height;
  c.value("width", w);
  c.value("height", h);
  c.check(w >= 16 && h >= 16 && w <= dsp::limits::kMaxSide && h <= dsp::limits::kMaxSide, "width",
          "and height must be 16.." + std::to_string(dsp::limits::kMaxSide) + " pixels");
  c.value("hfov_deg", s.hfov_deg, "the field of view the lens sees across the width");
  c.check(s.hfov_deg > 1 && s.hfov_deg < 179, "hfov_deg", "must be between 1 and 179 degrees");
  dsp::Distortion lens = s.camera.dist;
  c.section("lens", [&](formats::ConfigSection& l) { visit_lens(l, lens); },
            "the simulated camera's true lens (docs/geometry.md): pinhole-radtan terms k1 k2 p1 p2 k3, or a "
            "fisheye, pinhole-equi k1..k4");
  if (!c.file().empty()) {
    s.camera = dsp::CameraModel::from_hfov(w, h, s.hfov_deg * M_PI / 180.0, lens);
    check_lens(c, s.camera);
  }
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
