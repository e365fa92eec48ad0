// Velocity over LCM: rsd.velocity_t on the velocity channel (the simulated camera publishes
// its truth there too, so every source's velocity takes the same path), decoded on the LCM
// thread into the VelocityBuffer. Malformed messages are counted and skipped.
#pragma once

#include <lcm/lcm.h>

#include <atomic>
#include <string>
#include <thread>

#include "daemon/velocity_buffer.hpp"

namespace rsd::daemon {

class VelocityInput {
 public:
  VelocityInput(lcm_t* lcm, const std::string& channel, VelocityBuffer& buffer);
  ~VelocityInput();
  void start();  // the LCM handling thread
  void stop();
  uint64_t malformed() const { return malformed_.load(); }
  // Encodes and publishes a sample as rsd.velocity_t (the simulated camera's IMU).
  static void publish(lcm_t* lcm, const std::string& channel, const drivers::VelocitySample& s);

 private:
  static void on_message(const lcm_recv_buf_t* rbuf, const char* channel, void* user);
  lcm_t* lcm_;
  std::string channel_;
  VelocityBuffer& buffer_;
  lcm_subscription_t* sub_ = nullptr;
  std::atomic<bool> running_{false};
  std::atomic<uint64_t> malformed_{0};
  std::thread thread_;
};

}  // namespace rsd::daemon
