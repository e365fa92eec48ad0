// Velocity over LCM, decoded on the LCM thread into the VelocityBuffer (camera axes):
//  - rsd.velocity_t on the velocity channel (the simulated camera publishes its truth there
//    too, so every source's velocity takes the same path). FRAME_CAMERA is used as is;
//    FRAME_IMU is rotated into camera axes with imu_to_camera.
//  - bot_core.pose_t on the optional pose channel: rotation_rate and vel (both in the body
//    frame, as libbot2 documents them) rotated into camera axes with body_to_camera.
// Malformed messages (undecodable, unknown frame) are counted and skipped; the buffer
// rejects and counts insane or out-of-order samples. Both channels are handled on one thread,
// so the buffer keeps its single writer.
#pragma once

#include <lcm/lcm.h>
#include <bot_core/pose_t.hpp>
#include <rsd/velocity_t.hpp>

#include <Eigen/Core>
#include <atomic>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "daemon/velocity_buffer.hpp"
#include "dsp/core/stamp.hpp"
#include "formats/lcm_log.hpp"

namespace rsd::daemon {

// Raw IMU measurements also to background work (the online calibration): each FRAME_IMU sample
// as measured, on the IMU's clock and axes, before the calibration corrects it. Called with the
// velocity input's writer lock held (one caller at a time); it must neither wait nor allocate.
class GyroTap {
 public:
  virtual ~GyroTap() = default;
  virtual void gyro(int64_t utime_imu, const double* w_measured) = 0;
};

struct VelocityInputConfig {
  std::string pose_channel;  // bot_core.pose_t; empty: not subscribed
  // Rotations (row-major in the config), v_camera = R v_sensor.
  Eigen::Matrix3d imu_to_camera = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d body_to_camera = Eigen::Matrix3d::Identity();
  bool gyro_only = false;  // every sample has_linear = false (linear velocity zeroed)
  // The motion sensor's calibration (docs/formats/calibration-v1.md), applied to messages
  // received (not to a source's own camera-clock truth): a sample stamped t on the IMU clock
  // belongs to camera time t - imu_time_offset_s (t_imu = t_cam + offset); FRAME_IMU rates are
  // corrected, w_true = diag(gyro_scale) (w_measured - gyro_bias_rad_s), before the rotation.
  double imu_time_offset_s = 0;
  Eigen::Vector3d gyro_bias_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_scale = Eigen::Vector3d::Ones();
  // The camera clock's rate error (the recording's time model): t_motion = t_cam + offset +
  // drift_ppm 1e-6 (t_cam - T0). T0 is the first sample's camera time (the recording format's
  // first frame, which it precedes by a fraction of a second: drift x that gap is microseconds).
  double drift_ppm = 0;
  // T0 given (camera clock, s) instead of the first sample's: the online calibration's offset
  // holds at the time it was fitted (calibration.online apply).
  std::optional<double> drift_t0_s;
  // The camera's origin in the motion sensor's (body's) axes: a body moving at v and turning at
  // w carries the camera at v + w x lever_arm_m, before the rotation into camera axes.
  Eigen::Vector3d lever_arm_m = Eigen::Vector3d::Zero();
  // A calibration was given: bot_core.pose_t messages (a tracked body, on the motion clock) go
  // through its clock offset and drift too, and through its rotation unless body_to_camera is set.
  bool pose_calibrated = false;
  // Messages received over LCM while a live camera runs (set_clock_check) whose camera time
  // is further than this from the camera clock are refused and counted (0: no check).
  double max_clock_offset_s = 5;
};

class VelocityInput {
 public:
  // lcm_url: the URL `lcm` was made from; an instance that lost its tcpq hub is not unsubscribed
  // at the end (that would reconnect; the owner's drivers::destroy_lcm does it safely).
  // lcm_lock: the lock other threads hold around their calls into `lcm` (LcmPublisher::lcm_lock),
  // held here around subscribing, receiving (drivers::handle_lcm) and unsubscribing; null when
  // no other thread uses the instance.
  VelocityInput(lcm_t* lcm, const std::string& channel, VelocityBuffer& buffer, VelocityInputConfig cfg = {},
                std::string lcm_url = {}, std::mutex* lcm_lock = nullptr);
  ~VelocityInput();
  VelocityInput(const VelocityInput&) = delete;
  VelocityInput& operator=(const VelocityInput&) = delete;
  void start();  // the LCM handling thread
  void stop();
  uint64_t malformed() const { return malformed_.load(); }
  // A sample as the rsd.velocity_t message it is published as (FRAME_CAMERA, utime in us).
  static rsd::velocity_t to_message(const drivers::VelocitySample& s);

  // Velocity from the camera source itself (the simulator's truth, a replayed log, the lcm
  // source), delivered synchronously on the source's thread before the frame it precedes:
  // which samples a frame sees no longer depends on thread timing, so a replay reproduces a
  // live run. Decoded exactly as a message on the channel would be. Once a source delivers,
  // messages on the velocity channel are ignored (counted): they are the source's own
  // samples echoed by LCM, and two time lines cannot share the buffer.
  void deliver(const rsd::velocity_t& m);
  // A source's sample: camera truth straight into the buffer, an IMU measurement (imu_frame)
  // through the calibration.
  void deliver(const drivers::VelocitySample& s);
  // The same for bot_core.pose_t on the pose channel (a replayed log's, the lcm source's).
  void deliver(const bot_core::pose_t& m);
  uint64_t ignored() const { return ignored_.load(); }
  // Checks messages received over LCM against the camera clock (CLOCK_MONOTONIC): on for a live
  // camera, whose clock the stamps share; a replay's or a source's own samples are not checked.
  void set_clock_check(bool on) { clock_check_.store(on); }
  // A new calibration (SIGHUP): the rotations and the IMU's clock, bias, scale and lever arm of
  // `c`, for every sample from now on (the channels stay). Any thread.
  void set_calibration(const VelocityInputConfig& c);
  // rsd --record: velocity and pose messages received over LCM (an IMU, a localiser) are
  // written to the recording as they arrive, unless they are a source's echo.
  void set_recorder(formats::LcmLogWriter* log) { record_ = log; }
  // The raw IMU measurements to `tap` too; before start().
  void set_gyro_tap(GyroTap* tap) { gyro_tap_ = tap; }

 private:
  static void on_velocity(const lcm_recv_buf_t* rbuf, const char* channel, void* user);
  static void on_pose(const lcm_recv_buf_t* rbuf, const char* channel, void* user);
  // `live`: received over LCM (checked against the clock), not delivered by the source.
  void accept(const rsd::velocity_t& m, bool live);
  void push(std::optional<dsp::Stamp> t, const Eigen::Matrix3d& r, const double* w, const double* v, bool has_linear, bool live);
  // A motion-clock stamp on the camera clock, through the offset and drift.
  std::optional<dsp::Stamp> camera_time(std::optional<dsp::Stamp> motion);
  // A body's linear velocity carried to the camera's origin (the lever arm).
  void at_camera_origin(const double* w, const double* v, double* out) const;
  // A tracked body's pose message (body axes, motion clock) through the calibration.
  void push_pose(const bot_core::pose_t& m, bool live);
  // A motion-sensor measurement (IMU axes and clock) through the calibration.
  void push_imu(int64_t utime_imu, const double* w_measured, const double* v, bool has_linear, bool live);
  lcm_t* lcm_;
  std::string lcm_url_;
  std::mutex* lcm_lock_ = nullptr;  // see the constructor
  std::string channel_;
  VelocityBuffer& buffer_;
  VelocityInputConfig cfg_;
  lcm_subscription_t* sub_ = nullptr;
  lcm_subscription_t* pose_sub_ = nullptr;
  std::atomic<bool> running_{false};
  std::atomic<uint64_t> malformed_{0}, ignored_{0};
  std::atomic<bool> source_feeds_{false}, source_feeds_pose_{false};
  std::atomic<bool> clock_check_{false};
  std::optional<dsp::Stamp> t0_;  // camera time of the first sample (the drift's reference)
  formats::LcmLogWriter* record_ = nullptr;
  GyroTap* gyro_tap_ = nullptr;
  // The source's thread and the LCM thread (pose_t) both push, and set_calibration() changes
  // cfg_'s calibration: every entry point holds this while it converts and pushes.
  std::mutex writer_;
  std::thread thread_;
};

}  // namespace rsd::daemon
