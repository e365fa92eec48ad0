// The recording-v1 observation model: the time model's fixed point, gyro integration, and the
// match model, each against an independent evaluation.
#include <gtest/gtest.h>

#include <random>

#include "dsp/observation/observation_model.hpp"
#include "dsp/sim/smooth_motion.hpp"

using namespace rsd::dsp;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

SmoothPose test_pose() {
  return SmoothPose{Vector3d(0, 0, -1.2), Eigen::Matrix3d::Identity(),
                    SmoothSignal3(3, Vector3d::Constant(0.2), 1.5), SmoothSignal3(4, Vector3d::Constant(0.3), 1.5)};
}

CameraModel hd() {
  CameraModel c;
  c.width = 1920, c.height = 1080, c.fx = c.fy = 1329.75, c.cx = 959.5, c.cy = 539.5;
  c.dist.k1 = -0.1;
  return c;
}

}  // namespace

TEST(ObservationModel, LandmarkIsTheFixedPointOfTimeModelAndProjection) {
  const SmoothPose pose = test_pose();
  const auto body = FunctionMotion([&](double t) {
    Eigen::Affine3d g = Eigen::Affine3d::Identity();
    g.linear() = pose.orientation(t).toRotationMatrix().transpose();
    g.translation() = -g.linear() * pose.position(t);
    return g;
  });
  for (Readout dir : {Readout::TopToBottom, Readout::BottomToTop}) {
    LandmarkSetup s{hd(), {}, Vector3d(0.03, -0.02, 0.05)};
    s.time.line_delay_s = 2.5e-5;
    s.time.readout = dir;
    s.time.time_offset_s = 0.013;
    s.time.drift_ppm = 300;
    s.time.t0 = 10.0;
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(-0.3, 0.3);
    int n = 0;
    for (int i = 0; i < 100; ++i) {
      const double T = 10.0 + 0.05 * i;
      const Vector3d X(u(rng), u(rng), 0.0);
      const auto p = predict_landmark(s, body, T, X);
      if (!p) continue;
      ++n;
      // Independent check of the spec's equations at the returned capture time.
      const double row_index = dir == Readout::TopToBottom ? p->pixel.y() : s.cam.height - 1 - p->pixel.y();
      EXPECT_NEAR(p->t_camera, T + s.time.line_delay_s * row_index, 1e-12);
      const double tm = p->t_camera + 0.013 + 300e-6 * (p->t_camera - 10.0);
      const Eigen::Matrix3d R = pose.orientation(tm).toRotationMatrix();
      const Vector3d pc = pose.position(tm) + R * s.lever_arm;
      const Vector2d q = s.cam.project(R.transpose() * (X - pc)).value();
      EXPECT_LT((q - p->pixel).norm(), 1e-6);
    }
    EXPECT_GT(n, 80);
  }
}

TEST(ObservationModel, GyroIntegrationConvergesToTheOrientation) {
  // Rates known only at the samples: the error must fall at least as dt^3 and be
  // small at an ordinary 1 kHz.
  const SmoothPose pose = test_pose();
  const Eigen::Quaterniond truth = pose.orientation(0).conjugate() * pose.orientation(1.9);
  auto error = [&](double dt) {
    std::vector<GyroSample> gyro;
    for (int i = 0; i * dt <= 2.0; ++i) gyro.push_back({i * dt, pose.body_rate(i * dt)});
    gyro.insert(gyro.begin() + 100, GyroSample(gyro[100]));  // a repeated stamp changes nothing
    return truth.angularDistance(integrate_gyro(gyro, Vector3d::Zero()).at(1.9));
  };
  const double e1 = error(1e-3), e2 = error(5e-4);
  EXPECT_LT(e1, 1e-7);
  EXPECT_GT(e1 / e2, 7.0);  // halving dt divides the error by ~8 (3rd order), not 4
  // A bias subtracted from biased samples gives the same track.
  std::vector<GyroSample> gyro, biased;
  for (double t = 0; t <= 2.0; t += 1e-3) gyro.push_back({t, pose.body_rate(t)});
  for (auto g : gyro) biased.push_back({g.t, g.w + Vector3d(0.01, -0.02, 0.005)});
  const OrientationTrack a = integrate_gyro(gyro, Vector3d::Zero());
  const OrientationTrack b = integrate_gyro(biased, Vector3d(0.01, -0.02, 0.005));
  EXPECT_LT(a.at(1.7).angularDistance(b.at(1.7)), 1e-12);
  EXPECT_THROW(integrate_gyro({}, Vector3d::Zero()), std::invalid_argument);
}

TEST(ObservationModel, MatchPredictionIsSymmetric) {
  const SmoothPose pose = test_pose();
  std::vector<OrientationTrack::Sample> s;
  for (double t = 0; t <= 3; t += 1e-3) s.push_back({t, pose.orientation(t)});
  const OrientationTrack track(s);
  MatchSetup m{hd(), {}};
  m.time.line_delay_s = 3e-5;
  m.time.time_offset_s = -0.2;
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(100, 1800), v(100, 980);
  int n = 0;
  for (int i = 0; i < 50; ++i) {
    const Vector2d a(u(rng), v(rng));
    const auto b = predict_match(m, track, 1.0, a, 1.0 + 1 / 30.0);
    if (!b) continue;
    const auto back = predict_match(m, track, 1.0 + 1 / 30.0, b->pixel, 1.0);
    ASSERT_TRUE(back.has_value());
    EXPECT_LT((back->pixel - a).norm(), 1e-6);
    ++n;
  }
  EXPECT_GT(n, 40);
}

TEST(ObservationModel, CameraOrientationFollowsImuToCamera) {
  // w_camera = R_ic w_imu: rotating the IMU about its x axis rotates the camera about R_ic x.
  const Eigen::Matrix3d R_ic = Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Quaterniond q_imu(Eigen::AngleAxisd(0.1, Vector3d::UnitX()));
  const Eigen::Quaterniond q_cam0 = camera_orientation(Eigen::Quaterniond::Identity(), R_ic);
  const Eigen::Quaterniond q_cam = camera_orientation(q_imu, R_ic);
  const Eigen::AngleAxisd rel(q_cam0.conjugate() * q_cam);  // rotation in camera axes
  EXPECT_NEAR(rel.angle(), 0.1, 1e-12);
  EXPECT_LT((rel.axis() - R_ic * Vector3d::UnitX()).norm(), 1e-12);
}
