#include "dsp/diagnosis/imu_axes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/model.hpp"
#include "dsp/diagnosis/robust_stats.hpp"

namespace rsd::dsp {

std::vector<Eigen::Matrix3d> axis_rotations() {
  std::vector<Eigen::Matrix3d> out;
  std::array<int, 3> perm = {0, 1, 2};
  do {
    for (int signs = 0; signs < 8; ++signs) {
      Eigen::Matrix3d R = Eigen::Matrix3d::Zero();
      for (int row = 0; row < 3; ++row) R(row, perm[row]) = (signs >> row & 1) ? -1.0 : 1.0;
      if (R.determinant() > 0) out.push_back(R);
    }
  } while (std::next_permutation(perm.begin(), perm.end()));
  return out;
}

namespace {

// Clock offsets are searched this far either side of the nominal one (within the data): a camera
// and an IMU on separate clocks can be a third of a second apart.
constexpr double kOffsetSpanS = 1.0;

// The candidate's best robust residual scale over clock offsets, 10 ms apart, then 2 ms apart
// around the best (a wrong offset blurs every axis order alike; a wrong order stays wrong).
AxesCandidate score(Recording rec, const Eigen::Matrix3d& R, int max_observations) {
  rec.nominal.imu_to_camera = R;
  const DiagnosisModel m(rec);
  std::vector<int> all(static_cast<size_t>(m.size()));
  for (int i = 0; i < m.size(); ++i) all[static_cast<size_t>(i)] = i;
  const std::vector<int> idx = subsample(all, static_cast<size_t>(max_observations));
  const std::pair<double, double> range = m.offset_range();
  ModelParams p = nominal_params(rec.nominal);
  const double t0 = p[Param::TimeOffset];
  AxesCandidate best{R, std::numeric_limits<double>::infinity(), t0};
  auto at = [&](double offset) {
    if (offset < range.first || offset > range.second) return;
    p[Param::TimeOffset] = offset;
    const double s = robust_stats(m.residuals(p, idx)).scale_px;
    if (s < best.scale_px) best.scale_px = s, best.time_offset_s = offset;
  };
  for (double d = -kOffsetSpanS; d <= kOffsetSpanS + 1e-9; d += 0.01) at(t0 + d);
  const double coarse = best.time_offset_s;
  for (double d = -0.01; d <= 0.01 + 1e-9; d += 0.002) at(coarse + d);
  return best;
}

}  // namespace

Eigen::Matrix3d nearest_axis_rotation(const Eigen::Matrix3d& R) {
  const std::vector<Eigen::Matrix3d> axes = axis_rotations();
  // The angle between two rotations grows as the trace of one's transpose times the other falls.
  return *std::max_element(axes.begin(), axes.end(), [&](const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
    return (a.transpose() * R).trace() < (b.transpose() * R).trace();
  });
}

AxesSearch search_imu_axes(const Recording& rec, int max_observations) {
  if (rec.kind != ObservationKind::Matches) throw std::invalid_argument("search_imu_axes: a matches recording (gyro motion) is needed");
  // The given matrix's tilt off its nearest axis order, in camera axes: a calibrated rig's
  // T_cam_imu is a degree or two off the axes, and that tilt is the camera's on its board,
  // whichever way the gyro's axes are labelled. Every candidate carries it, so the given matrix
  // is one of them (and a search that keeps its axis order keeps its calibration).
  const Eigen::Matrix3d& given = rec.nominal.imu_to_camera;
  const Eigen::Matrix3d tilt = given * nearest_axis_rotation(given).transpose();
  AxesSearch s;
  for (const Eigen::Matrix3d& R : axis_rotations()) s.ranked.push_back(score(rec, tilt * R, max_observations));
  std::stable_sort(s.ranked.begin(), s.ranked.end(), [](const AxesCandidate& a, const AxesCandidate& b) { return a.scale_px < b.scale_px; });
  return s;
}

}  // namespace rsd::dsp
