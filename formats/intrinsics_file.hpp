// Camera intrinsics from a calibration tool's output: a Kalibr camchain YAML
// (kalibr_calibrate_cameras / kalibr_calibrate_rs_cameras / kalibr_calibrate_imu_camera) or a
// ROS camera_info YAML (camera_calibration, camera_info_manager).
//
// Pixel convention: Kalibr's pinhole model and ROS/OpenCV put pixel (0, 0) at the centre of
// the top-left pixel, as rsd does (dsp/geometry/camera_model.hpp), so the principal point is taken
// as written; no half-pixel shift.
//
// Errors are ConfigError (formats/yaml_map.hpp) naming file:line:column and the key.
#pragma once

#include <optional>
#include <string>

#include "dsp/geometry/camera_model.hpp"
#include "formats/yaml_map.hpp"

namespace rsd::formats {

struct Intrinsics {
  dsp::CameraModel cam;
  std::optional<double> line_delay_s;         // Kalibr rolling-shutter calibration's line_delay
  std::optional<double> timeshift_cam_imu_s;  // Kalibr camera-IMU calibration's time shift
  std::string source;                         // e.g. "Kalibr camchain calib.yaml cam1"
};

// Detects the format from the top-level keys (image_width / camera_matrix: ROS camera_info;
// cam0, cam1, ...: Kalibr camchain). `camera` selects a Kalibr camera ("cam1"); empty means
// cam0, or the only camera. For a ROS file a non-empty `camera` must equal its camera_name.
//
// Kalibr: camera_model pinhole, distortion_model radtan ([k1, k2, p1, p2]), equidistant
// (pinhole-equi, [k1, k2, k3, k4]) or none; others are refused. Extra keys are allowed (Kalibr
// writes several); T_cam_imu is not read here (rsd-extract takes --imu-to-camera).
// ROS: distortion_model plumb_bob ([k1, k2, p1, p2, k3]), or rational_polynomial when k4..k6
// are all zero; camera_matrix without skew. Unknown top-level keys are refused.
Intrinsics load_intrinsics(const std::string& file, const std::string& camera = "");

// One camera of a Kalibr camchain (camera_model pinhole; intrinsics; distortion_model radtan or
// none, distortion_coeffs; resolution): the intrinsics load_intrinsics and the calibration
// reader (formats/calibration_v1.hpp) both take from a Kalibr file.
dsp::CameraModel read_kalibr_camera(YamlMap& cam);

// A `camera:` mapping {width, height, fx, fy, cx, cy, distortion: [k1, k2, p1, p2]} read
// strictly over `defaults` (fy defaults to fx, cx and cy to the image centre).
dsp::CameraModel read_camera_section(YamlMap m, const dsp::CameraModel& defaults);

}  // namespace rsd::formats
