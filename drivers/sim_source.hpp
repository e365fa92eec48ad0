// The built-in simulated camera: the simulator's renderer as a live rolling-shutter camera.
// Frames come at the configured rate on CLOCK_MONOTONIC, each row imaged at the instant it
// is read; the camera's true velocity goes to the velocity sink (optionally with noise, a
// bias and a latency, as a real IMU would deliver it), so the whole pipeline runs without
// hardware.
#pragma once

#include <memory>
#include <random>

#include "drivers/camera_source.hpp"
#include "drivers/driver.hpp"
#include "drivers/monotonic_clock.hpp"
#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/sim/rs_renderer.hpp"

namespace rsd::drivers {

struct SimSourceConfig {
  double hfov_deg = 60;
  dsp::CameraModel camera = dsp::CameraModel::from_hfov(640, 480, hfov_deg * 3.14159265358979 / 180.0);
  double fps = 30;
  double line_delay_s = 0;   // 0: the readout fills the frame period
  bool global_shutter = false;  // every row read at once (source.shutter: global); line_delay_s unused
  dsp::Readout readout = dsp::Readout::TopToBottom;
  double exposure_s = 0.002;
  dsp::PixelFormat format = dsp::PixelFormat::Mono8;
  int supersample = 1;
  double noise_grey = 1.0;
  // Motion: the camera's own angular rate and velocity in its axes, constant, plus a
  // sinusoidal wobble of the rate so that rectification has something to follow.
  Eigen::Vector3d angular_rate{0.0, 0.3, 0.8};  // rad/s
  Eigen::Vector3d velocity{0.5, 0.0, 0.0};      // m/s
  double wobble_rad_s = 0.5, wobble_hz = 0.7;
  // Per axis, multiples of the wobble's amplitude and frequency: a hand turns about changing
  // axes (1, 1, 1: the same wobble about every axis, a fixed axis of rotation).
  Eigen::Vector3d wobble_axes{1, 1, 1}, wobble_axes_hz{1, 1, 1};
  double scene_depth_m = 3.0;                   // a textured wall this far ahead
  // The velocity feed.
  double velocity_rate_hz = 200;
  double velocity_noise = 0, velocity_latency_s = 0;
  // Rig physics the daemon is not told unless a calibration says so. The gyro measures in the
  // IMU's axes, w_camera = R w_imu with R = Exp(imu_mount_rotation_rad), as
  // w_measured = w_imu / gyro_scale + gyro_bias, stamped on the IMU clock: t_imu = t_camera +
  // imu_time_offset_s. Any of them set: samples go out as IMU measurements (FRAME_IMU).
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_scale = Eigen::Vector3d::Ones();
  Eigen::Vector3d imu_mount_rotation_rad = Eigen::Vector3d::Zero();
  double imu_time_offset_s = 0;
  bool publish_velocity = true;
  bool realtime = true;  // false: frames as fast as they render (tests, replays of sims)
  unsigned seed = 1;
};

class SimSource final : public CameraSource {
 public:
  explicit SimSource(SimSourceConfig cfg);
  ~SimSource() override;
  std::string name() const override { return "sim"; }
  void open() override;
  FrameFormat format() const override;
  dsp::RowTiming timing() const override { return timing_; }
  void start() override;
  CaptureStatus capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) override;
  void stop() override {}
  void set_velocity_sink(VelocitySink sink) override { sink_ = std::move(sink); }

  // The true camera motion: world -> camera at a time in seconds since start(), and the
  // scene (valid after open()): what a test needs to render the ground truth.
  const dsp::CameraMotion& truth() const;
  const dsp::Scene& scene() const { return scene_; }
  const SimSourceConfig& config() const { return cfg_; }

 private:
  void emit_velocity_until(double t_s);
  class Motion;
  SimSourceConfig cfg_;
  dsp::RowTiming timing_;
  std::unique_ptr<Motion> motion_;
  std::unique_ptr<dsp::RsRenderer> renderer_;
  dsp::Image rgb_;  // formats other than mono8 and rgb8: rendered here first (allocated at open)
  dsp::Scene scene_;
  VelocitySink sink_;
  int64_t t0_ns_ = 0;
  uint64_t frame_ = 0;
  double next_velocity_s_ = 0;
  std::mt19937 rng_;
};

// The daemon's built-in camera as `rsd` runs it with no configuration (and as config/rsd.yaml
// shows it): a camera turning on its mount whose IMU, like a real one, is a few milliseconds off
// the camera's clock and has a small gyro bias, so that the embedded default shows the online
// calibration learning them. A SimSourceConfig constructed in code is the ideal rig (no hidden
// physics) unless told otherwise.
SimSourceConfig embedded_default();

// The driver's entry (drivers/driver_registry.cpp) and its config section (source.sim).
Driver sim_driver();
void visit_config(formats::ConfigSection& c, SimSourceConfig& s);

}  // namespace rsd::drivers
