// Which way the gyro's axes point in the camera (docs/diagnosis.md, "The gyro's axes"): a real
// rig's IMU is mounted in whatever orientation its board has (a phone's sensor frame, a GoPro's
// ORIN, a drone's flight controller), and motion.imu_to_camera must say so before any effect can
// be measured; mount_rotation fits what remains, a degree or two. Of the 24 rotations that take
// axes onto axes (signed permutations of determinant +1), the search ranks each by how well the
// nominal model with it predicts a matches recording, at its best clock offset within +-1 s of the
// nominal one (a wrong axis order predicts turns about the wrong axis: tens of pixels; the right
// one leaves what the other effects do, the readout's and the bias's, a few).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "dsp/observation/recording.hpp"

namespace rsd::dsp {

struct AxesCandidate {
  Eigen::Matrix3d imu_to_camera;  // w_camera = R w_imu
  double scale_px = 0;            // robust residual sigma per coordinate, at its best offset
  double time_offset_s = 0;       // that offset
};

struct AxesSearch {
  std::vector<AxesCandidate> ranked;  // all 24, best first
  // The best explains the pictures clearly better than any other: its residual at most half the
  // runner-up's.
  bool decisive() const { return ranked.size() > 1 && ranked[0].scale_px <= 0.5 * ranked[1].scale_px; }
};

// The 24 rotations that take the coordinate axes onto coordinate axes.
std::vector<Eigen::Matrix3d> axis_rotations();

// The axis rotation nearest R (the smallest angle between them).
Eigen::Matrix3d nearest_axis_rotation(const Eigen::Matrix3d& R);

// Ranks the 24 axis orders for a matches recording (gyro motion), on at most `max_observations`
// matches spread over the recording: each is motion.imu_to_camera's tilt off its nearest axis
// order (the camera's on its board, a degree or two on a calibrated rig) times the order, so the
// given matrix is one of the candidates. Throws std::invalid_argument for a recording of another
// kind.
AxesSearch search_imu_axes(const Recording& rec, int max_observations = 1000);

}  // namespace rsd::dsp
