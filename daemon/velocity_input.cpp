#include "daemon/velocity_input.hpp"

#include "drivers/lcm_connect.hpp"
#include "drivers/lcm_receive.hpp"
#include "drivers/monotonic_clock.hpp"
#include "formats/image_t_codec.hpp"

#include <bot_core/pose_t.hpp>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <chrono>
#include <cmath>

namespace rsd::daemon {

VelocityInput::VelocityInput(lcm_t* lcm, const std::string& channel, VelocityBuffer& buffer, VelocityInputConfig cfg,
                             std::string lcm_url, std::mutex* lcm_lock)
    : lcm_(lcm), lcm_url_(std::move(lcm_url)), lcm_lock_(lcm_lock), channel_(channel), buffer_(buffer), cfg_(std::move(cfg)) {
  const std::unique_lock<std::mutex> lock = drivers::lock_if(lcm_lock_);
  sub_ = lcm_subscribe(lcm_, channel_.c_str(), &VelocityInput::on_velocity, this);
  if (!cfg_.pose_channel.empty()) pose_sub_ = lcm_subscribe(lcm_, cfg_.pose_channel.c_str(), &VelocityInput::on_pose, this);
}

// Unsubscribing a tcpq instance that lost its hub reconnects, and the hub may be one that never
// answers: the subscriptions are then left to the publisher's drivers::destroy_lcm, which asks
// the hub once (no thread handles this instance any more, so no callback reaches this object).
VelocityInput::~VelocityInput() {
  stop();
  const std::unique_lock<std::mutex> lock = drivers::lock_if(lcm_lock_);
  if (drivers::lost_tcpq_hub(lcm_, lcm_url_)) return;
  if (sub_) lcm_unsubscribe(lcm_, sub_);
  if (pose_sub_) lcm_unsubscribe(lcm_, pose_sub_);
}

void VelocityInput::push(std::optional<dsp::Stamp> t, const Eigen::Matrix3d& r, const double* w, const double* v,
                         bool has_linear, bool live) {
  if (!t) return buffer_.reject();  // beyond rsd's window for times (before or after the shift)
  if (live && clock_check_.load() && cfg_.max_clock_offset_s > 0 &&
      std::abs(static_cast<double>(t->ns() - drivers::monotonic_ns())) > cfg_.max_clock_offset_s * 1e9)
    return buffer_.reject();  // far in the future or the past of the camera's clock
  const Eigen::Vector3d wc = r * Eigen::Vector3d(w[0], w[1], w[2]);
  const Eigen::Vector3d vc = r * Eigen::Vector3d(v[0], v[1], v[2]);
  drivers::VelocitySample s;
  s.t_ns = t->us() * 1000;  // on rsd.velocity_t's microsecond line, as published
  s.has_linear = has_linear && !cfg_.gyro_only;
  for (int i = 0; i < 3; ++i) s.w[i] = wc[i], s.v[i] = s.has_linear ? vc[i] : 0.0;
  buffer_.push(s);  // rejects and counts insane samples (the caller holds writer_)
}

void VelocityInput::on_velocity(const lcm_recv_buf_t* rbuf, const char*, void* user) {
  auto* self = static_cast<VelocityInput*>(user);
  if (self->source_feeds_.load()) {
    self->ignored_.fetch_add(1);
    return;
  }
  if (self->record_) self->record_->write(self->channel_.c_str(), formats::wall_clock_us(), rbuf->data, rbuf->data_size);
  rsd::velocity_t m;
  std::string why;
  if (formats::decode_checked(static_cast<const uint8_t*>(rbuf->data), rbuf->data_size, m, why) != formats::DecodeStatus::Ok) {
    self->malformed_.fetch_add(1);
    return;
  }
  self->accept(m, true);
}

std::optional<dsp::Stamp> VelocityInput::camera_time(std::optional<dsp::Stamp> motion) {
  if (!motion) return std::nullopt;
  const std::optional<dsp::Stamp> shifted = motion->plus_ns(-std::llround(cfg_.imu_time_offset_s * 1e6) * 1000);
  if (cfg_.drift_ppm == 0 || !shifted) return shifted;
  // t_m - offset = t_cam + d (t_cam - T0)  =>  t_cam = T0 + (t_m - offset - T0) / (1 + d).
  if (!t0_) t0_ = shifted;
  // The reference given (the online calibration's), else the first sample's.
  const std::optional<dsp::Stamp> t0 = cfg_.drift_t0_s ? dsp::Stamp::from_s(*cfg_.drift_t0_s) : t0_;
  if (!t0) return shifted;  // a reference outside the stamps' window: no drift to apply from it
  // In whole microseconds, rsd.velocity_t's unit (the window and kDriftPpm keep llround in range).
  const double us = static_cast<double>((*shifted - *t0) / 1000) / (1.0 + cfg_.drift_ppm * 1e-6);
  return t0->plus_ns(std::llround(us) * 1000);
}

void VelocityInput::at_camera_origin(const double* w, const double* v, double* out) const {
  const Eigen::Vector3d c = Eigen::Vector3d(v[0], v[1], v[2]) + Eigen::Vector3d(w[0], w[1], w[2]).cross(cfg_.lever_arm_m);
  for (int i = 0; i < 3; ++i) out[i] = c[i];
}

void VelocityInput::push_imu(int64_t utime_imu, const double* w_measured, const double* v, bool has_linear, bool live) {
  const std::optional<dsp::Stamp> t = dsp::Stamp::from_us(utime_imu);
  if (!t) return buffer_.reject();
  if (gyro_tap_) gyro_tap_->gyro(utime_imu, w_measured);
  double w[3], vc[3];
  for (int i = 0; i < 3; ++i) w[i] = cfg_.gyro_scale[i] * (w_measured[i] - cfg_.gyro_bias_rad_s[i]);
  at_camera_origin(w, v, vc);
  push(camera_time(t), cfg_.imu_to_camera, w, vc, has_linear, live);
}

void VelocityInput::accept(const rsd::velocity_t& m, bool live) {
  std::lock_guard<std::mutex> lock(writer_);
  if (m.frame == rsd::velocity_t::FRAME_CAMERA)  // onto the camera clock
    push(camera_time(dsp::Stamp::from_us(m.utime)), Eigen::Matrix3d::Identity(), m.angular_velocity, m.linear_velocity,
         m.has_linear, live);
  else if (m.frame == rsd::velocity_t::FRAME_IMU)
    push_imu(m.utime, m.angular_velocity, m.linear_velocity, m.has_linear, live);
  else
    malformed_.fetch_add(1);  // a frame this version does not know
}

void VelocityInput::deliver(const rsd::velocity_t& m) {
  source_feeds_.store(true);
  accept(m, false);
}

void VelocityInput::deliver(const drivers::VelocitySample& s) {
  source_feeds_.store(true);
  std::lock_guard<std::mutex> lock(writer_);
  // On the time line of rsd.velocity_t (us), so that a replay of the published samples
  // reproduces the live run.
  if (s.imu_frame)
    push_imu(s.t_ns / 1000, s.w, s.v, s.has_linear, false);
  else
    push(dsp::Stamp::from_us(s.t_ns / 1000), Eigen::Matrix3d::Identity(), s.w, s.v, s.has_linear, false);
}

void VelocityInput::set_calibration(const VelocityInputConfig& c) {
  std::lock_guard<std::mutex> lock(writer_);
  // Everything but what the subscriptions and the configuration's own choices fixed at start.
  const std::string pose_channel = cfg_.pose_channel;
  const bool gyro_only = cfg_.gyro_only;
  cfg_ = c;
  cfg_.pose_channel = pose_channel;
  cfg_.gyro_only = gyro_only;
}

rsd::velocity_t VelocityInput::to_message(const drivers::VelocitySample& s) {
  rsd::velocity_t m{};
  m.utime = s.t_ns / 1000;
  m.frame = s.imu_frame ? rsd::velocity_t::FRAME_IMU : rsd::velocity_t::FRAME_CAMERA;
  for (int i = 0; i < 3; ++i) m.angular_velocity[i] = s.w[i], m.linear_velocity[i] = s.v[i];
  m.has_linear = s.has_linear;
  return m;
}

void VelocityInput::on_pose(const lcm_recv_buf_t* rbuf, const char*, void* user) {
  auto* self = static_cast<VelocityInput*>(user);
  if (self->source_feeds_pose_.load()) {
    self->ignored_.fetch_add(1);
    return;
  }
  if (self->record_)
    self->record_->write(self->cfg_.pose_channel.c_str(), formats::wall_clock_us(), rbuf->data, rbuf->data_size);
  bot_core::pose_t m;
  std::string why;
  if (formats::decode_checked(static_cast<const uint8_t*>(rbuf->data), rbuf->data_size, m, why) != formats::DecodeStatus::Ok) {
    self->malformed_.fetch_add(1);
    return;
  }
  std::lock_guard<std::mutex> lock(self->writer_);
  self->push_pose(m, true);
}

void VelocityInput::push_pose(const bot_core::pose_t& m, bool live) {
  double v[3];
  at_camera_origin(m.rotation_rate, m.vel, v);
  // A calibration learned from a trajectory holds the body-to-camera rotation in T_cam_imu;
  // velocity.body_to_camera, when set, says the same and comes first.
  const bool calibrated_rotation = cfg_.pose_calibrated && cfg_.body_to_camera.isIdentity();
  push(camera_time(dsp::Stamp::from_us(m.utime)), calibrated_rotation ? cfg_.imu_to_camera : cfg_.body_to_camera, m.rotation_rate, v, true, live);
}

void VelocityInput::deliver(const bot_core::pose_t& m) {
  source_feeds_pose_.store(true);
  std::lock_guard<std::mutex> lock(writer_);
  push_pose(m, false);
}

void VelocityInput::start() {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this] {
    while (running_.load())
      // A provider that cannot receive (tcpq without its hub: a publish reconnects it).
      if (drivers::handle_lcm(lcm_, 50, drivers::kLcmPartialMessageTimeoutMs, lcm_lock_) < 0)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
  });
}

void VelocityInput::stop() {
  if (!running_.exchange(false)) return;
  if (thread_.joinable()) thread_.join();
}


}  // namespace rsd::daemon
