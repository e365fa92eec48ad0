#include "dsp/diagnosis/parallax.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>

#include "dsp/core/statistics.hpp"
#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/model.hpp"
#include "dsp/diagnosis/robust_stats.hpp"

namespace rsd::dsp {

Eigen::Matrix<double, 2, 3> rotation_flow(const CameraModel& cam, const Eigen::Vector2d& px) {
  return rotation_flow_at(cam, {(px.x() - cam.cx) / cam.fx, (px.y() - cam.cy) / cam.fy});
}

Eigen::Matrix<double, 2, 3> rotation_flow_at(const CameraModel& cam, const Eigen::Vector2d& xn) {
  const double x = xn.x(), y = xn.y();
  Eigen::Matrix<double, 2, 3> J;
  J << cam.fx * x * y, -cam.fx * (1 + x * x), cam.fx * y,  //
      cam.fy * (1 + y * y), -cam.fy * x * y, -cam.fy * x;
  return J;
}

Eigen::Matrix<double, 2, 3> translation_flow(const CameraModel& cam, const Eigen::Vector2d& px) {
  const double x = (px.x() - cam.cx) / cam.fx, y = (px.y() - cam.cy) / cam.fy;
  Eigen::Matrix<double, 2, 3> J;
  J << cam.fx, 0, -cam.fx * x,  //
      0, cam.fy, -cam.fy * y;
  return J;
}

Parallax parallax_signal(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx_all) {
  Parallax out;
  if (m.kind() != ObservationKind::Matches) return out;
  const std::vector<int> idx = subsample(idx_all, 20000);
  ModelParams plain = p;
  plain.translation_nuisance = false;  // the residuals as the rotation-only model leaves them
  const auto res = m.residuals(plain, idx);
  const std::vector<bool> in = inliers(res);
  const CameraModel& cam = m.recording().nominal.cam;
  std::map<int, std::vector<size_t>> pairs;
  for (size_t k = 0; k < idx.size(); ++k)
    if (in[k]) pairs[m.frame_rank(idx[k])].push_back(k);
  double extra = 0, left = 0, total = 0, by_translation = 0;
  int dof_left = 0, coordinates = 0;
  for (const auto& [rank, pos] : pairs) {
    const int n = static_cast<int>(pos.size());
    if (n < 8) continue;
    Eigen::MatrixXd A(2 * n, 6);
    Eigen::VectorXd b(2 * n);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d px = m.observed(idx[pos[i]]);
      A.block<2, 3>(2 * i, 0) = rotation_flow(cam, px);
      A.block<2, 3>(2 * i, 3) = translation_flow(cam, px);
      b.segment<2>(2 * i) = res[pos[i]];
    }
    const Eigen::MatrixXd R = A.leftCols(3), T = A.rightCols(3);
    const Eigen::VectorXd rot = R * R.colPivHouseholderQr().solve(b), all = A * A.colPivHouseholderQr().solve(b),
                          trans = T * T.colPivHouseholderQr().solve(b);
    extra += (b - rot).squaredNorm() - (b - all).squaredNorm();
    by_translation += b.squaredNorm() - (b - trans).squaredNorm();
    left += (b - all).squaredNorm();
    total += b.squaredNorm();
    dof_left += 2 * n - 6;
    coordinates += 2 * n;
    ++out.pairs;
  }
  if (out.pairs == 0 || dof_left <= 0 || total <= 0) return out;
  const double var = left / dof_left;  // the noise, once both flows are out
  out.z = (extra / var - 3.0 * out.pairs) / std::sqrt(6.0 * out.pairs);
  out.share = std::max(0.0, by_translation - 3.0 * out.pairs * var) / total;
  out.rms_px = std::sqrt(std::max(0.0, extra - 3.0 * out.pairs * var) / coordinates);
  return out;
}

}  // namespace rsd::dsp
