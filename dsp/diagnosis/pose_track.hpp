// Fast evaluation of the two motion tracks the diagnosis evaluates millions of times: the
// trajectory of a landmarks recording (position linear, orientation slerp, as
// docs/formats/recording-v1.md prescribes) and the rotation exponential the gyro track
// uses. A slerp between samples q0, q1 is q0 exp(tau log(q0^-1 q1)): with the logarithm of each
// interval precomputed, an evaluation is one small-angle exponential (a short series, no
// trigonometric calls) instead of acos and three sines: the same result to 1e-15.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "dsp/observation/recording.hpp"

namespace rsd::dsp {

// exp of so(3) (Rodrigues) with sin(x)/x and (1 - cos x)/x^2 by their series for |x| < 0.25
// (error < 1e-16), the library functions beyond.
Eigen::Matrix3d exp_so3_fast(const Eigen::Vector3d& phi);
// Exp(phi) v by Rodrigues' formula on the vector (the same series as exp_so3_fast).
Eigen::Vector3d rotate_so3(const Eigen::Vector3d& phi, const Eigen::Vector3d& v);
// The right Jacobian J_r(phi) of so(3): Exp(phi + d) = Exp(phi) Exp(J_r(phi) d) to first order,
// so that d/dt Exp(phi(t)) = Exp(phi) [J_r(phi) phi']x.
Eigen::Matrix3d so3_right_jacobian(const Eigen::Vector3d& phi);

class PoseTrack {
 public:
  // Poses sorted by time (at least one); equal times keep the later pose.
  explicit PoseTrack(std::vector<PoseSample> poses);
  // World-from-body orientation R and position p at t (motion clock); held at the ends.
  void at(double t, Eigen::Matrix3d& R, Eigen::Vector3d& p) const;
  double t_begin() const { return knots_.front().t; }
  double t_end() const { return knots_.back().t; }

 private:
  struct Knot {
    double t;
    Eigen::Matrix3d R;
    Eigen::Vector3d p, phi;  // phi = log(R^T R_next), the interval's rotation
  };
  std::vector<Knot> knots_;
};

}  // namespace rsd::dsp
