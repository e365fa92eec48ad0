#include "dsp/sim/smooth_motion.hpp"

#include <cmath>
#include <random>

#include "dsp/geometry/camera_motion.hpp"

namespace rsd::dsp {

SmoothSignal3::SmoothSignal3(unsigned seed, const Eigen::Vector3d& amplitude, double base_hz) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> f(0.5, 1.5), ph(0, 2 * M_PI), a(0.5, 1.0);
  for (int axis = 0; axis < 3; ++axis) {
    double total = 0;
    for (int k = 0; k < kTerms; ++k) {
      amp_[axis][k] = a(rng);
      total += amp_[axis][k];
      omega_[axis][k] = 2 * M_PI * base_hz * f(rng) * (k + 1) / 2.0;
      phase_[axis][k] = ph(rng);
    }
    for (int k = 0; k < kTerms; ++k) amp_[axis][k] *= amplitude[axis] / total;  // peak <= amplitude
  }
}

Eigen::Vector3d SmoothSignal3::value(double t) const {
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int axis = 0; axis < 3; ++axis)
    for (int k = 0; k < kTerms; ++k) v[axis] += amp_[axis][k] * std::sin(omega_[axis][k] * t + phase_[axis][k]);
  return v;
}

Eigen::Vector3d SmoothSignal3::derivative(double t) const {
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int axis = 0; axis < 3; ++axis)
    for (int k = 0; k < kTerms; ++k)
      v[axis] += amp_[axis][k] * omega_[axis][k] * std::cos(omega_[axis][k] * t + phase_[axis][k]);
  return v;
}

Eigen::Quaterniond SmoothPose::orientation(double t) const {
  return Eigen::Quaterniond(R0 * exp_so3(rotation.value(t))).normalized();
}

Eigen::Vector3d SmoothPose::body_rate(double t) const {
  // w = vee(R^T dR/dt), by a central difference fine enough to be exact to ~1e-10 rad/s.
  const double h = 1e-5;
  const Eigen::Quaterniond a = orientation(t - h), b = orientation(t + h);
  return log_so3((a.conjugate() * b).toRotationMatrix()) / (2 * h);
}

}  // namespace rsd::dsp
