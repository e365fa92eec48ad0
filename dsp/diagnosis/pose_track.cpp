#include "dsp/diagnosis/pose_track.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "dsp/geometry/camera_motion.hpp"

namespace rsd::dsp {

namespace {

// sin(x)/x and (1 - cos x)/x^2 for x^2 = x2.
void rodrigues_coefficients(double x2, double& a, double& b) {
  if (x2 < 0.0625) {
    // Horner on x^2; the first omitted terms are x^10/11! and x^10/12!: < 1e-16 at x = 0.25.
    // Multiplied by the reciprocals (a chain of divisions cost a tenth of a diagnosis).
    constexpr double r6 = 1.0 / 6, r20 = 1.0 / 20, r42 = 1.0 / 42, r72 = 1.0 / 72, r110 = 1.0 / 110;
    constexpr double r12 = 1.0 / 12, r30 = 1.0 / 30, r56 = 1.0 / 56, r90 = 1.0 / 90, r132 = 1.0 / 132;
    a = 1 - x2 * r6 * (1 - x2 * r20 * (1 - x2 * r42 * (1 - x2 * r72 * (1 - x2 * r110))));
    b = 0.5 * (1 - x2 * r12 * (1 - x2 * r30 * (1 - x2 * r56 * (1 - x2 * r90 * (1 - x2 * r132)))));
  } else {
    const double x = std::sqrt(x2);
    a = std::sin(x) / x, b = (1 - std::cos(x)) / x2;
  }
}

}  // namespace

Eigen::Matrix3d exp_so3_fast(const Eigen::Vector3d& phi) {
  double a, b;
  rodrigues_coefficients(phi.squaredNorm(), a, b);
  const Eigen::Matrix3d K = hat(phi);
  return Eigen::Matrix3d::Identity() + a * K + b * K * K;
}

Eigen::Vector3d rotate_so3(const Eigen::Vector3d& phi, const Eigen::Vector3d& v) {
  double a, b;
  rodrigues_coefficients(phi.squaredNorm(), a, b);
  const Eigen::Vector3d pv = phi.cross(v);
  return v + a * pv + b * phi.cross(pv);
}

Eigen::Matrix3d so3_right_jacobian(const Eigen::Vector3d& phi) {
  // J_r = I - b K + c K^2, b = (1 - cos x) / x^2, c = (x - sin x) / x^3 = (1 - sin(x)/x) / x^2.
  const double x2 = phi.squaredNorm();
  double a, b;
  rodrigues_coefficients(x2, a, b);
  constexpr double r20 = 1.0 / 20, r42 = 1.0 / 42, r72 = 1.0 / 72;
  const double c = x2 < 0.0625 ? (1 - x2 * r20 * (1 - x2 * r42 * (1 - x2 * r72))) / 6 : (1 - a) / x2;
  const Eigen::Matrix3d K = hat(phi);
  return Eigen::Matrix3d::Identity() - b * K + c * K * K;
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
