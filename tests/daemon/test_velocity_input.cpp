// Velocity over LCM (in-process memq://): rsd.velocity_t in camera and IMU axes, bot_core.pose_t
// in body axes, gyro-only, and malformed messages, checked in the VelocityBuffer.
#include <gtest/gtest.h>
#include <lcm/lcm.h>

#include <bot_core/pose_t.hpp>
#include <rsd/velocity_t.hpp>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstdio>
#include <fstream>
#include <thread>
#include <unistd.h>
#include <vector>

#include "daemon/config.hpp"
#include "daemon/velocity_input.hpp"
#include "formats/yaml_map.hpp"

using namespace rsd::daemon;

namespace {

rsd::velocity_t velocity(int64_t utime, int8_t frame, double wx, double wy, double wz, double vx, double vy, double vz,
                         bool has_linear = true);

class VelocityInputTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_NE(lcm_, nullptr); }
  void TearDown() override {
    if (lcm_) lcm_destroy(lcm_);
  }

  template <class Msg>
  void publish(const char* channel, const Msg& m) {
    std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
    ASSERT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
    publish_raw(channel, buf.data(), buf.size());
  }
  void publish_raw(const char* channel, const void* data, size_t n) {
    ASSERT_EQ(lcm_publish(lcm_, channel, data, static_cast<unsigned>(n)), 0);
  }
  // Dispatches everything queued on the memq provider (no thread).
  void drain() {
    while (lcm_handle_timeout(lcm_, 20) > 0) {
    }
  }
  // The sample the buffer holds at utime (us).
  rsd::drivers::VelocitySample at(int64_t utime) {
    VelocityEstimate e;
    EXPECT_EQ(buffer_.at(utime * 1000, e), VelocityStatus::Ok);
    return e.sample;
  }

  // The drift tests' stream: rates 0.1 and 0.3 rad/s about x stamped 1.010 s and 3.010 s on the
  // IMU clock, through `cfg` into a buffer that interpolates across their 2 s; w_x(us) reads it.
  void two_rates_2_s_apart(const VelocityInputConfig& cfg) {
    VelocityInput in(lcm_, "RSD_VELOCITY", slow_buffer_, cfg);
    publish("RSD_VELOCITY", velocity(1'010'000, rsd::velocity_t::FRAME_IMU, 0.1, 0, 0, 0, 0, 0, false));
    publish("RSD_VELOCITY", velocity(3'010'000, rsd::velocity_t::FRAME_IMU, 0.3, 0, 0, 0, 0, 0, false));
    drain();
    ASSERT_EQ(slow_buffer_.count(), 2u);
  }
  double w_x(int64_t us) {
    VelocityEstimate e;
    EXPECT_EQ(slow_buffer_.at(us * 1000, e), VelocityStatus::Ok);
    return e.sample.w[0];
  }

  lcm_t* lcm_ = lcm_create("memq://");
  VelocityBuffer buffer_;
  VelocityBuffer slow_buffer_{VelocityLimits{20, 100, 5.0}};
};

rsd::velocity_t velocity(int64_t utime, int8_t frame, double wx, double wy, double wz, double vx, double vy, double vz,
                         bool has_linear) {
  rsd::velocity_t m{};
  m.utime = utime;
  m.frame = frame;
  m.angular_velocity[0] = wx, m.angular_velocity[1] = wy, m.angular_velocity[2] = wz;
  m.linear_velocity[0] = vx, m.linear_velocity[1] = vy, m.linear_velocity[2] = vz;
  m.has_linear = has_linear;
  return m;
}

// 90 degrees about z: x -> y, y -> -x (row-major [0 -1 0; 1 0 0; 0 0 1]).
Eigen::Matrix3d rot_z90() {
  Eigen::Matrix3d r;
  r << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  return r;
}

}  // namespace

TEST_F(VelocityInputTest, CameraFrameIsTakenAsIs) {
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_);
  publish("RSD_VELOCITY", velocity(1000, rsd::velocity_t::FRAME_CAMERA, 0.1, 0.2, 0.3, 1.0, 2.0, 3.0));
  publish("RSD_VELOCITY", velocity(2000, rsd::velocity_t::FRAME_CAMERA, 0.3, 0.4, 0.5, 3.0, 4.0, 5.0));
  drain();
  EXPECT_EQ(buffer_.count(), 2u);
  EXPECT_EQ(in.malformed(), 0u);
  const auto s = at(1000);
  EXPECT_EQ(s.w[0], 0.1);
  EXPECT_EQ(s.w[1], 0.2);
  EXPECT_EQ(s.w[2], 0.3);
  EXPECT_EQ(s.v[0], 1.0);
  EXPECT_EQ(s.v[2], 3.0);
  EXPECT_TRUE(s.has_linear);
  const auto mid = at(1500);  // interpolated to the query time
  EXPECT_NEAR(mid.w[0], 0.2, 1e-12);
  EXPECT_NEAR(mid.v[1], 3.0, 1e-12);
}

TEST_F(VelocityInputTest, ImuFrameIsRotatedIntoCameraAxes) {
  VelocityInputConfig cfg;
  cfg.imu_to_camera = rot_z90();
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_, cfg);
  publish("RSD_VELOCITY", velocity(1000, rsd::velocity_t::FRAME_IMU, 0.1, 0.2, 0.3, 1.0, 2.0, 3.0));
  drain();
  ASSERT_EQ(buffer_.count(), 1u);
  EXPECT_EQ(in.malformed(), 0u);
  const auto s = at(1000);
  EXPECT_EQ(s.w[0], -0.2);  // exact: the rotation's entries are 0 and +-1
  EXPECT_EQ(s.w[1], 0.1);
  EXPECT_EQ(s.w[2], 0.3);
  EXPECT_EQ(s.v[0], -2.0);
  EXPECT_EQ(s.v[1], 1.0);
  EXPECT_EQ(s.v[2], 3.0);
  EXPECT_TRUE(s.has_linear);
}

// A calibration's IMU part: bias, then scale, then the rotation; the IMU clock's offset moves
// the sample onto the camera clock (t_imu = t_cam + offset). Worked by hand: w - b = (0.1, 0.2,
// 0.3), scaled (0.11, 0.2, 0.27), rotated by 90 degrees about z (-0.2, 0.11, 0.27), at 100 ms
// - 12 ms on the camera clock.
TEST_F(VelocityInputTest, ImuCalibrationCorrectsBiasScaleRotationAndClock) {
  VelocityInputConfig cfg;
  cfg.imu_to_camera = rot_z90();
  cfg.gyro_bias_rad_s = {0.01, 0.02, 0.03};
  cfg.gyro_scale = {1.1, 1.0, 0.9};
  cfg.imu_time_offset_s = 0.012;
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_, cfg);
  publish("RSD_VELOCITY", velocity(100000, rsd::velocity_t::FRAME_IMU, 0.11, 0.22, 0.33, 1.0, 2.0, 3.0));
  drain();
  ASSERT_EQ(buffer_.count(), 1u);
  const auto s = at(88000);
  EXPECT_NEAR(s.w[0], -0.2, 1e-12);
  EXPECT_NEAR(s.w[1], 0.11, 1e-12);
  EXPECT_NEAR(s.w[2], 0.27, 1e-12);
  EXPECT_NEAR(s.v[0], -2.0, 1e-12);  // linear velocity: rotated only
  EXPECT_NEAR(s.v[1], 1.0, 1e-12);
}

// Clock drift: t_imu = t_cam + offset + d (t_cam - T0), T0 the first sample's camera time. With
// d = 500 ppm and a 10 ms offset, an IMU stamp 2 s after the first is 2 s / 1.0005 later on the
// camera clock: 1999.0005 ms (to the microsecond).
TEST_F(VelocityInputTest, ClockDriftStretchesTheImuTimeLine) {
  VelocityInputConfig cfg;
  cfg.imu_time_offset_s = 0.010;
  cfg.drift_ppm = 500;
  two_rates_2_s_apart(cfg);
  const int64_t t1 = 1'000'000 + std::llround(2e6 / 1.0005);  // 2'999'000 us
  EXPECT_NEAR(w_x(1'000'000), 0.1, 1e-12);
  EXPECT_NEAR(w_x(t1), 0.3, 1e-9);  // the second sample sits exactly there
  // Half way between the two on the stretched time line: the mean of the two rates. Without the
  // drift the second sample would sit 1 ms later, and the rate here would be 0.1999.
  EXPECT_NEAR(w_x(1'000'000 + (t1 - 1'000'000) / 2), 0.2, 1e-6);
}

// The online calibration's drift holds from where its offset was fitted (drift_t0_s), not from
// the first sample: with T0 = 0.5 s, the same stamps sit at 0.5 + 0.5 / 1.0005 s and
// 0.5 + 2.5 / 1.0005 s on the camera clock (999.750 and 2998.751 ms).
TEST_F(VelocityInputTest, ClockDriftFromAGivenReference) {
  VelocityInputConfig cfg;
  cfg.imu_time_offset_s = 0.010;
  cfg.drift_ppm = 500;
  cfg.drift_t0_s = 0.5;
  two_rates_2_s_apart(cfg);
  EXPECT_NEAR(w_x(500'000 + std::llround(0.5e6 / 1.0005)), 0.1, 1e-12);  // 999'750 us
  EXPECT_NEAR(w_x(500'000 + std::llround(2.5e6 / 1.0005)), 0.3, 1e-9);   // 2'998'751 us
}

// The lever arm: a body turning at 1 rad/s about z carries a camera 0.5 m along its x axis at
// 0.5 m/s along y, on top of the body's own velocity; then the rotation into camera axes.
TEST_F(VelocityInputTest, LeverArmCarriesTheBodyVelocityToTheCamera) {
  VelocityInputConfig cfg;
  cfg.lever_arm_m = {0.5, 0, 0};
  cfg.imu_to_camera = rot_z90();
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_, cfg);
  publish("RSD_VELOCITY", velocity(1000, rsd::velocity_t::FRAME_IMU, 0, 0, 1.0, 1.0, 0, 0));
  drain();
  const auto s = at(1000);
  // body: v + w x l = (1, 0.5, 0); rotated by 90 degrees about z: (-0.5, 1, 0).
  EXPECT_NEAR(s.v[0], -0.5, 1e-12);
  EXPECT_NEAR(s.v[1], 1.0, 1e-12);
  EXPECT_NEAR(s.v[2], 0.0, 1e-12);
}

TEST_F(VelocityInputTest, CameraFrameIgnoresImuRotation) {
  VelocityInputConfig cfg;
  cfg.imu_to_camera = rot_z90();
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_, cfg);
  publish("RSD_VELOCITY", velocity(1000, rsd::velocity_t::FRAME_CAMERA, 0.1, 0.2, 0.3, 1.0, 2.0, 3.0));
  drain();
  const auto s = at(1000);
  EXPECT_EQ(s.w[0], 0.1);
  EXPECT_EQ(s.v[1], 2.0);
}

TEST_F(VelocityInputTest, UnknownFrameIsMalformed) {
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_);
  publish("RSD_VELOCITY", velocity(1000, 7, 0.1, 0.2, 0.3, 0, 0, 0));
  publish("RSD_VELOCITY", velocity(2000, -1, 0.1, 0.2, 0.3, 0, 0, 0));
  drain();
  EXPECT_EQ(in.malformed(), 2u);
  EXPECT_EQ(buffer_.count(), 0u);
  EXPECT_EQ(buffer_.rejected(), 0u);
}

TEST_F(VelocityInputTest, TruncatedAndGarbageMessagesAreMalformed) {
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_);
  const auto m = velocity(1000, rsd::velocity_t::FRAME_CAMERA, 0.1, 0.2, 0.3, 0, 0, 0);
  std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  publish_raw("RSD_VELOCITY", buf.data(), buf.size() / 2);  // truncated
  const uint8_t garbage[] = {0xde, 0xad, 0xbe, 0xef, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
  publish_raw("RSD_VELOCITY", garbage, sizeof garbage);  // wrong fingerprint
  publish_raw("RSD_VELOCITY", garbage, 0);               // empty
  publish("RSD_VELOCITY", m);                             // and a good one still gets through
  drain();
  EXPECT_EQ(in.malformed(), 3u);
  EXPECT_EQ(buffer_.count(), 1u);
  EXPECT_EQ(at(1000).w[2], 0.3);
}

TEST_F(VelocityInputTest, PoseIsRotatedFromBodyToCameraAxes) {
  VelocityInputConfig cfg;
  cfg.pose_channel = "POSE";
  cfg.body_to_camera = rot_z90();
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_, cfg);
  bot_core::pose_t p{};
  p.utime = 5000;
  p.orientation[0] = 1;
  p.rotation_rate[0] = 0.5, p.rotation_rate[1] = -0.25, p.rotation_rate[2] = 1.0;
  p.vel[0] = 4.0, p.vel[1] = 0.5, p.vel[2] = -1.0;
  p.pos[0] = 100, p.accel[2] = 9.81;  // ignored
  publish("POSE", p);
  publish_raw("POSE", "nonsense", 8);  // malformed on the pose channel too
  drain();
  EXPECT_EQ(in.malformed(), 1u);
  ASSERT_EQ(buffer_.count(), 1u);
  const auto s = at(5000);
  EXPECT_EQ(s.w[0], 0.25);
  EXPECT_EQ(s.w[1], 0.5);
  EXPECT_EQ(s.w[2], 1.0);
  EXPECT_EQ(s.v[0], -0.5);
  EXPECT_EQ(s.v[1], 4.0);
  EXPECT_EQ(s.v[2], -1.0);
  EXPECT_TRUE(s.has_linear);
  EXPECT_EQ(s.t_ns, 5000 * 1000);
}

// With a calibration, a tracked body's poses are on the motion clock: its offset moves them onto
// the camera clock, and its rotation (a trajectory's T_cam_imu is body-to-camera) turns them,
// unless velocity.body_to_camera says otherwise.
TEST_F(VelocityInputTest, PosesGoThroughTheCalibration) {
  VelocityInputConfig cfg;
  cfg.pose_channel = "POSE";
  cfg.pose_calibrated = true;
  cfg.imu_to_camera = rot_z90();
  cfg.imu_time_offset_s = 0.012;
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_, cfg);
  bot_core::pose_t p{};
  p.utime = 100000;
  p.orientation[0] = 1;
  p.rotation_rate[0] = 0.5, p.rotation_rate[1] = -0.25, p.rotation_rate[2] = 1.0;
  p.vel[0] = 4.0;
  publish("POSE", p);
  drain();
  ASSERT_EQ(buffer_.count(), 1u);
  const auto s = at(88000);  // 12 ms earlier on the camera clock
  EXPECT_EQ(s.w[0], 0.25);
  EXPECT_EQ(s.w[1], 0.5);
  EXPECT_EQ(s.v[1], 4.0);
  // body_to_camera set: it wins over the calibration's rotation (the clock still moves).
  VelocityBuffer other;
  cfg.body_to_camera = rot_z90().transpose();
  VelocityInput in2(lcm_, "RSD_VELOCITY_2", other, cfg);
  p.utime = 200000;
  in2.deliver(p);
  VelocityEstimate e;
  ASSERT_EQ(other.at(188000 * 1000, e), VelocityStatus::Ok);
  EXPECT_EQ(e.sample.w[0], -0.25);
  EXPECT_EQ(e.sample.w[1], -0.5);
}

TEST_F(VelocityInputTest, PoseChannelIsOffByDefault) {
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_);
  bot_core::pose_t p{};
  p.utime = 5000;
  publish("POSE", p);
  drain();
  EXPECT_EQ(buffer_.count(), 0u);
  EXPECT_EQ(in.malformed(), 0u);
}

TEST_F(VelocityInputTest, GyroOnlyDropsLinearVelocity) {
  VelocityInputConfig cfg;
  cfg.pose_channel = "POSE";
  cfg.gyro_only = true;
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_, cfg);
  // Linear velocity beyond the sanity limit: not rejected, since it is not used.
  publish("RSD_VELOCITY", velocity(1000, rsd::velocity_t::FRAME_CAMERA, 0.1, 0.2, 0.3, 500, 0, 0));
  bot_core::pose_t p{};
  p.utime = 2000;
  p.rotation_rate[2] = 0.7;
  p.vel[0] = 3.0;
  publish("POSE", p);
  drain();
  ASSERT_EQ(buffer_.count(), 2u);
  EXPECT_EQ(buffer_.rejected(), 0u);
  for (int64_t t : {1000, 2000}) {
    const auto s = at(t);
    EXPECT_FALSE(s.has_linear);
    EXPECT_EQ(s.v[0], 0.0);
  }
  EXPECT_EQ(at(2000).w[2], 0.7);
}

TEST_F(VelocityInputTest, InsaneSamplesAreRejectedByTheBuffer) {
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_);
  publish("RSD_VELOCITY", velocity(1000, rsd::velocity_t::FRAME_CAMERA, 0, 0, 50, 0, 0, 0));  // > 20 rad/s
  publish("RSD_VELOCITY", velocity(2000, rsd::velocity_t::FRAME_CAMERA, 0, 0, 1, 0, 0, 0));
  publish("RSD_VELOCITY", velocity(1500, rsd::velocity_t::FRAME_CAMERA, 0, 0, 1, 0, 0, 0));  // back in time
  drain();
  EXPECT_EQ(in.malformed(), 0u);
  EXPECT_EQ(buffer_.count(), 1u);
  EXPECT_EQ(buffer_.rejected(), 2u);
}

TEST_F(VelocityInputTest, ThreadReceivesUntilStopped) {
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_);
  in.start();
  publish("RSD_VELOCITY", velocity(1000, rsd::velocity_t::FRAME_CAMERA, 0, 0, 1, 0, 0, 0));
  // Waits for the sample, not for a time: the limit only ends a run that hangs.
  for (int i = 0; i < 12000 && buffer_.count() == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  in.stop();
  EXPECT_EQ(buffer_.count(), 1u);
}


namespace {
Config load_text(const std::string& yaml) {
  char name[] = "/tmp/rsd-velocity-config-XXXXXX";
  const int fd = mkstemp(name);
  EXPECT_GE(fd, 0);
  if (fd >= 0) close(fd);
  std::ofstream(name) << yaml;
  try {
    Config c = load_config(name);
    std::remove(name);
    return c;
  } catch (...) {
    std::remove(name);
    throw;
  }
}
}  // namespace

TEST(VelocityInputConfig, KeysAreReadRowMajor) {
  const Config c = load_text(
      "velocity:\n  pose_channel: POSE\n  imu_to_camera: [0, -1, 0, 1, 0, 0, 0, 0, 1]\n"
      "  body_to_camera: [0, 1, 0, 0, 0, 1, 1, 0, 0]\n  gyro_only: true\n");
  EXPECT_EQ(c.velocity_input.pose_channel, "POSE");
  EXPECT_EQ(c.velocity_input.imu_to_camera, rot_z90());
  EXPECT_EQ(c.velocity_input.body_to_camera(0, 1), 1.0);
  EXPECT_EQ(c.velocity_input.body_to_camera(1, 2), 1.0);
  EXPECT_EQ(c.velocity_input.body_to_camera(2, 0), 1.0);
  EXPECT_TRUE(c.velocity_input.gyro_only);
  const Config d = load_text("{}\n");
  EXPECT_TRUE(d.velocity_input.pose_channel.empty());
  EXPECT_EQ(d.velocity_input.imu_to_camera, Eigen::Matrix3d::Identity());
  EXPECT_FALSE(d.velocity_input.gyro_only);
}

TEST(VelocityInputConfig, NonRotationIsAnErrorNamingTheKey) {
  try {
    load_text("velocity:\n  imu_to_camera: [1, 0, 0, 0, 1, 0, 0, 0, -1]\n");
    FAIL() << "a reflection was accepted";
  } catch (const rsd::formats::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("'velocity.imu_to_camera' must be a rotation"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_text("velocity:\n  body_to_camera: [1, 0, 0]\n"), rsd::formats::ConfigError);
  EXPECT_THROW(load_text("velocity:\n  pose_channel: RSD_VELOCITY\n"), rsd::formats::ConfigError);
}

// Issue 16, defect 1: utime * 1000 overflowed on extreme stamps (undefined behaviour; the
// sanitizer build aborted). They are refused and counted, in camera and IMU axes and as poses.
TEST_F(VelocityInputTest, ExtremeStampsAreRefusedAndCounted) {
  VelocityInputConfig cfg;
  cfg.pose_channel = "POSE";
  cfg.imu_time_offset_s = 0.5;
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_, cfg);
  for (const int64_t t : {INT64_MAX, INT64_MIN, INT64_MAX / 1000 + 1, -(INT64_MAX / 1000) - 1}) {
    publish("RSD_VELOCITY", velocity(t, rsd::velocity_t::FRAME_CAMERA, 0.1, 0, 0, 0, 0, 0));
    publish("RSD_VELOCITY", velocity(t, rsd::velocity_t::FRAME_IMU, 0.1, 0, 0, 0, 0, 0));
    bot_core::pose_t p{};
    p.utime = t;
    p.orientation[0] = 1;
    publish("POSE", p);
  }
  publish("RSD_VELOCITY", velocity(1000, rsd::velocity_t::FRAME_CAMERA, 0.1, 0, 0, 0, 0, 0));
  drain();
  EXPECT_EQ(buffer_.rejected(), 12u);
  EXPECT_EQ(buffer_.count(), 1u);
  EXPECT_EQ(in.malformed(), 0u);
}

// With a live camera, messages share its clock (CLOCK_MONOTONIC): one stamped a minute away is
// refused and counted, one stamped now is taken; without the check (a replay) both would be.
TEST_F(VelocityInputTest, WithALiveCameraStampsFarFromTheClockAreRefused) {
  VelocityInputConfig cfg;
  cfg.max_clock_offset_s = 5;
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_, cfg);
  in.set_clock_check(true);
  const int64_t now_us = std::chrono::duration_cast<std::chrono::microseconds>(
                             std::chrono::steady_clock::now().time_since_epoch()).count();
  publish("RSD_VELOCITY", velocity(now_us + 60'000'000, rsd::velocity_t::FRAME_CAMERA, 0.1, 0, 0, 0, 0, 0));
  publish("RSD_VELOCITY", velocity(now_us - 60'000'000, rsd::velocity_t::FRAME_IMU, 0.1, 0, 0, 0, 0, 0));
  publish("RSD_VELOCITY", velocity(now_us, rsd::velocity_t::FRAME_CAMERA, 0.2, 0, 0, 0, 0, 0));
  drain();
  EXPECT_EQ(buffer_.rejected(), 2u);
  EXPECT_EQ(buffer_.count(), 1u);
  EXPECT_EQ(at(now_us).w[0], 0.2);
}

// Issue 16, fault matrix: a second of a 10 kHz flood in which every other message is NaN,
// infinite, wildly stamped or not a velocity at all. Every good sample goes in, every bad one
// is counted, and the buffer answers for the good time line afterwards.
TEST_F(VelocityInputTest, AFloodOfBadMessagesLosesNoGoodSample) {
  VelocityInput in(lcm_, "RSD_VELOCITY", buffer_);
  const double inf = std::numeric_limits<double>::infinity(), nan = std::nan("");
  int good = 0, bad = 0, garbage = 0;
  for (int i = 0; i < 10000; ++i) {
    const int64_t t = 1'000'000 + i * 100;  // 10 kHz
    switch (i % 6) {
      case 1: publish("RSD_VELOCITY", velocity(t, rsd::velocity_t::FRAME_CAMERA, nan, 0, 0, 0, 0, 0)), ++bad; break;
      case 3: publish("RSD_VELOCITY", velocity(t, rsd::velocity_t::FRAME_IMU, 0, inf, 0, 0, 0, 0)), ++bad; break;
      case 5: {
        const int64_t wild = (i % 12 == 5) ? INT64_MAX - i : t + 3'600'000'000LL;  // beyond range, or an hour ahead
        publish("RSD_VELOCITY", velocity(wild, rsd::velocity_t::FRAME_CAMERA, 0.1, 0, 0, 0, 0, 0)), ++bad;
        break;
      }
      case 4: {
        const uint8_t junk[13] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13};
        publish_raw("RSD_VELOCITY", junk, sizeof junk), ++garbage;
        break;
      }
      default: publish("RSD_VELOCITY", velocity(t, rsd::velocity_t::FRAME_CAMERA, 0.001 * i, 0, 0, 0, 0, 0)), ++good;
    }
    if (i % 500 == 499) drain();  // memq's queue is served as the LCM thread would
  }
  drain();
  EXPECT_EQ(buffer_.count(), static_cast<uint64_t>(good));
  EXPECT_EQ(buffer_.rejected(), static_cast<uint64_t>(bad));
  EXPECT_EQ(in.malformed(), static_cast<uint64_t>(garbage));
  EXPECT_EQ(buffer_.time_line_changes(), 0u);
  EXPECT_NEAR(at(1'000'000 + 9996 * 100).w[0], 0.001 * 9996, 1e-12);
}
