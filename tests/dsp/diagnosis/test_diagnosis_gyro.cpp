// The diagnosis's gyro track (dsp/diagnosis/gyro.hpp) against the true orientation of a smooth
// motion, and its agreement with the nominal model's integrate_gyro at the samples.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <utility>

#include "dsp/diagnosis/gyro.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/sim/smooth_motion.hpp"

using namespace rsd::dsp;
using Eigen::Vector3d;

namespace {

SmoothPose test_pose() {
  return SmoothPose{Vector3d::Zero(), Eigen::Matrix3d::Identity(), SmoothSignal3(3, Vector3d::Zero(), 1.0),
                    SmoothSignal3(4, Vector3d::Constant(0.25), 1.2)};
}

// Irregular stamps: intervals drawn from 5 to 50 ms (20-200 Hz).
std::vector<double> irregular_stamps(double t_end, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> rate(20, 200);
  std::vector<double> t;
  for (double s = 0; s <= t_end; s += 1.0 / rate(rng)) t.push_back(s);
  return t;
}

// Largest error of the rotation over one frame interval (33 ms, what a match transfers
// through) along a dense grid of start times.
template <class At>
double worst_frame_error(const SmoothPose& pose, At at, double t_end) {
  double worst = 0;
  for (double t = 0.1; t < t_end - 0.2; t += 1e-3) {
    const Eigen::Quaterniond truth = pose.orientation(t).conjugate() * pose.orientation(t + 1.0 / 30);
    worst = std::max(worst, truth.angularDistance(at(t).conjugate() * at(t + 1.0 / 30)));
  }
  return worst;
}

}  // namespace

TEST(DiagnosisGyro, IrregularSamplingStaysWithinATenthMilliradianOverAFrame) {
  // At 20-200 Hz a slerp between integrated samples (and integrate_gyro's first-order slopes on
  // the irregular grid) is off by milliradians over a frame interval; the track's partial
  // Hermite integral with second-order slopes must be well over an order of magnitude better.
  const SmoothPose pose = test_pose();
  std::vector<GyroSample> g;
  for (double t : irregular_stamps(3.0, 2)) g.push_back({t, pose.body_rate(t)});
  const GyroTrack track(clean_gyro(g), Vector3d::Zero(), Eigen::Matrix3d::Identity());
  const OrientationTrack slerped = integrate_gyro(g, Vector3d::Zero());
  const double worst =
      worst_frame_error(pose, [&](double t) { return Eigen::Quaterniond(track.camera_at(t)); }, 3.0);
  const double slerp_worst = worst_frame_error(pose, [&](double t) { return slerped.at(t); }, 3.0);
  std::printf("worst rotation error over a frame: Hermite track %.3g rad, slerped samples %.3g rad\n", worst,
              slerp_worst);
  EXPECT_LT(worst, 1.5e-4);  // 0.2 px at f = 1450, at the worst 50 ms interval
  EXPECT_LT(worst, slerp_worst / 30);
}

// RMS error of the rotation over one frame interval along a dense grid of start times, and the
// RMS of that rotation itself.
template <class At>
std::pair<double, double> rms_frame_error(const SmoothPose& pose, At at, double t_end) {
  double e = 0, r = 0;
  int n = 0;
  for (double t = 0.1; t < t_end - 0.2; t += 1e-3, ++n) {
    const Eigen::Quaterniond truth = pose.orientation(t).conjugate() * pose.orientation(t + 1.0 / 30);
    e += std::pow(truth.angularDistance(at(t).conjugate() * at(t + 1.0 / 30)), 2);
    r += std::pow(truth.angularDistance(Eigen::Quaterniond::Identity()), 2);
  }
  return {std::sqrt(e / n), std::sqrt(r / n)};
}

TEST(DiagnosisGyro, StampJitterOfAThirdOfThePeriodDoesNotBlowUpTheSlopes) {
  // A regular 200 Hz gyro whose stamps jitter by 2 ms (a logger that stamps samples as they
  // arrive): neighbours come stamped almost together or swapped. The parabola's slope divided
  // by those intervals and the rotation over a frame erred by a quarter of itself; with the
  // slope's intervals floored at half the median it must stay near what the stamps' error
  // itself costs: integrate_gyro's first-order slopes, slerped, on the same samples.
  const SmoothPose pose = test_pose();
  std::mt19937 rng(7);
  std::normal_distribution<double> jitter(0, 0.002);
  std::vector<GyroSample> g;
  for (double t = 0; t <= 3.0; t += 0.005) g.push_back({t + jitter(rng), pose.body_rate(t)});
  const std::vector<GyroSample> c = clean_gyro(g);
  const GyroTrack track(c, Vector3d::Zero(), Eigen::Matrix3d::Identity());
  const OrientationTrack slerped = integrate_gyro(c, Vector3d::Zero());
  const auto [err, rot] = rms_frame_error(pose, [&](double t) { return Eigen::Quaterniond(track.camera_at(t)); }, 3.0);
  const auto [slerp_err, rot2] = rms_frame_error(pose, [&](double t) { return slerped.at(t); }, 3.0);
  std::printf("RMS rotation over a frame %.3g rad; its error: Hermite track %.3g rad, slerped samples %.3g rad\n", rot, err,
              slerp_err);
  EXPECT_LT(err, 0.03 * rot);
  EXPECT_LT(err, 1.5 * slerp_err);
}

TEST(DiagnosisGyro, RepeatedStampsKeepTheFirstSampleAndStayFinite) {
  const std::vector<GyroSample> g = {{0.02, Vector3d(3, 0, 0)}, {0.0, Vector3d(1, 0, 0)}, {0.01, Vector3d(2, 0, 0)},
                                     {0.01, Vector3d(9, 9, 9)}, {0.01, Vector3d(8, 8, 8)}, {0.03, Vector3d(4, 0, 0)}};
  const std::vector<GyroSample> c = clean_gyro(g);
  ASSERT_EQ(c.size(), 4u);
  EXPECT_DOUBLE_EQ(c[1].t, 0.01);
  EXPECT_DOUBLE_EQ(c[1].w.x(), 2.0);  // the first of the three stamped 0.01
  const GyroTrack track(c, Vector3d::Zero(), Eigen::Matrix3d::Identity());
  for (double t = -0.01; t < 0.05; t += 1e-3) EXPECT_TRUE(track.camera_at(t).allFinite()) << t;
  // w = 1 + 100 t exactly on the linear rate: the integral to 0.03 is 0.03 + 50 * 0.03^2.
  EXPECT_NEAR(log_so3(track.camera_at(0.03)).x(), 0.03 + 50 * 0.0009, 1e-12);
}

TEST(DiagnosisGyro, BiasAndImuToCameraAreApplied) {
  const SmoothPose pose = test_pose();
  const Vector3d b(0.01, -0.02, 0.005);
  Eigen::Matrix3d R_ic;
  R_ic << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  std::vector<GyroSample> clean, biased;
  for (double t : irregular_stamps(2.0, 3)) clean.push_back({t, pose.body_rate(t)}), biased.push_back({t, pose.body_rate(t) + b});
  const GyroTrack a(clean_gyro(clean), Vector3d::Zero(), R_ic), c(clean_gyro(biased), b, R_ic);
  // Spec: R_c = R_imu R_ic^T, so the camera-frame relative rotation is R_ic dR_imu R_ic^T.
  const Eigen::Matrix3d rel = a.camera_at(0.5).transpose() * a.camera_at(1.5);
  const Eigen::Matrix3d imu_rel = (pose.orientation(0.5).conjugate() * pose.orientation(1.5)).toRotationMatrix();
  EXPECT_LT((rel - R_ic * imu_rel * R_ic.transpose()).norm(), 1e-4);  // integration error over 1 s
  EXPECT_LT((a.camera_at(1.7) - c.camera_at(1.7)).norm(), 1e-12);
  EXPECT_THROW(GyroTrack({}, Vector3d::Zero(), R_ic), std::invalid_argument);
}

// The vector forms the residuals use equal the matrix camera_at applied to the vector, inside
// the data (rotations of up to about 0.3 rad within an interval: both branches of the series)
// and held at either end, whatever interval the hint last held.
namespace {

// A fast irregular gyro (8 x the test pose's rate, 20-200 Hz for 2 s) ending in a 0.2 s interval
// at about 9 rad/s (|phi| past 0.25, the series' other branch), in a phone's axes.
std::vector<GyroSample> fast_gyro_with_a_long_interval() {
  const SmoothPose pose = test_pose();
  std::vector<GyroSample> g;
  for (double t : irregular_stamps(2.0, 5)) g.push_back({t, 8.0 * pose.body_rate(t)});
  g.push_back({2.2, Vector3d(6, -5, 4)});
  return g;
}
Eigen::Matrix3d phone_axes() {
  Eigen::Matrix3d R_ic;
  R_ic << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  return R_ic;
}

}  // namespace

TEST(DiagnosisGyro, TurningAVectorEqualsTheMatrix) {
  const Eigen::Matrix3d R_ic = phone_axes();
  const GyroTrack track(clean_gyro(fast_gyro_with_a_long_interval()), Vector3d(0.01, 0, -0.02), R_ic);
  const Vector3d v = Vector3d(0.3, -0.2, 1.0).normalized();
  // The hint carried from time to time as the residuals carry it (forwards, backwards, far).
  size_t hint = 0;
  for (double t : {-0.5, 0.0, 0.013, 0.014, 0.77, 0.0135, 1.5, 1.99, 2.15, 2.2, 3.0, 1.0}) {
    const Eigen::Matrix3d R = track.camera_at(t);
    EXPECT_LT((track.to_world(t, v, hint) - R * v).norm(), 1e-14) << t;
    EXPECT_LT((track.to_camera(t, v, hint) - R.transpose() * v).norm(), 1e-14) << t;
  }
}

// camera_at's rate and by_gyro against central differences of the track itself: the rate
// against R^T dR/dt, by_gyro against tracks built with the bias and scale moved (right
// perturbations: log(R^T R')). Across a 0.2 s interval at 9 rad/s too, where the Magnus term and
// the exponential's Jacobian are far from negligible, and held (rate zero) outside the data.
TEST(DiagnosisGyro, RateAndBiasScaleDerivativesAgreeWithDifferencesOfTheTrack) {
  const Eigen::Matrix3d R_ic = phone_axes();
  std::vector<GyroSample> g = fast_gyro_with_a_long_interval();
  g.push_back({2.21, Vector3d(6, -5, 4)});
  g = clean_gyro(g);
  const Vector3d bias(0.01, 0, -0.02), scale(1.01, 0.99, 1.002);
  const GyroTrack track(g, bias, R_ic, 0.1, scale);
  for (double t : {-0.5, 0.013, 0.77, 1.5, 1.99, 2.05, 2.15, 2.205, 3.0}) {
    size_t hint = 0;
    Vector3d rate;
    GyroTrack::ByGyro G;
    const Eigen::Matrix3d R = track.camera_at(t, hint, rate, &G);
    EXPECT_LT((R - track.camera_at(t)).norm(), 1e-14) << t;
    const double h = 1e-6;
    const Vector3d fd_rate = log_so3(track.camera_at(t - h).transpose() * track.camera_at(t + h)) / (2 * h);
    EXPECT_LT((rate - fd_rate).norm(), 1e-6 * std::max(1.0, fd_rate.norm())) << "rate at " << t;
    // R_c = R_imu E^T: the IMU orientation's right perturbation is E^T (R_c^T R_c') E.
    for (int j = 0; j < 6; ++j) {
      const double d = 1e-6;
      Vector3d b_hi = bias, b_lo = bias, s_hi = scale, s_lo = scale;
      (j < 3 ? b_hi : s_hi)[j % 3] += d, (j < 3 ? b_lo : s_lo)[j % 3] -= d;
      const GyroTrack hi(g, b_hi, R_ic, 0.1, s_hi), lo(g, b_lo, R_ic, 0.1, s_lo);
      const Vector3d fd = R_ic.transpose() * log_so3(lo.camera_at(t).transpose() * hi.camera_at(t)) / (2 * d);
      EXPECT_LT((G.col(j) - fd).norm(), 1e-6 * std::max(1.0, fd.norm())) << "column " << j << " at " << t;
    }
  }
}
