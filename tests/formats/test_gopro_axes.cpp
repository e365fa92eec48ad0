// A GoPro gyro's axes in rsd's camera frame (formats/gopro_axes.hpp), against turns worked by
// hand: the camera turned about one of its own axes (x right, y down, z forward), and what each
// of GoPro's documented channel orders then measures on GoPro's body axes (X to the camera's
// left, Y out of its back, Z up). The karma and MAX clips say their model and ORIN.
#include "formats/gopro_axes.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "formats/gpmf_mp4.hpp"

namespace rsd::formats {
namespace {

// The camera's rate imu_to_camera makes of a gyro sample.
Eigen::Vector3d camera_rate(const std::string& letters, const Eigen::Vector3d& sample) {
  const auto m = gopro_letters_to_camera(letters);
  EXPECT_TRUE(m.has_value()) << letters;
  return m ? Eigen::Vector3d(*m * sample) : Eigen::Vector3d::Constant(NAN);
}

TEST(GoProAxes, TheHero5sDocumentedOrderTurnsEachCameraAxisIntoItsChannel) {
  // HERO5 channels Z, X, Y. A turn about the optical axis (z, forward) is -1 about Y (out of the
  // back): the third channel; about x (right), -1 about X: the second; about y (down), -1 about Z.
  EXPECT_TRUE(camera_rate("ZXY", {0, 0, -1}).isApprox(Eigen::Vector3d(0, 0, 1)));
  EXPECT_TRUE(camera_rate("ZXY", {0, -1, 0}).isApprox(Eigen::Vector3d(1, 0, 0)));
  EXPECT_TRUE(camera_rate("ZXY", {-1, 0, 0}).isApprox(Eigen::Vector3d(0, 1, 0)));
  // The matrix the twenty-first session wrote for it from the same documentation.
  Eigen::Matrix3d documented;
  documented << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  EXPECT_TRUE(gopro_letters_to_camera("ZXY")->isApprox(documented));
}

TEST(GoProAxes, TheHero6sAndAnOrinWithNegativeChannels) {
  // HERO6: Y, -X, Z. A turn about y (down) is -1 about Z: the third channel, -1.
  EXPECT_TRUE(camera_rate("YxZ", {0, 0, -1}).isApprox(Eigen::Vector3d(0, 1, 0)));
  // About x (right): -1 about X, which the second channel measures negated: +1.
  EXPECT_TRUE(camera_rate("YxZ", {0, 1, 0}).isApprox(Eigen::Vector3d(1, 0, 0)));
  // A MAX's ORIN XzY: about z (forward) is -1 about Y, the third channel.
  EXPECT_TRUE(camera_rate("XzY", {0, 0, -1}).isApprox(Eigen::Vector3d(0, 0, 1)));
  // About y (down): -1 about Z, which the second channel measures negated: +1.
  EXPECT_TRUE(camera_rate("XzY", {0, 1, 0}).isApprox(Eigen::Vector3d(0, 1, 0)));
}

// The MAX clip's own MTRX (its GPMF, read by hand: floats 0 -1 0, 1 0 0, 0 0 1) takes a sample
// in its ORIN's order (XzY) to its ORIO's (ZXY): both orders must then give one camera rate.
TEST(GoProAxes, TheMaxsOwnMatrixFromOrinToOrioAgreesWithTheLetters) {
  Eigen::Matrix3d mtrx;
  mtrx << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_TRUE(gopro_letters_to_camera("XzY")->isApprox(*gopro_letters_to_camera("ZXY") * mtrx));
}

TEST(GoProAxes, EveryRightHandedOrderIsARotationAndNoMirrorIsTaken) {
  int rotations = 0, refused = 0;
  const std::string axes = "XYZxyz";
  for (char a : axes)
    for (char b : axes)
      for (char c : axes) {
        const std::string l{a, b, c};
        if (const auto m = gopro_letters_to_camera(l)) {
          EXPECT_TRUE((*m * m->transpose()).isIdentity(1e-12)) << l;
          EXPECT_NEAR(m->determinant(), 1.0, 1e-12) << l;
          ++rotations;
        } else {
          ++refused;
        }
      }
  // 48 signed permutations, half of them mirrors; the rest name an axis twice.
  EXPECT_EQ(rotations, 24);
  EXPECT_EQ(refused, 216 - 24);
  for (const char* bad : {"", "XY", "XYZW", "XYz", "XXY", "XyA", "xyz"}) EXPECT_FALSE(gopro_letters_to_camera(bad)) << bad;
}

TEST(GoProAxes, OrinFirstThenTheModelsDocumentedOrderElseNothing) {
  const auto orin = gopro_axes("XzY", "H19.03.01.30.00");
  ASSERT_TRUE(orin);
  EXPECT_EQ(orin->letters, "XzY");
  EXPECT_EQ(orin->source, "the gyro's ORIN 'XzY'");
  const auto hero5 = gopro_axes("", "HD5.02.02.00.00");
  ASSERT_TRUE(hero5);
  EXPECT_EQ(hero5->letters, "ZXY");
  EXPECT_EQ(hero5->source, "the order GoPro documents for the HERO5 Black (firmware HD5.02.02.00.00)");
  EXPECT_EQ(gopro_axes("", "HD6.01.60.00.00")->letters, "YxZ");
  EXPECT_FALSE(gopro_axes("", "H19.03.01.30.00"));  // a model without ORIN whose order is not documented
  EXPECT_FALSE(gopro_axes("", ""));
  try {
    gopro_axes("XYz", "");
    ADD_FAILURE() << "a mirrored ORIN was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ORIN 'XYz'"), std::string::npos) << e.what();
  }
}

TEST(GoProAxes, TheSampleClipsSayTheirModelAndOrin) {
  const GpmfVideo karma = read_gpmf_video(std::string(RSD_REAL_DATA_DIR) + "/gpmf/karma.mp4");
  EXPECT_EQ(karma.firmware, "HD5.02.02.00.00");
  EXPECT_EQ(gopro_axes(karma.orin, karma.firmware)->letters, "ZXY");
  const GpmfVideo max = read_gpmf_video(std::string(RSD_REAL_DATA_DIR) + "/gpmf/max-heromode.mp4");
  EXPECT_EQ(max.firmware, "H19.03.01.30.00");
  EXPECT_EQ(max.orin, "XzY");
}

}  // namespace
}  // namespace rsd::formats
