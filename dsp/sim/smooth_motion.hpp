// Smooth, repeatable random motion for simulations: each coordinate is a sum of a few
// sinusoids with random frequencies and phases, so velocities and accelerations are
// continuous and every run with the same seed is the same.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

namespace rsd::dsp {

class SmoothSignal3 {
 public:
  // amplitude per axis; frequencies drawn from [0.5, 1.5] x base_hz.
  SmoothSignal3(unsigned seed, const Eigen::Vector3d& amplitude, double base_hz);
  Eigen::Vector3d value(double t) const;
  Eigen::Vector3d derivative(double t) const;

 private:
  static constexpr int kTerms = 3;
  std::array<std::array<double, kTerms>, 3> amp_{}, omega_{}, phase_{};
};

// World-from-body pose: position p0 + translation(t), orientation R0 exp(rotation(t)).
struct SmoothPose {
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R0 = Eigen::Matrix3d::Identity();
  SmoothSignal3 translation, rotation;
  Eigen::Quaterniond orientation(double t) const;
  Eigen::Vector3d position(double t) const { return p0 + translation.value(t); }
  // Angular rate in body axes (dR/dt = R [w]x), by differentiating the orientation.
  Eigen::Vector3d body_rate(double t) const;
};

}  // namespace rsd::dsp
