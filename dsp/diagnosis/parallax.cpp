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
  const double x = (px.x() - cam.cx) / cam.fx, y = (px.y() - cam.cy) / cam.fy;
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

namespace {

// The translation flow of one pair fitted to the residuals at `pos` (positions into r) whose
// length is within 4 robust scales of the current fit: twice, from no fit.
Eigen::Vector3d fit_pair(const CameraModel& cam, const DiagnosisModel& m, const std::vector<int>& idx,
                         const std::vector<Eigen::Vector2d>& r, const std::vector<size_t>& pos) {
  std::vector<Eigen::Matrix<double, 2, 3>> J(pos.size());
  for (size_t j = 0; j < pos.size(); ++j) J[j] = translation_flow(cam, m.observed(idx[pos[j]]));
  Eigen::Vector3d beta = Eigen::Vector3d::Zero();
  std::vector<double> len(pos.size());
  for (int pass = 0; pass < 2; ++pass) {
    for (size_t j = 0; j < pos.size(); ++j) len[j] = (r[pos[j]] - J[j] * beta).norm();
    const double limit = 4 * std::max(median(len) / std::sqrt(2 * std::log(2.0)), 1e-6);
    Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    int used = 0;
    for (size_t j = 0; j < pos.size(); ++j) {
      if (len[j] > limit) continue;
      N += J[j].transpose() * J[j], b += J[j].transpose() * r[pos[j]], ++used;
    }
    if (used < 6) return Eigen::Vector3d::Zero();
    beta = N.ldlt().solve(b);
  }
  return beta;
}

}  // namespace

void remove_translation(const DiagnosisModel& m, const std::vector<int>& idx, std::vector<Eigen::Vector2d>& r) {
  const CameraModel& cam = m.recording().nominal.cam;
  // The positions grouped by frame pair: sorted (rank, position) rather than a map of vectors,
  // which allocated per pair on every evaluation of the model.
  std::vector<std::pair<int, size_t>> by_pair;
  by_pair.reserve(idx.size());
  for (size_t k = 0; k < idx.size(); ++k)
    if (r[k].allFinite()) by_pair.emplace_back(m.frame_rank(idx[k]), k);
  std::sort(by_pair.begin(), by_pair.end());
  std::vector<size_t> pos;
  for (size_t b = 0, e = 0; b < by_pair.size(); b = e) {
    pos.clear();
    for (e = b; e < by_pair.size() && by_pair[e].first == by_pair[b].first; ++e) pos.push_back(by_pair[e].second);
    if (pos.size() < 6) continue;
    const Eigen::Vector3d beta = fit_pair(cam, m, idx, r, pos);
    for (size_t k : pos) r[k] -= translation_flow(cam, m.observed(idx[k])) * beta;
  }
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
  int dof_left = 0;
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
    ++out.pairs;
  }
  if (out.pairs == 0 || dof_left <= 0 || total <= 0) return out;
  const double var = left / dof_left;  // the noise, once both flows are out
  out.z = (extra / var - 3.0 * out.pairs) / std::sqrt(6.0 * out.pairs);
  out.share = std::max(0.0, by_translation - 3.0 * out.pairs * var) / total;
  return out;
}

}  // namespace rsd::dsp
