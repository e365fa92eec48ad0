// The simulator's hidden rig physics (an IMU clock offset, a rotated mount, gyro bias and
// scale) and the calibration that undoes them: the simulated gyro's samples, through the
// daemon's velocity input told the true calibration, give the same angular velocity on the
// camera clock as the same simulation without the physics; told nothing, they do not.
#include <gtest/gtest.h>
#include <lcm/lcm.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "daemon/velocity_buffer.hpp"
#include "daemon/velocity_input.hpp"
#include "drivers/sim_source.hpp"

namespace rsd {
namespace {

std::vector<drivers::VelocitySample> samples(const drivers::SimSourceConfig& cfg, int frames) {
  drivers::SimSource src(cfg);
  std::vector<drivers::VelocitySample> out;
  src.set_velocity_sink([&](const drivers::VelocitySample& s) { out.push_back(s); });
  src.open();
  src.start();
  dsp::Image img(cfg.camera.width, cfg.camera.height, cfg.format);
  drivers::FrameMeta meta;
  for (int k = 0; k < frames; ++k) src.capture(img.view(), meta, std::chrono::milliseconds(1000));
  return out;
}

// Fills `buffer` with the samples through a velocity input with this calibration.
void through(const std::vector<drivers::VelocitySample>& s, const daemon::VelocityInputConfig& cfg,
             daemon::VelocityBuffer& buffer) {
  lcm_t* lcm = lcm_create("memq://");
  {
    daemon::VelocityInput in(lcm, "RSD_VELOCITY_TEST", buffer, cfg);
    for (const auto& x : s) in.deliver(x);
  }
  lcm_destroy(lcm);
}

TEST(SimRigPhysics, TheTrueCalibrationRecoversTheCameraRate) {
  drivers::SimSourceConfig base;
  base.camera = dsp::CameraModel::from_hfov(64, 48, 1.0);
  base.realtime = false;
  base.noise_grey = 0;
  drivers::SimSourceConfig hidden = base;
  hidden.imu_time_offset_s = 0.012;
  hidden.imu_mount_rotation_rad = {0.01, -0.02, 0.015};
  hidden.gyro_scale = {1.02, 0.98, 1.01};
  hidden.gyro_bias = {0.01, -0.005, 0.002};
  const auto truth = samples(base, 10), measured = samples(hidden, 10);
  ASSERT_GT(truth.size(), 50u);
  ASSERT_FALSE(truth.front().imu_frame);
  ASSERT_TRUE(measured.front().imu_frame);

  daemon::VelocityInputConfig cal;  // what a correct calibration file says
  cal.imu_time_offset_s = 0.012;
  const Eigen::Vector3d r = hidden.imu_mount_rotation_rad;
  cal.imu_to_camera = Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix();
  cal.gyro_scale = hidden.gyro_scale;
  cal.gyro_bias_rad_s = hidden.gyro_bias;
  daemon::VelocityBuffer want, got, naive;
  through(truth, {}, want);
  through(measured, cal, got);
  through(measured, {}, naive);

  // Each run starts its own clock: the first sample is at camera time 0 (t_imu = 12 ms).
  const int64_t t0 = truth.front().t_ns, t0_hidden = measured.front().t_ns - 12'000'000;
  double worst = 0, naive_worst = 0;
  for (int k = 5; k < 40; ++k) {  // camera times inside both streams
    const int64_t dt = k * 5'000'000LL;
    daemon::VelocityEstimate a, b, c;
    ASSERT_EQ(want.at(t0 + dt, a), daemon::VelocityStatus::Ok);
    ASSERT_EQ(got.at(t0_hidden + dt, b), daemon::VelocityStatus::Ok);
    ASSERT_EQ(naive.at(t0_hidden + dt, c), daemon::VelocityStatus::Ok);
    for (int i = 0; i < 3; ++i) {
      worst = std::max(worst, std::abs(a.sample.w[i] - b.sample.w[i]));
      naive_worst = std::max(naive_worst, std::abs(a.sample.w[i] - c.sample.w[i]));
    }
  }
  std::printf("angular rate error: calibrated %.3g rad/s, uncalibrated %.3g rad/s\n", worst, naive_worst);
  EXPECT_LT(worst, 1e-4);       // interpolation between stamps that differ by the microsecond rounding
  EXPECT_GT(naive_worst, 5e-3);  // the bias alone is 10 mrad/s
}

}  // namespace
}  // namespace rsd
