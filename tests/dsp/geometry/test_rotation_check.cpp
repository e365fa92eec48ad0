// dsp::is_rotation against matrices whose nature is known by construction.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "dsp/geometry/rotation_check.hpp"

using rsd::dsp::is_rotation;

TEST(IsRotation, AcceptsRotationsAndRefusesReflectionsScalesAndNaN) {
  EXPECT_TRUE(is_rotation(Eigen::Matrix3d::Identity()));
  EXPECT_TRUE(is_rotation(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix()));
  EXPECT_TRUE(is_rotation(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix()));
  Eigen::Matrix3d reflection = Eigen::Matrix3d::Identity();
  reflection(2, 2) = -1;
  EXPECT_FALSE(is_rotation(reflection));
  EXPECT_FALSE(is_rotation(2.0 * Eigen::Matrix3d::Identity()));
  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(0, 1) = std::nan("");
  EXPECT_FALSE(is_rotation(nan));
}

TEST(IsRotation, HoldsItsToleranceOnBothSides) {
  // A rotation rounded to 7 digits (as a hand-written file has it) passes at 1e-6; one whose
  // entries are 1e-5 off does not, and passes at a tolerance of 1e-4.
  Eigen::Matrix3d r = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d rounded = (r * 1e7).array().round() / 1e7;
  EXPECT_TRUE(is_rotation(rounded));
  r(1, 1) += 1e-5;
  EXPECT_FALSE(is_rotation(r));
  EXPECT_TRUE(is_rotation(r, 1e-4));
}
