// load_intrinsics: Kalibr camchain and ROS camera_info files, written here, parse to the exact
// numbers written; unsupported models and malformed files fail naming file:line:column and key.
#include "formats/intrinsics_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "formats/yaml_map.hpp"
#include "tests/support/temp_dir.hpp"

using rsd::formats::ConfigError;
using rsd::formats::Intrinsics;
using rsd::formats::load_intrinsics;

namespace test_intrinsics_file {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

// The files, in a directory of this process's that goes when it ends.
const rsd::test::TempDir& g_tmp = rsd::test::register_temp_dir("rsd-intr-");

std::string write(const std::string& name, const std::string& text) {
  const std::string path = g_tmp.path(name);
  std::ofstream(path) << text;
  return path;
}

// What kalibr_calibrate_rs_cameras / kalibr_calibrate_imu_camera write, two cameras.
const char* kKalibr = R"(cam0:
  cam_overlaps: [1]
  camera_model: pinhole
  distortion_coeffs: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
  distortion_model: radtan
  intrinsics: [458.654, 457.296, 367.215, 248.375]
  resolution: [752, 480]
  rostopic: /cam0/image_raw
  line_delay: 2.9e-05
  timeshift_cam_imu: 0.0021
cam1:
  T_cn_cnm1:
  - [0.9999972564779, 0.0023120128, 0.0003412653, -0.110073808127187]
  - [-0.0023171353, 0.9998980485, 0.0140022291, 0.000399121547014]
  - [-0.0003088423, -0.0140029786, 0.9999019, -0.000853702503358]
  - [0.0, 0.0, 0.0, 1.0]
  cam_overlaps: [0]
  camera_model: pinhole
  distortion_coeffs: [-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05]
  distortion_model: radtan
  intrinsics: [457.587, 456.134, 379.999, 255.238]
  resolution: [752, 480]
  rostopic: /cam1/image_raw
)";

// What camera_calibration (cameracalibrator.py) writes via camera_info_manager.
const char* kRos = R"(image_width: 1280
image_height: 720
camera_name: narrow_stereo
camera_matrix:
  rows: 3
  cols: 3
  data: [912.5, 0, 641.25, 0, 911.75, 359.5, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.125, 0.0625, 0.001, -0.002, 0.03125]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
projection_matrix:
  rows: 3
  cols: 4
  data: [900, 0, 640, 0, 0, 900, 360, 0, 0, 0, 1, 0]
)";

std::string error_of(const std::string& path, const std::string& camera = "") {
  try {
    load_intrinsics(path, camera);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto i = s.find(from);
  EXPECT_NE(i, std::string::npos) << from;
  return s.replace(i, from.size(), to);
}

}  // namespace

TEST(IntrinsicsFile, KalibrCamchainDefaultsToCam0WithLineDelay) {
  const Intrinsics in = load_intrinsics(write("kalibr.yaml", kKalibr));
  EXPECT_EQ(in.cam.width, 752);
  EXPECT_EQ(in.cam.height, 480);
  EXPECT_EQ(in.cam.fx, 458.654);
  EXPECT_EQ(in.cam.fy, 457.296);
  EXPECT_EQ(in.cam.cx, 367.215);
  EXPECT_EQ(in.cam.cy, 248.375);
  EXPECT_EQ(in.cam.dist.k1, -0.28340811);
  EXPECT_EQ(in.cam.dist.k2, 0.07395907);
  EXPECT_EQ(in.cam.dist.p1, 0.00019359);
  EXPECT_EQ(in.cam.dist.p2, 1.76187114e-05);
  EXPECT_EQ(in.cam.dist.k3, 0.0);
  ASSERT_TRUE(in.line_delay_s.has_value());
  EXPECT_EQ(*in.line_delay_s, 2.9e-05);
  ASSERT_TRUE(in.timeshift_cam_imu_s.has_value());
  EXPECT_EQ(*in.timeshift_cam_imu_s, 0.0021);
  EXPECT_NE(in.source.find("Kalibr"), std::string::npos);
  EXPECT_NE(in.source.find("cam0"), std::string::npos);
}

TEST(IntrinsicsFile, KalibrSelectsCam1) {
  const Intrinsics in = load_intrinsics(write("kalibr1.yaml", kKalibr), "cam1");
  EXPECT_EQ(in.cam.fx, 457.587);
  EXPECT_EQ(in.cam.fy, 456.134);
  EXPECT_EQ(in.cam.cx, 379.999);
  EXPECT_EQ(in.cam.cy, 255.238);
  EXPECT_EQ(in.cam.dist.k1, -0.28368365);
  EXPECT_EQ(in.cam.dist.k2, 0.07451284);
  EXPECT_EQ(in.cam.dist.p1, -0.00010473);
  EXPECT_EQ(in.cam.dist.p2, -3.55590700e-05);
  EXPECT_FALSE(in.line_delay_s.has_value());
  EXPECT_FALSE(in.timeshift_cam_imu_s.has_value());
  EXPECT_NE(in.source.find("cam1"), std::string::npos);
}

TEST(IntrinsicsFile, KalibrUnknownCameraListsAvailable) {
  const std::string path = write("kalibr5.yaml", kKalibr);
  const std::string err = error_of(path, "cam5");
  EXPECT_NE(err.find(path + ":1:1: 'cam5' is not in this Kalibr camchain (available: cam0, cam1)"), std::string::npos)
      << err;
}

TEST(IntrinsicsFile, KalibrOnlyCameraIsTheDefault) {
  const std::string one = replace(replace(kKalibr, "cam0:", "cam3:"), "cam1:", "cam3_extra:");
  EXPECT_EQ(load_intrinsics(write("kalibr-one.yaml", one)).cam.fx, 458.654);
}

// Kalibr's pinhole-equi camera: distortion_model equidistant, coefficients [k1, k2, k3, k4].
TEST(IntrinsicsFile, KalibrEquidistantIsThePinholeEquiLens) {
  const std::string fish = replace(replace(kKalibr, "distortion_model: radtan", "distortion_model: equidistant"),
                                   "[-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]", "[-0.0137, 0.0212, -0.0271, 0.0113]");
  const Intrinsics in = load_intrinsics(write("kalibr-fish.yaml", fish));
  EXPECT_EQ(in.cam.dist.model, rsd::dsp::LensModel::PinholeEqui);
  EXPECT_EQ(in.cam.dist.k1, -0.0137);
  EXPECT_EQ(in.cam.dist.k2, 0.0212);
  EXPECT_EQ(in.cam.dist.k3, -0.0271);
  EXPECT_EQ(in.cam.dist.k4, 0.0113);
  EXPECT_EQ(in.cam.dist.p1, 0);
  EXPECT_EQ(in.cam.dist.p2, 0);
  EXPECT_EQ(in.cam.fx, 458.654);
}

TEST(IntrinsicsFile, KalibrUnknownLensModelRefusedNamingTheModels) {
  const std::string path = write("kalibr-ds.yaml", replace(kKalibr, "distortion_model: radtan", "distortion_model: fov"));
  const std::string err = error_of(path);
  EXPECT_NE(err.find(path + ":5:21: 'cam0.distortion_model' is 'fov'"), std::string::npos) << err;
  EXPECT_NE(err.find("'radtan', 'equidistant'"), std::string::npos) << err;
}

TEST(IntrinsicsFile, KalibrMissingIntrinsicsNamesFileLineAndKey) {
  const std::string path = write("kalibr-noK.yaml", replace(kKalibr, "  intrinsics: [458.654, 457.296, 367.215, 248.375]\n", ""));
  const std::string err = error_of(path);
  EXPECT_NE(err.find(path + ":2:3: 'cam0.intrinsics' is missing"), std::string::npos) << err;
}

TEST(IntrinsicsFile, KalibrWrongTypeNamesKey) {
  const std::string path = write("kalibr-type.yaml", replace(kKalibr, "resolution: [752, 480]", "resolution: 752x480"));
  const std::string err = error_of(path);
  EXPECT_NE(err.find(path + ":7:15: 'cam0.resolution' must be a list of 2 numbers"), std::string::npos) << err;
}

TEST(IntrinsicsFile, RosPlumbBob) {
  const Intrinsics in = load_intrinsics(write("ros.yaml", kRos));
  EXPECT_EQ(in.cam.width, 1280);
  EXPECT_EQ(in.cam.height, 720);
  EXPECT_EQ(in.cam.fx, 912.5);
  EXPECT_EQ(in.cam.fy, 911.75);
  EXPECT_EQ(in.cam.cx, 641.25);
  EXPECT_EQ(in.cam.cy, 359.5);
  EXPECT_EQ(in.cam.dist.k1, -0.125);
  EXPECT_EQ(in.cam.dist.k2, 0.0625);
  EXPECT_EQ(in.cam.dist.p1, 0.001);
  EXPECT_EQ(in.cam.dist.p2, -0.002);
  EXPECT_EQ(in.cam.dist.k3, 0.03125);
  EXPECT_FALSE(in.line_delay_s.has_value());
  EXPECT_NE(in.source.find("narrow_stereo"), std::string::npos);
}

// ROS's fisheye camera_info (camera_calibration's fisheye model): distortion_model equidistant, D
// of four coefficients.
TEST(IntrinsicsFile, RosEquidistantIsThePinholeEquiLens) {
  const std::string fish = replace(replace(kRos, "distortion_model: plumb_bob", "distortion_model: equidistant"),
                                   "  cols: 5\n  data: [-0.125, 0.0625, 0.001, -0.002, 0.03125]",
                                   "  cols: 4\n  data: [0.0469, -0.0135, 0.0021, -0.0003]");
  const Intrinsics in = load_intrinsics(write("ros-fish.yaml", fish));
  EXPECT_EQ(in.cam.dist, rsd::dsp::Distortion::equidistant(0.0469, -0.0135, 0.0021, -0.0003));
  // Five coefficients are plumb_bob's, not a fisheye's: refused by key.
  const std::string five = replace(kRos, "distortion_model: plumb_bob", "distortion_model: equidistant");
  const std::string path = write("ros-fish5.yaml", five);
  const std::string err = error_of(path);
  EXPECT_NE(err.find("'distortion_coefficients' must have 4 coefficients [k1, k2, k3, k4] for equidistant, has 5"),
            std::string::npos) << err;
}

TEST(IntrinsicsFile, RosRationalPolynomialWithZeroExtraTermsAccepted) {
  const std::string text = replace(replace(replace(kRos, "plumb_bob", "rational_polynomial"), "cols: 5", "cols: 8"),
                                   "0.03125]", "0.03125, 0, 0, 0]");
  const Intrinsics in = load_intrinsics(write("ros-rat0.yaml", text));
  EXPECT_EQ(in.cam.dist.k3, 0.03125);
}

TEST(IntrinsicsFile, RosRationalPolynomialWithK4Refused) {
  const std::string text = replace(replace(replace(kRos, "plumb_bob", "rational_polynomial"), "cols: 5", "cols: 8"),
                                   "0.03125]", "0.03125, 0.5, 0, 0]");
  const std::string path = write("ros-rat.yaml", text);
  const std::string err = error_of(path);
  EXPECT_NE(err.find(path + ":10:3: 'distortion_coefficients' has non-zero rational_polynomial terms k4"),
            std::string::npos)
      << err;
}

TEST(IntrinsicsFile, RosDataOfWrongLengthRefused) {
  const std::string path = write("ros-len.yaml", replace(kRos, "0, 0, 1]", "0, 0]"));
  const std::string err = error_of(path);
  EXPECT_NE(err.find(path + ":7:9: 'camera_matrix.data' must have 9 numbers, has 8"), std::string::npos) << err;
}

TEST(IntrinsicsFile, RosUnknownKeyAndSkewRefused) {
  const std::string typo = write("ros-typo.yaml", std::string(kRos) + "binning_x: 0\n");
  EXPECT_NE(error_of(typo).find(typo + ":21:1: unknown key 'binning_x'"), std::string::npos) << error_of(typo);
  const std::string skew = write("ros-skew.yaml", replace(kRos, "[912.5, 0,", "[912.5, 0.5,"));
  EXPECT_NE(error_of(skew).find("'camera_matrix' has skew"), std::string::npos) << error_of(skew);
}

TEST(IntrinsicsFile, NeitherFormatRefused) {
  const std::string path = write("neither.yaml", "camera: {width: 640}\n");
  EXPECT_NE(error_of(path).find("neither a Kalibr camchain"), std::string::npos) << error_of(path);
  EXPECT_NE(error_of(testing::TempDir() + "/rsd-intr-none.yaml").find("cannot open"), std::string::npos);
}

// Issue 16, defect 6: sizes are checked against rsd's frame limit (4..8000, the rectifier's) before use; a width
// of -2^31 overflowed the default principal point.
TEST(IntrinsicsFile, SizesBeyondTheFrameLimitRefused) {
  const std::string kalibr = write("kalibr-huge.yaml", replace(kKalibr, "resolution: [752, 480]", "resolution: [100000, 480]"));
  EXPECT_NE(error_of(kalibr).find("'cam0.resolution' must be two whole numbers [width, height] of 4..8000 pixels"),
            std::string::npos)
      << error_of(kalibr);
  const std::string ros = write("ros-negative.yaml", replace(kRos, "image_width: 1280", "image_width: -2147483648"));
  EXPECT_NE(error_of(ros).find(ros + ":1:14: 'image_width' must be 4..8000 pixels"), std::string::npos) << error_of(ros);
  const std::string tall = write("ros-tall.yaml", replace(kRos, "image_height: 720", "image_height: 16385"));
  EXPECT_NE(error_of(tall).find("'image_height' must be 4..8000 pixels"), std::string::npos) << error_of(tall);
}

}  // namespace test_intrinsics_file
