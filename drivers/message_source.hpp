// What the replay and LCM sources share: frames that arrive as bot_core.image_t messages
// (with per-row timing in their metadata) and velocity that arrives as rsd.velocity_t, in
// one stream, so that the velocity before a frame is delivered before the frame is.
#pragma once

#include <bot_core/pose_t.hpp>
#include <rsd/velocity_t.hpp>

#include <functional>
#include <optional>

#include "drivers/camera_source.hpp"
#include "dsp/geometry/camera_model.hpp"

namespace rsd::drivers {

using VelocityMessageSink = std::function<void(const rsd::velocity_t&)>;
using PoseMessageSink = std::function<void(const bot_core::pose_t&)>;

class MessageSource : public CameraSource {
 public:
  // The velocity messages as they come (any frame: the daemon rotates FRAME_IMU into camera
  // axes). Without this sink, FRAME_CAMERA messages go to the VelocitySink and others are
  // counted in velocity_dropped().
  void set_velocity_message_sink(VelocityMessageSink s) { message_sink_ = std::move(s); }
  void set_velocity_sink(VelocitySink s) override { sample_sink_ = std::move(s); }
  // bot_core.pose_t on `channel` (the daemon's velocity.pose_channel), delivered like
  // velocity, in stream order. Call before open(). Without it, pose messages are not read.
  void set_pose_message_sink(std::string channel, PoseMessageSink s) {
    pose_channel_ = std::move(channel);
    pose_sink_ = std::move(s);
  }
  // The intrinsics the frames carry (rsd's own recordings do), valid after open().
  virtual std::optional<dsp::CameraModel> recorded_camera() const = 0;
  uint64_t velocity_messages() const { return velocity_messages_; }
  uint64_t velocity_dropped() const { return velocity_dropped_; }
  uint64_t pose_messages() const { return pose_messages_; }

 protected:
  void deliver_velocity(const rsd::velocity_t& m) {
    ++velocity_messages_;
    if (message_sink_) return message_sink_(m);
    if (!sample_sink_ || m.frame != rsd::velocity_t::FRAME_CAMERA) {
      ++velocity_dropped_;
      return;
    }
    VelocitySample s;
    s.t_ns = m.utime * 1000;
    for (int i = 0; i < 3; ++i) s.w[i] = m.angular_velocity[i], s.v[i] = m.linear_velocity[i];
    s.has_linear = m.has_linear;
    sample_sink_(s);
  }
  void deliver_pose(const bot_core::pose_t& m) {
    ++pose_messages_;
    if (pose_sink_) pose_sink_(m);
  }
  std::string pose_channel_;
  PoseMessageSink pose_sink_;
  uint64_t pose_messages_ = 0;

 private:
  VelocityMessageSink message_sink_;
  VelocitySink sample_sink_;
  uint64_t velocity_messages_ = 0, velocity_dropped_ = 0;
};

}  // namespace rsd::drivers
