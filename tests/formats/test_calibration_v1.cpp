// rsd-calibration/1: the format's own example reads as written; a file Kalibr wrote reads with
// rsd's additions at their defaults; what the writer writes reads back to the same doubles; bad
// files are refused naming file, key and reason.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>

#include "formats/calibration_v1.hpp"
#include "formats/yaml_map.hpp"
#include "tests/support/temp_dir.hpp"

namespace rsd::test_calibration_v1 {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

const test::TempDir& g_tmp = test::register_temp_dir("rsd_test_calibration_");

std::string write(const std::string& name, const std::string& text) {
  const std::string path = g_tmp.path(name);
  std::ofstream(path) << text;
  return path;
}

std::string error_of(const std::string& text) {
  try {
    formats::read_calibration(write("bad.yaml", text));
  } catch (const formats::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

// The example of docs/formats/calibration-v1.md.
const char* kExample = R"(cam0:
  camera_model: pinhole
  intrinsics: [1510.4, 1510.4, 959.5, 539.5]
  distortion_model: radtan
  distortion_coeffs: [0.221, -0.351, 0.0, 0.0]
  resolution: [1920, 1080]
  T_cam_imu:
  - [0.0, 1.0, 0.0, 0.0]
  - [-1.0, 0.0, 0.0, 0.0]
  - [0.0, 0.0, 1.0, 0.0]
  - [0.0, 0.0, 0.0, 1.0]
  timeshift_cam_imu: 0.550
  rsd:
    format: rsd-calibration/1
    line_delay_s: 2.8e-05
    readout: top_to_bottom
    drift_ppm: 0.0
    gyro_bias_rad_s: [0, 0, 0]
    gyro_scale: [1, 1, 1]
    lever_arm_m: [0, 0, 0]
    source: "rsd-diagnose: phone/recording.yaml"
    sigma:
      line_delay_s: 4.0e-07
      timeshift_cam_imu: 0.0003
)";

TEST(CalibrationV1, TheFormatsExampleReadsAsWritten) {
  const formats::Calibration c = formats::read_calibration(write("example.yaml", kExample));
  EXPECT_EQ(c.cam.width, 1920);
  EXPECT_EQ(c.cam.height, 1080);
  EXPECT_DOUBLE_EQ(c.cam.fx, 1510.4);
  EXPECT_DOUBLE_EQ(c.cam.cy, 539.5);
  EXPECT_DOUBLE_EQ(c.cam.dist.k2, -0.351);
  // w_cam = R w_imu: the IMU's x axis is the camera's -y.
  EXPECT_EQ(c.imu_to_camera * Eigen::Vector3d::UnitX(), Eigen::Vector3d(0, -1, 0));
  EXPECT_DOUBLE_EQ(c.timeshift_cam_imu_s, 0.55);
  EXPECT_DOUBLE_EQ(c.line_delay_s, 2.8e-5);
  EXPECT_EQ(c.readout, dsp::Readout::TopToBottom);
  EXPECT_EQ(c.source, "rsd-diagnose: phone/recording.yaml");
  ASSERT_EQ(c.sigma.count("line_delay_s"), 1u);
  EXPECT_DOUBLE_EQ(c.sigma.at("line_delay_s")[0], 4e-7);
  EXPECT_TRUE(c.has_rsd_block);
  EXPECT_NO_THROW(formats::require_resolution(c, 1920, 1080));
  try {
    formats::require_resolution(c, 640, 480);
    FAIL() << "a resolution that is not the camera's must be refused";
  } catch (const formats::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("example.yaml: 'cam0.resolution' is [1920, 1080], but the camera delivers 640x480"),
              std::string::npos)
        << e.what();
  }
}

TEST(CalibrationV1, AKalibrFileIsACalibrationWithDefaultsForTheAdditions) {
  const formats::Calibration c = formats::read_calibration(write("kalibr.yaml", R"(cam0:
  cam_overlaps: [1]
  camera_model: pinhole
  distortion_coeffs: [-0.28, 0.07, 0.0002, 1.7e-05]
  distortion_model: radtan
  intrinsics: [458.654, 457.296, 367.215, 248.375]
  resolution: [752, 480]
  rostopic: /cam0/image_raw
  T_cam_imu:
  - [1, 0, 0, 0.05]
  - [0, 1, 0, -0.01]
  - [0, 0, 1, 0.002]
  - [0, 0, 0, 1]
  timeshift_cam_imu: -0.0123
cam1:
  camera_model: pinhole
)"));
  EXPECT_FALSE(c.has_rsd_block);
  EXPECT_EQ(c.cam.width, 752);
  EXPECT_DOUBLE_EQ(c.timeshift_cam_imu_s, -0.0123);
  EXPECT_EQ(c.imu_to_camera_t, Eigen::Vector3d(0.05, -0.01, 0.002));
  EXPECT_EQ(c.line_delay_s, 0.0);
  EXPECT_EQ(c.gyro_scale, Eigen::Vector3d::Ones());
  EXPECT_EQ(c.gyro_bias_rad_s, Eigen::Vector3d::Zero());
}

TEST(CalibrationV1, WrittenFilesReadBackToTheSameDoubles) {
  formats::Calibration c;
  c.cam = dsp::CameraModel::from_hfov(1280, 720, 1.1);
  c.cam.dist = {0.1 / 3, -0.02, 1e-4, -2e-5, 0};
  c.imu_to_camera = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  c.imu_to_camera_t = {0.01, -0.02, 0.3};
  c.timeshift_cam_imu_s = 0.0123456789;
  c.line_delay_s = 1.0 / 36000;
  c.readout = dsp::Readout::BottomToTop;
  c.drift_ppm = -12.5;
  c.gyro_bias_rad_s = {0.01, -0.002, 1e-3 / 7};
  c.gyro_scale = {1.01, 0.99, 1.0 + 1e-9};
  c.lever_arm_m = {0.1, 0.2, -0.3};
  c.source = "rsd-diagnose: a: b # c";
  c.sigma["line_delay_s"] = {3e-8};
  c.sigma["gyro_bias_rad_s"] = {1e-4, 2e-4, 3e-4};
  const std::string path = g_tmp.path("written.yaml");
  formats::write_calibration(path, c);
  const formats::Calibration r = formats::read_calibration(path);
  EXPECT_EQ(r.cam.fx, c.cam.fx);
  EXPECT_EQ(r.cam.cx, c.cam.cx);
  EXPECT_EQ(r.cam.dist.k1, c.cam.dist.k1);
  EXPECT_EQ(r.cam.dist.p2, c.cam.dist.p2);
  EXPECT_EQ(r.cam.width, 1280);
  EXPECT_EQ(r.imu_to_camera, c.imu_to_camera);
  EXPECT_EQ(r.imu_to_camera_t, c.imu_to_camera_t);
  EXPECT_EQ(r.timeshift_cam_imu_s, c.timeshift_cam_imu_s);
  EXPECT_EQ(r.line_delay_s, c.line_delay_s);
  EXPECT_EQ(r.readout, dsp::Readout::BottomToTop);
  EXPECT_EQ(r.drift_ppm, c.drift_ppm);
  EXPECT_EQ(r.gyro_bias_rad_s, c.gyro_bias_rad_s);
  EXPECT_EQ(r.gyro_scale, c.gyro_scale);
  EXPECT_EQ(r.lever_arm_m, c.lever_arm_m);
  EXPECT_EQ(r.source, c.source);
  EXPECT_EQ(r.sigma, c.sigma);
  EXPECT_TRUE(r.has_rsd_block);
}

// An equidistant (pinhole-equi) camera: Kalibr's distortion_model equidistant with k1..k4.
TEST(CalibrationV1, AnEquidistantCameraIsWrittenAndReadBack) {
  formats::Calibration c;
  c.cam = dsp::CameraModel::from_hfov(1280, 960, 2.2);
  c.cam.dist = dsp::Distortion::equidistant(0.0469, -0.0135, 0.0021, -1.0 / 3000);
  const std::string path = g_tmp.path("equidistant.yaml");
  formats::write_calibration(path, c);
  EXPECT_EQ(formats::read_calibration(path).cam.dist, c.cam.dist);
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("distortion_model: equidistant"), std::string::npos) << text;
}

TEST(CalibrationV1, BadFilesAreRefusedNamingKeyAndReason) {
  const std::string cam = "cam0:\n  camera_model: pinhole\n  intrinsics: [500, 500, 319.5, 239.5]\n"
                          "  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n  resolution: [640, 480]\n";
  EXPECT_NE(error_of(cam + "  T_cam_imu:\n  - [1, 0, 0, 0]\n  - [0, 1, 0, 0]\n  - [0, 0, 1.01, 0]\n  - [0, 0, 0, 1]\n")
                .find("bad.yaml:8:3: 'cam0.T_cam_imu' has a rotation part that is not a rotation"),
            std::string::npos)
      << error_of(cam + "  T_cam_imu:\n  - [1, 0, 0, 0]\n  - [0, 1, 0, 0]\n  - [0, 0, 1.01, 0]\n  - [0, 0, 0, 1]\n");
  EXPECT_NE(error_of(cam + "  T_cam_imu:\n  - [0, 1, 0, 0]\n  - [1, 0, 0, 0]\n  - [0, 0, 1, 0]\n  - [0, 0, 0, 1]\n")
                .find("'cam0.T_cam_imu' has a rotation part that is not a rotation"),
            std::string::npos);  // a reflection: orthonormal, determinant -1
  std::string nan = cam;
  nan.replace(nan.find("[500, 500"), 9, "[.nan, 500");
  EXPECT_NE(error_of(nan).find("'cam0.intrinsics' must hold finite numbers"), std::string::npos) << error_of(nan);
  EXPECT_NE(error_of(cam + "  timeshift_cam_imu: .inf\n").find("'cam0.timeshift_cam_imu' must be a finite number"),
            std::string::npos);
  EXPECT_NE(error_of(cam + "  rsd:\n    format: rsd-calibration/1\n    gyro_bais_rad_s: [0, 0, 0]\n")
                .find("unknown key 'cam0.rsd.gyro_bais_rad_s'"),
            std::string::npos);
  EXPECT_NE(error_of(cam + "  rsd:\n    format: rsd-calibration/2\n").find("'cam0.rsd.format' is 'rsd-calibration/2'"),
            std::string::npos);
  EXPECT_NE(error_of(cam + "  rsd:\n    format: rsd-calibration/1\n    sigma: {k9: 1}\n")
                .find("'cam0.rsd.sigma.k9' is not a key a sigma can be given for"),
            std::string::npos);
  EXPECT_NE(error_of("cam1:\n  camera_model: pinhole\n").find("'cam0' is missing"), std::string::npos);
  // Unknown keys outside cam0.rsd are Kalibr's business: ignored.
  EXPECT_EQ(error_of(cam + "  rostopic: /cam0/image_raw\n  cam_overlaps: []\n"), "no error");
}

// Issue 38: values that passed as finite numbers and then overflowed the velocity input's
// microsecond arithmetic (a time shift of 1e13 s) or blackened every frame (fx 1e300, k1 1e6)
// are refused by rsd's input limits (dsp/core/input_limits.hpp), naming the key.
TEST(CalibrationV1, ValuesBeyondRsdsInputLimitsAreRefusedNamingTheKey) {
  const std::string head = "cam0:\n  camera_model: pinhole\n  distortion_model: radtan\n  resolution: [640, 480]\n";
  const std::string cam = head + "  intrinsics: [500, 500, 319.5, 239.5]\n  distortion_coeffs: [0, 0, 0, 0]\n";
  const std::string rsd = "  rsd:\n    format: rsd-calibration/1\n";
  const std::pair<std::string, std::string> cases[] = {
      {cam + "  timeshift_cam_imu: 1e13\n", "'cam0.timeshift_cam_imu' is 1e+13, outside -86400..86400 s"},
      {head + "  intrinsics: [1e300, 500, 319.5, 239.5]\n  distortion_coeffs: [0, 0, 0, 0]\n", "'cam0.intrinsics' has fx 1e+300 is outside 1..1e7 pixels"},
      {head + "  intrinsics: [500, 500, 1e300, 239.5]\n  distortion_coeffs: [0, 0, 0, 0]\n", "'cam0.intrinsics' has cx / width"},
      {head + "  intrinsics: [500, 500, 319.5, 239.5]\n  distortion_coeffs: [1e6, 0, 0, 0]\n", "'cam0.distortion_coeffs' has k1 1000000 is outside -1000..1000"},
      {cam + rsd + "    line_delay_s: 5\n", "'cam0.rsd.line_delay_s' must be 0..1 s"},
      {cam + rsd + "    drift_ppm: 1e9\n", "'cam0.rsd.drift_ppm' is 1e+09, outside -10000..10000 ppm"},
      {cam + rsd + "    gyro_scale: [1, 1e-300, 1]\n", "'cam0.rsd.gyro_scale' is 1e-300, outside 0.1..10"},
  };
  for (const auto& [text, want] : cases) EXPECT_NE(error_of(text).find(want), std::string::npos) << error_of(text);
  EXPECT_EQ(error_of(cam + "  timeshift_cam_imu: -86400\n" + rsd + "    line_delay_s: 1\n    drift_ppm: 10000\n"), "no error");
}

}  // namespace
}  // namespace rsd::test_calibration_v1
