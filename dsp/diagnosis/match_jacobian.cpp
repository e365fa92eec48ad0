#include "dsp/diagnosis/match_jacobian.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "dsp/geometry/camera_motion.hpp"

namespace rsd::dsp {

namespace {

constexpr int kLineDelay = 0, kDrift = 2, kFx = 3, kMount = 11, kBias = 14;  // columns of kAnalyticParams
constexpr int kLens = 8;  // fx, fy, cx, cy, k1..k4: columns kFx.. kFx + 7
using LensJacobian = Eigen::Matrix<double, 2, kLens>;

// d pixel / d (fx, fy, cx, cy, k1..k4) of the pixel K distort(xn) at a fixed normalised point,
// with the distortion's own Jacobian J (d distort / d xn) alongside.
LensJacobian pixel_by_lens(const CameraModel& cam, const Eigen::Vector2d& xn, Eigen::Matrix2d& J) {
  const Eigen::Vector2d xd = distort(cam.dist, xn, J);
  LensJacobian L = LensJacobian::Zero();
  L(0, 0) = xd.x(), L(1, 1) = xd.y(), L(0, 2) = 1, L(1, 3) = 1;
  Eigen::Matrix<double, 2, 4> K = distort_radial_jacobian(cam.dist, xn);
  if (cam.dist.model == LensModel::PinholeRadtan) K.col(2).setZero();  // lens_of reads k1, k2 only
  K.row(0) *= cam.fx, K.row(1) *= cam.fy;
  L.rightCols<4>() = K;
  return L;
}

}  // namespace

int analytic_column(Param q) {
  for (size_t j = 0; j < kAnalyticParams.size(); ++j)
    if (kAnalyticParams[j] == q) return static_cast<int>(j);
  return -1;
}

MatchJacobian match_prediction_jacobian(const CameraModel& cam, const MatchAtSolution& m) {
  MatchJacobian D = MatchJacobian::Zero();
  const Eigen::Matrix3d& M = m.mount;
  const Eigen::Matrix3d Rba = m.R_b.transpose() * m.R_a;
  const Eigen::Vector3d u = M.transpose() * m.ray, y = Rba * u, X = M * y;
  if (!(X.z() > 0)) return D;
  // pi at X: d pi / d X = K J_distort d(xn)/dX.
  const Eigen::Vector2d xn_b = X.head<2>() / X.z();
  Eigen::Matrix2d Jb, Ja;
  const LensJacobian lens_b = pixel_by_lens(cam, xn_b, Jb);
  Eigen::Matrix<double, 2, 3> dxn_dX;
  dxn_dX << 1 / X.z(), 0, -xn_b.x() / X.z(), 0, 1 / X.z(), -xn_b.y() / X.z();
  const Eigen::Matrix<double, 2, 3> dpi_dX = Eigen::Vector2d(cam.fx, cam.fy).asDiagonal() * Jb * dxn_dX;
  // The clock: through t_a and t_b.
  const Eigen::Vector2d dq_dta = dpi_dX * (M * (Rba * m.w_a.cross(u)));
  const Eigen::Vector2d dq_dtb = dpi_dX * (-(M * m.w_b.cross(y)));
  for (int j = kLineDelay; j <= kDrift; ++j) D.col(j) = dq_dta * m.dta[j] + dq_dtb * m.dtb[j];
  // The lens: pi's own, and the ray's through pi(ray) = px_a.
  const LensJacobian lens_a = pixel_by_lens(cam, m.ray.head<2>(), Ja);
  const Eigen::Matrix2d K_Ja = Eigen::Vector2d(cam.fx, cam.fy).asDiagonal() * Ja;
  const LensJacobian dray = -K_Ja.partialPivLu().solve(lens_a);
  const Eigen::Matrix<double, 3, 2> A = (M * Rba * M.transpose()).leftCols<2>();
  D.middleCols<kLens>(kFx) = lens_b + dpi_dX * A * dray;
  // The mount.
  const Eigen::Matrix3d dX_de = M * (Rba * hat(u) - hat(y));
  D.middleCols<3>(kMount) = dpi_dX * dX_de * m.mount_jr;
  // The gyro: dX = M dy = -M [y]x (R_b^T R_a E G_a - E G_b) dg.
  const Eigen::Matrix3d& E = m.imu_to_camera;
  D.middleCols<6>(kBias) = -dpi_dX * M * hat(y) * (Rba * E * m.gyro_a - E * m.gyro_b);
  // The fixed point: v* moves with each parameter as dv*/dp = (dq_y/dp) / (1 - dq_y/dv).
  const Eigen::Vector2d dq_dv = dq_dtb * m.dtb_dv;
  const double settle = 1.0 - dq_dv.y();
  if (std::abs(settle) < 1e-9) return MatchJacobian::Zero();
  for (int j = 0; j < D.cols(); ++j) D.col(j) += dq_dv * (D(1, j) / settle);
  return D;
}

}  // namespace rsd::dsp
