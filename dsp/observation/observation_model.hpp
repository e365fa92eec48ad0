// The observation model of docs/formats/recording-v1.md, shared by the simulator
// (which evaluates it with the true parameters) and the diagnosis tool (which fits them).
//
// Time model: a feature at row v of frame k (timestamp T_k, camera clock) is captured at
//   t = T_k + line_delay * v            (top_to_bottom)
//   t = T_k + line_delay * (H - 1 - v)  (bottom_to_top)
// on the camera clock, i.e. at t_m = t + time_offset + drift_ppm 1e-6 (t - T_0) on the
// motion clock. Because v itself depends on when the row was read, an observation is the
// fixed point of the time model and the projection: the rolling-shutter constraint,
// eq. (3), solved by project_trajectory.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::dsp {

struct TimeModel {
  double line_delay_s = 0.0;
  Readout readout = Readout::TopToBottom;
  double time_offset_s = 0.0;  // t_motion = t_camera + offset (+ drift)
  double drift_ppm = 0.0;
  double t0 = 0.0;             // T_0, the first frame's timestamp
  double motion_time(double t_camera) const {
    return t_camera + time_offset_s + drift_ppm * 1e-6 * (t_camera - t0);
  }
};

// Orientation over time (world-from-frame rotation), sampled and slerped; held at the ends.
class OrientationTrack {
 public:
  struct Sample {
    double t;
    Eigen::Quaterniond q;
  };
  OrientationTrack() = default;
  explicit OrientationTrack(std::vector<Sample> samples);
  Eigen::Quaterniond at(double t) const;
  bool empty() const { return samples_.empty(); }
  double t_begin() const { return samples_.front().t; }
  double t_end() const { return samples_.back().t; }

 private:
  std::vector<Sample> samples_;
};

struct GyroSample {
  double t;
  Eigen::Vector3d w;  // rad/s, IMU axes
};

// Integrates dR/dt = R [w - bias]x over gyro samples (a Magnus step per
// interval through the exponential map). Repeated timestamps contribute nothing; a gap is
// bridged with the rates at its ends. Returns the IMU orientation track, starting at identity.
OrientationTrack integrate_gyro(const std::vector<GyroSample>& gyro, const Eigen::Vector3d& bias);

// Camera orientation from IMU orientation: w_camera = R_ic w_imu, so R_c = R_imu R_ic^T.
Eigen::Quaterniond camera_orientation(const Eigen::Quaterniond& q_imu, const Eigen::Matrix3d& imu_to_camera);

// Row timing of a frame in the paper's terms for this time model.
RowTiming row_timing(const TimeModel& tm, int height);

// Landmarks: body pose over time (world-from-body, motion clock) with the camera at lever
// arm l in body axes. Predicts the pixel of world point X in the frame stamped T_k.
struct LandmarkSetup {
  CameraModel cam;
  TimeModel time;
  Eigen::Vector3d lever_arm = Eigen::Vector3d::Zero();
  // The camera's axes in the body's (spec mount_rotation: R_c = R Exp(r), so mount = Exp(r)).
  Eigen::Matrix3d mount = Eigen::Matrix3d::Identity();
};
struct Prediction {
  Eigen::Vector2d pixel;
  double t_camera;  // capture time on the camera clock
};
std::optional<Prediction> predict_landmark(const LandmarkSetup& s, const CameraMotion& world_to_body,
                                           double T_k, const Eigen::Vector3d& X);

// Matches: a rotation-only camera whose world-from-camera orientation is `track` (motion
// clock). Predicts where the feature seen at pixel_a in frame T_a appears in frame T_b.
struct MatchSetup {
  CameraModel cam;
  TimeModel time;
};
std::optional<Prediction> predict_match(const MatchSetup& s, const OrientationTrack& camera_track, double T_a,
                                        const Eigen::Vector2d& pixel_a, double T_b);
// The direction (world axes) seen at `pixel` of the frame stamped T.
std::optional<Eigen::Vector3d> world_direction(const MatchSetup& s, const OrientationTrack& camera_track,
                                               double T, const Eigen::Vector2d& pixel);
// Where a world direction appears in the frame stamped T.
std::optional<Prediction> predict_direction(const MatchSetup& s, const OrientationTrack& camera_track, double T,
                                            const Eigen::Vector3d& d_world);

}  // namespace rsd::dsp
