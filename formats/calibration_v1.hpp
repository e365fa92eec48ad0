// Camera calibration files, rsd-calibration/1 (docs/formats/calibration-v1.md): a Kalibr
// camchain-imucam YAML file whose cam0 holds the camera, T_cam_imu and timeshift_cam_imu, with
// rsd's additions under cam0.rsd. A file Kalibr wrote (no rsd block) is a calibration with the
// additions at their defaults. The one reader and the one writer of the format.
//
// Errors are ConfigError (formats/yaml_map.hpp) naming the file, line, column, key and reason:
// R of T_cam_imu not a rotation (within 1e-6), a number not finite, an unknown key inside
// cam0.rsd. Unknown keys elsewhere are ignored (Kalibr writes several).
#pragma once

#include <Eigen/Core>

#include <map>
#include <string>
#include <vector>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/row_timing.hpp"
#include "dsp/observation/recording.hpp"

namespace rsd::formats {

struct Calibration {
  dsp::CameraModel cam;  // intrinsics, lens (radtan k1, k2, p1, p2 or equidistant k1..k4), resolution
  // T_cam_imu: X_cam = R X_imu + t; R is the recording's imu_to_camera (w_cam = R w_imu).
  Eigen::Matrix3d imu_to_camera = Eigen::Matrix3d::Identity();
  Eigen::Vector3d imu_to_camera_t = Eigen::Vector3d::Zero();
  double timeshift_cam_imu_s = 0;  // t_imu = t_cam + timeshift (the recording's time_offset_s)
  // cam0.rsd
  double line_delay_s = 0;  // between consecutive rows; 0: global shutter
  dsp::Readout readout = dsp::Readout::TopToBottom;
  double drift_ppm = 0;  // camera clock rate error, as in the recording's time model
  // w_true = diag(gyro_scale) (w_measured - gyro_bias), IMU axes.
  Eigen::Vector3d gyro_bias_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_scale = Eigen::Vector3d::Ones();
  Eigen::Vector3d lever_arm_m = Eigen::Vector3d::Zero();  // camera origin in the tracked body's frame
  std::string source;                                     // where the values came from (free text)
  // 1-sigma uncertainties by key (line_delay_s, timeshift_cam_imu, intrinsics, ...): one number
  // for a scalar key, one per element for a list.
  std::map<std::string, std::vector<double>> sigma;
  bool has_rsd_block = false;  // false: a file Kalibr wrote
  std::string file;            // the file read, for messages
};

// A nominal model (an observation recording's header) as a calibration: its camera, row timing,
// imu_to_camera, time offset, drift and lever arm; no gyro bias, unit scale.
Calibration calibration_of(const dsp::NominalModel& nominal, const std::string& source);

// Reads and checks a calibration file.
Calibration read_calibration(const std::string& file);

// Refuses (ConfigError naming the file and cam0.resolution) a calibration whose resolution is
// not the camera's.
void require_resolution(const Calibration& c, int width, int height);

// Writes the file (Kalibr's keys, then cam0.rsd with format rsd-calibration/1; every number
// shortest-exact, so it reads back to the same doubles), atomically (a temporary file renamed
// over it). Throws std::runtime_error naming the file if it cannot be written.
void write_calibration(const std::string& file, const Calibration& c);

}  // namespace rsd::formats
