#include "dsp/diagnosis/pose_track.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "dsp/geometry/camera_motion.hpp"

namespace rsd::dsp {

Eigen::Matrix3d exp_so3_fast(const Eigen::Vector3d& phi) {
  const double x2 = phi.squaredNorm();
  double a, b;  // sin(x)/x, (1 - cos x)/x^2
  if (x2 < 0.0625) {
    // Horner on x^2; the first omitted terms are x^10/11! and x^10/12!: < 1e-16 at x = 0.25.
    a = 1 - x2 / 6 * (1 - x2 / 20 * (1 - x2 / 42 * (1 - x2 / 72 * (1 - x2 / 110))));
    b = 0.5 * (1 - x2 / 12 * (1 - x2 / 30 * (1 - x2 / 56 * (1 - x2 / 90 * (1 - x2 / 132)))));
  } else {
    const double x = std::sqrt(x2);
    a = std::sin(x) / x, b = (1 - std::cos(x)) / x2;
  }
  const Eigen::Matrix3d K = hat(phi);
  return Eigen::Matrix3d::Identity() + a * K + b * K * K;
}

PoseTrack::PoseTrack(std::vector<PoseSample> poses) {
  if (poses.empty()) throw std::invalid_argument("trajectory: no poses");
  std::stable_sort(poses.begin(), poses.end(), [](const PoseSample& a, const PoseSample& b) { return a.t < b.t; });
  for (const PoseSample& s : poses) {
    if (!knots_.empty() && s.t == knots_.back().t) knots_.pop_back();
    knots_.push_back({s.t, s.q.normalized().toRotationMatrix(), s.p, Eigen::Vector3d::Zero()});
  }
  for (size_t k = 0; k + 1 < knots_.size(); ++k) knots_[k].phi = log_so3(knots_[k].R.transpose() * knots_[k + 1].R);
}

void PoseTrack::at(double t, Eigen::Matrix3d& R, Eigen::Vector3d& p) const {
  auto hi = std::upper_bound(knots_.begin(), knots_.end(), t, [](double tt, const Knot& k) { return tt < k.t; });
  if (hi == knots_.begin() || hi == knots_.end()) {
    const Knot& k = hi == knots_.begin() ? knots_.front() : knots_.back();
    R = k.R, p = k.p;
    return;
  }
  const Knot &a = *(hi - 1), &b = *hi;
  const double tau = (t - a.t) / (b.t - a.t);
  R = a.R * exp_so3_fast(tau * a.phi);
  p = (1 - tau) * a.p + tau * b.p;
}

}  // namespace rsd::dsp
