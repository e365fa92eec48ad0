// Whether a matrix read from a file or a command line is a rotation: the one check behind every
// imu_to_camera, body_to_camera and T_cam_imu rsd accepts (the daemon's config, recording.yaml's
// motion keys, the calibration file, rsd-extract's --imu-to-camera). A reflection (determinant
// -1) would mirror the gyro's axes, a scaled matrix would scale its rates; both are set-up
// mistakes no fitted effect should be left to absorb.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>

namespace rsd::dsp {

// Orthonormal and of determinant +1, each within `tol`; false for any non-finite entry.
inline bool is_rotation(const Eigen::Matrix3d& m, double tol = 1e-6) {
  return m.allFinite() && (m.transpose() * m - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= tol &&
         std::abs(m.determinant() - 1.0) <= tol;
}

}  // namespace rsd::dsp
