// gyroflow lens profiles: a profile in gyroflow's layout (every key its calibrator writes, the
// numbers made up here) reads to the exact numbers written; scaled to another resolution the
// camera sees every direction where the calibrated one does, scaled; and what rsd cannot
// represent is refused naming the file, line and key.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "formats/gyroflow_profile.hpp"
#include "formats/yaml_map.hpp"
#include "tests/support/temp_dir.hpp"

using namespace rsd;

namespace test_gyroflow_profile {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

const test::TempDir& g_tmp = test::register_temp_dir("rsd_test_gyroflow_");

// gyroflow's layout (its calibrator's keys, in its order); a 2.7K action camera's wide mode.
const char* kProfile = R"({
  "name": "Example_Action Camera_Wide__2.7k_16by9_2704x1520-29.97fps",
  "note": "",
  "calibrated_by": "rsd tests",
  "camera_brand": "Example",
  "camera_model": "Action Camera",
  "lens_model": "Wide",
  "camera_setting": "",
  "calib_dimension": {
    "w": 2704,
    "h": 1520
  },
  "orig_dimension": {
    "w": 2704,
    "h": 1520
  },
  "output_dimension": {
    "w": 2704,
    "h": 1520
  },
  "frame_readout_time": 15.5,
  "gyro_lpf": null,
  "input_horizontal_stretch": 1.0,
  "num_images": 14,
  "fps": 29.97003,
  "official": false,
  "use_opencv_fisheye": true,
  "fisheye_params": {
    "RMS_error": 0.61,
    "camera_matrix": [
      [1187.25, 0.0, 1351.75],
      [0.0, 1186.5, 759.25],
      [0.0, 0.0, 1.0]
    ],
    "distortion_coeffs": [0.046875, 0.0234375, -0.01171875, 0.0029296875],
    "radial_distortion_limit": null
  },
  "use_opencv_standard": false,
  "calib_params": {
    "RMS_error": 0.0,
    "camera_matrix": [],
    "distortion_coeffs": [],
    "radial_distortion_limit": null
  },
  "identifier": "",
  "calibrator_version": "1.5.4",
  "date": "2024-01-01",
  "compatible_settings": []
}
)";

std::string write(const std::string& name, const std::string& text) {
  const std::string path = g_tmp.path(name);
  std::ofstream(path) << text;
  return path;
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto i = s.find(from);
  EXPECT_NE(i, std::string::npos) << from;
  return s.replace(i, from.size(), to);
}

std::string error_of(const std::string& path) {
  try {
    formats::read_gyroflow_profile(path);
  } catch (const formats::ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(GyroflowProfile, ReadsTheLensAndTheReadoutExactly) {
  const formats::GyroflowProfile p = formats::read_gyroflow_profile(write("p.json", kProfile));
  EXPECT_EQ(p.name, "Example_Action Camera_Wide__2.7k_16by9_2704x1520-29.97fps");
  EXPECT_EQ(p.cam.width, 2704);
  EXPECT_EQ(p.cam.height, 1520);
  EXPECT_EQ(p.cam.fx, 1187.25);
  EXPECT_EQ(p.cam.fy, 1186.5);
  EXPECT_EQ(p.cam.cx, 1351.75);
  EXPECT_EQ(p.cam.cy, 759.25);
  EXPECT_EQ(p.cam.dist, dsp::Distortion::equidistant(0.046875, 0.0234375, -0.01171875, 0.0029296875));
  ASSERT_TRUE(p.frame_readout_s);
  EXPECT_DOUBLE_EQ(*p.frame_readout_s, 0.0155);  // milliseconds in the profile
  EXPECT_EQ(p.readout, dsp::Readout::TopToBottom);
}

TEST(GyroflowProfile, NoReadoutWhenNullOrZeroAndTheDirectionRead) {
  const auto null_time = formats::read_gyroflow_profile(write("null.json", replace(kProfile, "\"frame_readout_time\": 15.5", "\"frame_readout_time\": null")));
  EXPECT_FALSE(null_time.frame_readout_s);
  const auto zero = formats::read_gyroflow_profile(write("zero.json", replace(kProfile, "\"frame_readout_time\": 15.5", "\"frame_readout_time\": 0")));
  EXPECT_FALSE(zero.frame_readout_s);
  const auto up = formats::read_gyroflow_profile(
      write("up.json", replace(kProfile, "\"gyro_lpf\": null", "\"frame_readout_direction\": \"BottomToTop\"")));
  EXPECT_EQ(up.readout, dsp::Readout::BottomToTop);
}

// At half the resolution the camera sees each direction at the same place of the frame: the
// pixel grids' edges coincide, so p' = (p + 1/2) / 2 - 1/2.
TEST(GyroflowProfile, AtAnotherResolutionEveryDirectionLandsWhereItDid) {
  const std::string path = write("s.json", kProfile);
  const formats::GyroflowProfile p = formats::read_gyroflow_profile(path);
  const dsp::CameraModel half = formats::profile_camera_at(p, path, 1352, 760);
  EXPECT_EQ(half.width, 1352);
  EXPECT_EQ(half.dist, p.cam.dist);
  for (const Eigen::Vector3d& X : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1.2, -0.4, 1), Eigen::Vector3d(-3, 1.5, 0.4)}) {
    const Eigen::Vector2d full = *p.cam.project(X), small = *half.project(X);
    EXPECT_NEAR(small.x(), (full.x() + 0.5) * 0.5 - 0.5, 1e-9);
    EXPECT_NEAR(small.y(), (full.y() + 0.5) * 0.5 - 0.5, 1e-9);
  }
  try {
    formats::profile_camera_at(p, path, 1920, 1440);  // 4:3 from a 16:9 calibration
    ADD_FAILURE() << "another aspect ratio must be refused";
  } catch (const formats::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("'calib_dimension' is 2704x1520, another aspect ratio than 1920x1440"), std::string::npos)
        << e.what();
  }
}

TEST(GyroflowProfile, WhatRsdCannotRepresentIsRefusedNamingTheKey) {
  const auto err = [](const std::string& name, const std::string& from, const std::string& to) {
    const std::string path = write(name, replace(kProfile, from, to));
    return std::pair{path, error_of(path)};
  };
  {
    const auto [path, e] = err("std.json", "\"use_opencv_standard\": false", "\"use_opencv_standard\": true");
    EXPECT_NE(e.find(path + ":"), std::string::npos) << e;
    EXPECT_NE(e.find("'use_opencv_standard' is true"), std::string::npos) << e;
  }
  {
    const auto [path, e] = err("five.json", "[0.046875, 0.0234375, -0.01171875, 0.0029296875]", "[0.1, 0.2, 0.3, 0.4, 0.5]");
    EXPECT_NE(e.find(path + ":35:"), std::string::npos) << e;
    EXPECT_NE(e.find("'fisheye_params.distortion_coeffs'"), std::string::npos) << e;
  }
  {
    const auto [path, e] = err("stretch.json", "\"input_horizontal_stretch\": 1.0", "\"input_horizontal_stretch\": 1.33");
    EXPECT_NE(e.find("'input_horizontal_stretch' is not 1"), std::string::npos) << e;
  }
  {
    const auto [path, e] = err("poly.json", "\"gyro_lpf\": null", "\"distortion_model\": \"poly5\"");
    EXPECT_NE(e.find("'distortion_model' is 'poly5'"), std::string::npos) << e;
  }
  {
    const auto [path, e] = err("sideways.json", "\"gyro_lpf\": null", "\"frame_readout_direction\": \"LeftToRight\"");
    EXPECT_NE(e.find("'frame_readout_direction' is 'LeftToRight'"), std::string::npos) << e;
  }
  {
    const auto [path, e] = err("skew.json", "[1187.25, 0.0, 1351.75]", "[1187.25, 0.5, 1351.75]");
    EXPECT_NE(e.find("'fisheye_params.camera_matrix' must have the form"), std::string::npos) << e;
  }
  {
    const auto [path, e] = err("neg.json", "\"frame_readout_time\": 15.5", "\"frame_readout_time\": -15.5");
    EXPECT_NE(e.find("'frame_readout_time' must be 0..1000 ms"), std::string::npos) << e;
  }
  {
    const auto [path, e] = err("huge.json", "\"w\": 2704,\n    \"h\": 1520\n  },\n  \"orig", "\"w\": 27040,\n    \"h\": 1520\n  },\n  \"orig");
    EXPECT_NE(e.find("'calib_dimension.w' must be a whole number of 4..8000 pixels"), std::string::npos) << e;
  }
  {
    const auto [path, e] = err("k.json", "[0.046875, 0.0234375, -0.01171875, 0.0029296875]", "[1e9, 0, 0, 0]");
    EXPECT_NE(e.find("'fisheye_params.distortion_coeffs' has k1"), std::string::npos) << e;
  }
  EXPECT_NE(error_of(write("empty.json", "")).find("'document' must be a mapping"), std::string::npos);
  EXPECT_NE(error_of(write("bare.json", "{}")).find("'calib_dimension' is missing"), std::string::npos) << error_of(write("bare.json", "{}"));
}

}  // namespace test_gyroflow_profile
