// The gyro's axes found from the pictures (dsp/diagnosis/imu_axes.hpp): the 24 axis rotations
// against a brute-force count, a phone-like matches recording whose gyro is mounted in a
// permuted, mirrored-pair orientation, a 20 ms clock offset and outliers, told the identity, and
// the same rig tilted off the axes as a calibration says it is.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <set>
#include <vector>

#include "dsp/diagnosis/imu_axes.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/support/sanitizer.hpp"

namespace rsd::dsp {
namespace {

TEST(ImuAxes, TheTwentyFourRotationsThatTakeAxesOntoAxes) {
  // Brute force: every 3x3 matrix of 0 and +-1 that is a rotation.
  int rotations = 0;
  for (int code = 0; code < 19683; ++code) {  // 3^9
    Eigen::Matrix3d M;
    for (int k = 0, c = code; k < 9; ++k, c /= 3) M(k / 3, k % 3) = c % 3 - 1;
    rotations += (M * M.transpose()).isApprox(Eigen::Matrix3d::Identity()) && M.determinant() > 0;
  }
  const std::vector<Eigen::Matrix3d> r = axis_rotations();
  ASSERT_EQ(static_cast<int>(r.size()), rotations);
  EXPECT_EQ(rotations, 24);
  std::set<std::vector<double>> distinct;
  for (const Eigen::Matrix3d& R : r) {
    EXPECT_TRUE((R * R.transpose()).isApprox(Eigen::Matrix3d::Identity()));
    EXPECT_DOUBLE_EQ(R.determinant(), 1.0);
    distinct.insert(std::vector<double>(R.data(), R.data() + 9));
  }
  EXPECT_EQ(distinct.size(), 24u);
}

// A phone-like matches recording whose gyro is mounted `imu_to_camera`, 20 ms late, with outliers.
Recording phone(const Eigen::Matrix3d& imu_to_camera) {
  SimConfig c = rsd::test::simulation(ObservationKind::Matches, 3, 4.0, 0.5);
  c.start_time_s = 1000;
  c.outlier_fraction = 0.1;
  c.matches_per_pair = 60;
  c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2;
  c.nominal.imu_to_camera = imu_to_camera;
  c.effects.time_offset_s = 0.02;
  return simulate_recording(c).rec;
}

// The gyro's x is the camera's -z, y is -x, z is y.
Eigen::Matrix3d permuted() {
  Eigen::Matrix3d p;
  p << 0, -1, 0, 0, 0, 1, -1, 0, 0;
  return p;
}

TEST(ImuAxes, APhonesGyroAxesFoundFromItsMatches) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("ImuAxes.TheTwentyFourRotationsThatTakeAxesOntoAxes and DiagnosisMatches.*");
  const Eigen::Matrix3d truth = permuted();
  Recording rec = phone(truth);
  rec.nominal.imu_to_camera = Eigen::Matrix3d::Identity();  // what a first configuration says
  const AxesSearch s = search_imu_axes(rec);
  ASSERT_EQ(s.ranked.size(), 24u);
  std::printf("best %.3f px at %.3f s, runner-up %.3f px\n", s.ranked[0].scale_px, s.ranked[0].time_offset_s, s.ranked[1].scale_px);
  EXPECT_TRUE(s.ranked[0].imu_to_camera.isApprox(truth)) << s.ranked[0].imu_to_camera;
  EXPECT_TRUE(s.decisive());
  EXPECT_NEAR(s.ranked[0].time_offset_s, 0.02, 0.002);
  EXPECT_LT(s.ranked[0].scale_px, 1.0);  // the noise's 0.7 px per coordinate of a match
}

TEST(ImuAxes, ACalibratedRigsTiltIsKeptWhicheverWayItsAxesAreLabelled) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("ImuAxes.TheTwentyFourRotationsThatTakeAxesOntoAxes and DiagnosisMatches.*");
  // A Kalibr-calibrated rig: the camera sits 2.5 degrees off the gyro's board axes. Ranked among
  // the bare axis orders, the given (right) matrix was not a candidate: the nearest order won
  // and the tool said the pictures do NOT follow motion.imu_to_camera.
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.044, Eigen::Vector3d(0.6, -0.48, 0.64).normalized()).toRotationMatrix();
  const Eigen::Matrix3d truth = tilt * permuted();
  Recording rec = phone(truth);
  const AxesSearch right = search_imu_axes(rec);
  std::printf("given the truth: best %.3f px, runner-up %.3f px\n", right.ranked[0].scale_px, right.ranked[1].scale_px);
  EXPECT_TRUE(right.ranked[0].imu_to_camera.isApprox(truth, 1e-12)) << right.ranked[0].imu_to_camera;
  EXPECT_TRUE(right.decisive());
  EXPECT_LT(right.ranked[0].scale_px, 1.0);
  EXPECT_TRUE(nearest_axis_rotation(truth).isApprox(permuted(), 1e-12));

  // The same tilt with the gyro's axes written in the camera's order: the right order is found
  // and the tilt kept, so `--imu-axes search` loses nothing of the calibration.
  rec.nominal.imu_to_camera = tilt;
  const AxesSearch wrong = search_imu_axes(rec);
  EXPECT_TRUE(wrong.ranked[0].imu_to_camera.isApprox(truth, 1e-12)) << wrong.ranked[0].imu_to_camera;
  EXPECT_TRUE(wrong.decisive());
}

}  // namespace
}  // namespace rsd::dsp
