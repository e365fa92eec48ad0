// The analytic derivatives of a match's prediction (docs/formats/recording-v1.md, "Matches")
// with respect to every parameter a matches recording has but the lever arm (which it does not
// see): the clock (line delay, offset, drift), the intrinsics and lens, the mount, the gyro's
// bias and scale. The fits' Jacobian (fit.cpp) takes its columns from here: a column by
// differences costs the whole rotation model again (two projections per match, a ray per match
// when the intrinsics move, a track integrated anew when the gyro's values move), these all of
// them at once.
//
// The prediction of a match at its rolling-shutter fixed point v* (spec "Time model"): with u
// = M^T ray(px_a) (M = Exp(r), the mount), y = R_b^T R_a u, X = M y,
//   q(v) = pi(X),  R_a = R_c(t_a),  R_b = R_c(t_b(v)),  v* = q_y(v*),
// t_a = motion_time(T_a + row_time(y_a)), t_b(v) = motion_time(T_b + row_time(v)). The row's
// fixed point moves with a parameter as the implicit function theorem says:
//   dv*/dp = (dq_y/dp) / (1 - dq_y/dv),  the total dq/dp = dq/dp + dq/dv dv*/dp,
// and the residual's derivative is -dq/dp. The partial derivatives:
//   time      dX/dt_a = M R_b^T R_a [w_a]x u,  dX/dt_b = -M [w_b]x y  (dR_c/dt = R_c [w_c]x)
//   mount     dX/de = M (R_b^T R_a [u]x - [y]x) for M -> M Exp(e), e = J_r(r) dr
//   lens      pi's own (pi = K distort(X_xy / X_z)), and the ray's: pi(ray) = px_a holds, so
//             d ray_xy / d theta = -(K J_distort)^-1 d pi / d theta at the ray.
//   gyro      the track's IMU orientation turns as R_imu -> R_imu Exp(G dg) with the bias and
//             scale g (GyroTrack::camera_at's by_gyro), R_c = R_imu E^T (E = imu_to_camera):
//             dy = ((R_b^T R_a E G_a - E G_b) dg) x y.
// Pure functions of their arguments: any thread.
#pragma once

#include <Eigen/Core>
#include <array>
#include <type_traits>

#include "dsp/diagnosis/model.hpp"
#include "dsp/geometry/camera_model.hpp"

namespace rsd::dsp {

// The parameters with an analytic derivative, in the order of a MatchJacobian's columns. K1..K4
// are the lens terms as lens_of reads them: pinhole-equi k1..k4, pinhole-radtan k1 and k2 (its
// K3 and K4 columns are zero: lens_of does not read them). The gyro's bias and scale come last.
inline constexpr std::array<Param, 20> kAnalyticParams = {
    Param::LineDelay, Param::TimeOffset, Param::Drift,  Param::Fx,     Param::Fy,     Param::Cx,     Param::Cy,
    Param::K1,        Param::K2,         Param::K3,     Param::K4,     Param::MountX, Param::MountY, Param::MountZ,
    Param::BiasX,     Param::BiasY,      Param::BiasZ,  Param::ScaleX, Param::ScaleY, Param::ScaleZ};
using MatchJacobian = Eigen::Matrix<double, 2, static_cast<int>(kAnalyticParams.size())>;
static_assert(std::is_same_v<MatchJacobian, Eigen::Matrix<double, 2, 20>>, "DiagnosisModel::rotation_jacobian's type");
// Column of q in a MatchJacobian, -1 when q has no analytic derivative.
int analytic_column(Param q);

// One match at its solution, as the model has it.
struct MatchAtSolution {
  Eigen::Vector3d ray;            // frame_a's ray (x_n, y_n, 1), camera axes before the mount
  Eigen::Matrix3d R_a, R_b;       // world-from-camera (the gyro track's) at t_a and t_b(v*)
  Eigen::Vector3d w_a, w_b;       // the track's rate there, camera axes (GyroTrack::rate)
  Eigen::Matrix3d mount;          // the mount M = Exp(r)
  Eigen::Matrix3d mount_jr;       // and J_r(r) (so3_right_jacobian)
  GyroTrack::ByGyro gyro_a, gyro_b;  // how the track turns there with the bias and scale
  Eigen::Matrix3d imu_to_camera;      // E, the nominal's
  Eigen::Vector3d dta, dtb;       // d t_a, d t_b (at fixed rows) / d (line delay, offset, drift)
  double dtb_dv = 0;              // d t_b / d v
};

// d q(v*) / d p for the parameters kAnalyticParams, q the predicted pixel in frame_b, through
// `cam` (its lens the family lens_of gives). Zero where the prediction is not in front of the
// camera.
MatchJacobian match_prediction_jacobian(const CameraModel& cam, const MatchAtSolution& m);

}  // namespace rsd::dsp
