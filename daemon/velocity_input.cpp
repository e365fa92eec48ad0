#include "daemon/velocity_input.hpp"

#include <rsd/velocity_t.hpp>

#include <cmath>

namespace rsd::daemon {

VelocityInput::VelocityInput(lcm_t* lcm, const std::string& channel, VelocityBuffer& buffer)
    : lcm_(lcm), channel_(channel), buffer_(buffer) {
  sub_ = lcm_subscribe(lcm_, channel_.c_str(), &VelocityInput::on_message, this);
}

VelocityInput::~VelocityInput() {
  stop();
  if (sub_) lcm_unsubscribe(lcm_, sub_);
}

void VelocityInput::on_message(const lcm_recv_buf_t* rbuf, const char*, void* user) {
  auto* self = static_cast<VelocityInput*>(user);
  rsd::velocity_t m;
  if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0 || m.frame != rsd::velocity_t::FRAME_CAMERA) {
    self->malformed_.fetch_add(1);
    return;
  }
  drivers::VelocitySample s;
  s.t_ns = m.utime * 1000;
  for (int i = 0; i < 3; ++i) s.w[i] = m.angular_velocity[i], s.v[i] = m.linear_velocity[i];
  s.has_linear = m.has_linear;
  self->buffer_.push(s);  // rejects and counts insane samples
}

void VelocityInput::start() {
  running_ = true;
  thread_ = std::thread([this] {
    while (running_.load()) lcm_handle_timeout(lcm_, 50);
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
