// The gyro's axes found from the pictures (dsp/diagnosis/imu_axes.hpp): the 24 axis rotations
// against a brute-force count, and a phone-like matches recording whose gyro is mounted in a
// permuted, mirrored-pair orientation, a 20 ms clock offset and outliers, told the identity.
#include <gtest/gtest.h>

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

TEST(ImuAxes, APhonesGyroAxesFoundFromItsMatches) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("ImuAxes.TheTwentyFourRotationsThatTakeAxesOntoAxes and DiagnosisMatches.*");
  SimConfig c = rsd::test::simulation(ObservationKind::Matches, 3, 4.0, 0.5);
  c.start_time_s = 1000;
  c.outlier_fraction = 0.1;
  c.matches_per_pair = 60;
  c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2;
  Eigen::Matrix3d truth;
  truth << 0, -1, 0, 0, 0, 1, -1, 0, 0;  // the gyro's x is the camera's -z, y is -x, z is y
  c.nominal.imu_to_camera = truth;
  c.effects.time_offset_s = 0.02;
  Recording rec = simulate_recording(c).rec;
  rec.nominal.imu_to_camera = Eigen::Matrix3d::Identity();  // what a first configuration says
  const AxesSearch s = search_imu_axes(rec);
  ASSERT_EQ(s.ranked.size(), 24u);
  std::printf("best %.3f px at %.3f s, runner-up %.3f px\n", s.ranked[0].scale_px, s.ranked[0].time_offset_s, s.ranked[1].scale_px);
  EXPECT_TRUE(s.ranked[0].imu_to_camera.isApprox(truth)) << s.ranked[0].imu_to_camera;
  EXPECT_TRUE(s.decisive());
  EXPECT_NEAR(s.ranked[0].time_offset_s, 0.02, 0.002);
  EXPECT_LT(s.ranked[0].scale_px, 1.0);  // the noise's 0.7 px per coordinate of a match
}

}  // namespace
}  // namespace rsd::dsp
