#include <gtest/gtest.h>

#include <random>

#include "dsp/geometry/camera_motion.hpp"

using namespace rsd::dsp;
using Eigen::Vector3d;

TEST(CameraMotion, ScrewMotionObeysItsDifferentialEquation) {
  // dX_c/dt = [w]x X_c + v for a static point, at every t (finite differences).
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int i = 0; i < 50; ++i) {
    Twist tw;
    tw.v = {u(rng), u(rng), u(rng)};
    tw.w = {u(rng), u(rng), u(rng)};
    const Vector3d X(u(rng), u(rng), 3 + u(rng));
    const ScrewMotion m(tw);
    for (double t : {0.0, 0.01, 0.1, 0.7}) {
      const double h = 1e-6;
      const Vector3d fd = (m.at(t + h) * X - m.at(t - h) * X) / (2 * h);
      const Vector3d Xc = m.at(t) * X;
      EXPECT_LT((fd - (tw.w.cross(Xc) + tw.v)).norm(), 1e-7);
    }
    EXPECT_LT((m.at(0).matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-15);
  }
}

TEST(CameraMotion, ScrewMotionIsAGroup) {
  Twist tw;
  tw.v = {0.3, -1, 0.5};
  tw.w = {1.2, 0.4, -2};
  const ScrewMotion m(tw);
  EXPECT_LT(((m.at(0.2) * m.at(0.3)).matrix() - m.at(0.5).matrix()).norm(), 1e-12);
  EXPECT_LT(((m.at(1e-7) * m.at(-1e-7)).matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-15);
}

TEST(CameraMotion, LinearisedMotionIsFirstOrderOfScrew) {
  Twist tw;
  tw.v = {0.3, -1, 0.5};
  tw.w = {1.2, 0.4, -2};
  const Vector3d X(0.5, 0.2, 4);
  for (double t : {1e-2, 1e-3}) {
    const double diff = (ScrewMotion(tw).at(t) * X - LinearisedMotion(tw).at(t) * X).norm();
    EXPECT_NEAR(diff / (t * t), 0.5 * (tw.w.cross(tw.w.cross(X) + tw.v)).norm(), 0.05);
  }
}

TEST(CameraMotion, ExpLogRoundTrip) {
  const Vector3d phi(0.3, -1.1, 0.7);
  EXPECT_LT((log_so3(exp_so3(phi)) - phi).norm(), 1e-12);
  EXPECT_LT((exp_so3(Vector3d(1e-10, 0, 0)) - Eigen::Matrix3d::Identity()).norm(), 2e-10);
}

TEST(CameraMotion, SampledTrajectoryInterpolatesLinearAndSlerp) {
  std::vector<SampledTrajectory::Sample> s = {
      {0.0, Eigen::Quaterniond::Identity(), Vector3d(0, 0, 0)},
      {1.0, Eigen::Quaterniond(Eigen::AngleAxisd(0.8, Vector3d::UnitZ())), Vector3d(2, 0, -4)},
  };
  const SampledTrajectory traj(s);
  const Eigen::Affine3d g = traj.at(0.25);  // camera-from-world
  // Camera at 0.25: position (0.5, 0, -1), yaw 0.2 rad.
  const Eigen::Matrix3d R_wc = Eigen::AngleAxisd(0.2, Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_LT((g.linear() - R_wc.transpose()).norm(), 1e-12);
  EXPECT_LT((g.inverse().translation() - Vector3d(0.5, 0, -1)).norm(), 1e-12);
  // Held at the ends.
  EXPECT_LT((traj.at(-5).matrix() - traj.at(0).matrix()).norm(), 1e-15);
  EXPECT_LT((traj.at(9).matrix() - traj.at(1).matrix()).norm(), 1e-15);
  EXPECT_THROW(SampledTrajectory({}), std::invalid_argument);
}

// IntegratedMotion with constant rates is the screw motion of the negated twist (the scene's
// twist in camera axes): exactly for the rotation, to the midpoint rule's second order for the
// translation (steps of 4 ms here: far below 1e-9 m).
TEST(IntegratedMotion, ConstantRatesAreTheScrewMotion) {
  const Vector3d w(0.3, -1.2, 0.8), v(0.5, 0.1, -2.0);
  IntegratedMotion::Knot k[9];
  for (int i = 0; i < 9; ++i) k[i] = {-0.004 + 0.004 * i, w, v};
  const IntegratedMotion m(k, 9);
  const ScrewMotion s(Twist{-v, -w});
  for (double t : {-0.02, -0.003, 0.0, 0.0101, 0.027, 0.05}) {
    const Eigen::Affine3d a = m.at(t), b = s.at(t);
    EXPECT_LT((a.linear() - b.linear()).norm(), 1e-12) << t;
    EXPECT_LT((a.translation() - b.translation()).norm(), 1e-9) << t;
  }
  EXPECT_LT((m.at(0).matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-15);  // the reference: t = 0
}

// About a fixed axis the rotation angle is the integral of the rate, linear here: exact.
TEST(IntegratedMotion, RateLinearInTimeAboutOneAxisIntegratesExactly) {
  const double a = 0.7, b = 40.0;  // rad/s, rad/s^2
  IntegratedMotion::Knot k[5];
  for (int i = 0; i < 5; ++i) {
    const double t = 0.01 * i;
    k[i] = {t, Vector3d(0, 0, a + b * t), Vector3d::Zero()};
  }
  const IntegratedMotion m(k, 5);
  for (double t : {0.0, 0.005, 0.013, 0.04}) {
    const double angle = a * t + 0.5 * b * t * t;  // camera turned by this; the scene by minus it
    const Eigen::Matrix3d want = Eigen::AngleAxisd(-angle, Vector3d::UnitZ()).toRotationMatrix();
    EXPECT_LT((m.at(t).linear() - want).norm(), 1e-12) << t;
  }
}

// A rate whose axis turns: against a brute-force integration with 20000 steps.
TEST(IntegratedMotion, TurningAxisAgainstFineIntegration) {
  auto w = [](double t) { return Vector3d(1.5 * std::cos(30 * t), 1.5 * std::sin(30 * t), 0.4); };
  IntegratedMotion::Knot k[IntegratedMotion::kMaxKnots];
  const int n = 17;
  for (int i = 0; i < n; ++i) k[i] = {0.002 * i, w(0.002 * i), Vector3d::Zero()};
  const IntegratedMotion m(k, n);
  Eigen::Matrix3d Q = Eigen::Matrix3d::Identity();  // camera axes in the reference
  const double T = 0.03;
  const int steps = 20000;
  for (int i = 0; i < steps; ++i) Q = Q * exp_so3(w((i + 0.5) * T / steps) * (T / steps));
  EXPECT_LT((m.at(T).linear() - Q.transpose()).norm(), 2e-5);
  // One rate held for the frame (what a single twist does) is far off.
  EXPECT_GT((ScrewMotion(Twist{Vector3d::Zero(), -w(0.5 * T)}).at(T).linear() - Q.transpose()).norm(), 1e-3);
  EXPECT_THROW(IntegratedMotion(k, 0), std::invalid_argument);
}
