#include "daemon/velocity_input.hpp"

#include <bot_core/pose_t.hpp>
#include <rsd/velocity_t.hpp>

#include <Eigen/LU>
#include <chrono>
#include <cmath>

namespace rsd::daemon {

bool is_rotation(const Eigen::Matrix3d& m, double tol) {
  return m.allFinite() && (m.transpose() * m - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= tol &&
         std::abs(m.determinant() - 1.0) <= tol;
}

VelocityInput::VelocityInput(lcm_t* lcm, const std::string& channel, VelocityBuffer& buffer, VelocityInputConfig cfg)
    : lcm_(lcm), channel_(channel), buffer_(buffer), cfg_(std::move(cfg)) {
  sub_ = lcm_subscribe(lcm_, channel_.c_str(), &VelocityInput::on_velocity, this);
  if (!cfg_.pose_channel.empty()) pose_sub_ = lcm_subscribe(lcm_, cfg_.pose_channel.c_str(), &VelocityInput::on_pose, this);
}

VelocityInput::~VelocityInput() {
  stop();
  if (sub_) lcm_unsubscribe(lcm_, sub_);
  if (pose_sub_) lcm_unsubscribe(lcm_, pose_sub_);
}

void VelocityInput::push(int64_t utime, const Eigen::Matrix3d& r, const double* w, const double* v, bool has_linear) {
  const Eigen::Vector3d wc = r * Eigen::Vector3d(w[0], w[1], w[2]);
  const Eigen::Vector3d vc = r * Eigen::Vector3d(v[0], v[1], v[2]);
  drivers::VelocitySample s;
  s.t_ns = utime * 1000;
  s.has_linear = has_linear && !cfg_.gyro_only;
  for (int i = 0; i < 3; ++i) s.w[i] = wc[i], s.v[i] = s.has_linear ? vc[i] : 0.0;
  buffer_.push(s);  // rejects and counts insane samples
}

void VelocityInput::on_velocity(const lcm_recv_buf_t* rbuf, const char*, void* user) {
  auto* self = static_cast<VelocityInput*>(user);
  rsd::velocity_t m;
  if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) {
    self->malformed_.fetch_add(1);
    return;
  }
  if (m.frame == rsd::velocity_t::FRAME_CAMERA)
    self->push(m.utime, Eigen::Matrix3d::Identity(), m.angular_velocity, m.linear_velocity, m.has_linear);
  else if (m.frame == rsd::velocity_t::FRAME_IMU)
    self->push(m.utime, self->cfg_.imu_to_camera, m.angular_velocity, m.linear_velocity, m.has_linear);
  else
    self->malformed_.fetch_add(1);  // a frame this version does not know
}

void VelocityInput::on_pose(const lcm_recv_buf_t* rbuf, const char*, void* user) {
  auto* self = static_cast<VelocityInput*>(user);
  bot_core::pose_t m;
  if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) {
    self->malformed_.fetch_add(1);
    return;
  }
  self->push(m.utime, self->cfg_.body_to_camera, m.rotation_rate, m.vel, true);
}

void VelocityInput::start() {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this] {
    while (running_.load())
      if (lcm_handle_timeout(lcm_, 50) < 0)  // a provider that cannot receive (a log being written)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
  });
}

void VelocityInput::stop() {
  if (!running_.exchange(false)) return;
  if (thread_.joinable()) thread_.join();
}

void VelocityInput::publish(lcm_t* lcm, const std::string& channel, const drivers::VelocitySample& s) {
  rsd::velocity_t m{};
  m.utime = s.t_ns / 1000;
  m.frame = rsd::velocity_t::FRAME_CAMERA;
  for (int i = 0; i < 3; ++i) m.angular_velocity[i] = s.w[i], m.linear_velocity[i] = s.v[i];
  m.has_linear = s.has_linear;
  uint8_t buf[128];
  const int len = m.encode(buf, 0, sizeof buf);
  if (len > 0) lcm_publish(lcm, channel.c_str(), buf, static_cast<unsigned>(len));
}

}  // namespace rsd::daemon
