// Camera motion over a frame: the time dependence of the paper's P(t) = K [R(t) | T(t)].
//
// Every model answers one question: the transform that takes a point from the
// reference coordinates (the camera at the frame start t = 0 for velocity models, the
// world for trajectories) into the camera's coordinates at time t:  X_c(t) = R(t) X + T(t).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace rsd::dsp {

// The paper's velocities: v is the rate of change of T(t), w the angular velocity,
// both in camera axes, so that dX_c/dt = [w]x X_c + v for a static point.
struct Twist {
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
};

Eigen::Matrix3d hat(const Eigen::Vector3d& w);
// Exponential map of so(3) (Rodrigues), accurate for tiny angles.
Eigen::Matrix3d exp_so3(const Eigen::Vector3d& phi);
// Logarithm of SO(3): the rotation vector.
Eigen::Vector3d log_so3(const Eigen::Matrix3d& R);

class CameraMotion {
 public:
  virtual ~CameraMotion() = default;
  // Reference -> camera-at-time-t transform. Rigid for every model but LinearisedMotion.
  virtual Eigen::Affine3d at(double t) const = 0;
};

// The paper's linear approximation of P(t) about t = 0 with R(0) = I, T(0) = 0:
// P(t) ~ K [(I + t [w]x) | v t]. Exact when w = 0.
class LinearisedMotion final : public CameraMotion {
 public:
  explicit LinearisedMotion(const Twist& tw) : tw_(tw) {}
  Eigen::Affine3d at(double t) const override;

 private:
  Twist tw_;
};

// Constant v and w without linearisation: the screw motion X_c(t) = exp(t xi^) X,
// xi = (v, w), through the exponential map of SE(3).
class ScrewMotion final : public CameraMotion {
 public:
  explicit ScrewMotion(const Twist& tw) : tw_(tw) {}
  Eigen::Affine3d at(double t) const override;

 private:
  Twist tw_;
};

// The camera's own velocities sampled over a frame (camera axes, as a gyro gives them), linear
// in time between samples and held beyond them, integrated: each row gets the orientation the
// rates accumulate up to its time, not one rate held for the whole frame. The reference is the
// camera at t = 0, as for the twist models (at() with constant rates equals
// ScrewMotion(-w, -v) to second order in the step). Fixed capacity: building it allocates nothing.
class IntegratedMotion final : public CameraMotion {
 public:
  static constexpr int kMaxKnots = 32;
  struct Knot {
    double t = 0;
    Eigen::Vector3d w = Eigen::Vector3d::Zero();  // the camera's own angular velocity, rad/s
    Eigen::Vector3d v = Eigen::Vector3d::Zero();  // its velocity, m/s, camera axes
  };
  // `n` knots (1..kMaxKnots) at increasing times.
  IntegratedMotion(const Knot* knots, int n);
  Eigen::Affine3d at(double t) const override;

 private:
  struct Pose {
    Eigen::Matrix3d Q;  // camera-at-t axes in the reference
    Eigen::Vector3d P;  // camera-at-t position in the reference
  };
  Pose pose(double t) const;  // relative to the first knot
  Knot knots_[kMaxKnots];
  Pose at_knot_[kMaxKnots];
  int n_;
  Pose origin_;  // the pose at t = 0
};

// A pose over time, sampled: world -> camera transforms at increasing times; position
// interpolated linearly and orientation by slerp (as recording-v1 prescribes).
class SampledTrajectory final : public CameraMotion {
 public:
  struct Sample {
    double t;
    Eigen::Quaterniond q_wc;  // orientation of the camera in the world
    Eigen::Vector3d p_wc;     // position of the camera in the world
  };
  // Samples must be sorted by time with at least one entry; outside them the end
  // samples are held.
  explicit SampledTrajectory(std::vector<Sample> samples);
  Eigen::Affine3d at(double t) const override;

 private:
  std::vector<Sample> samples_;
};

// Any callable pose(t) as a CameraMotion (analytic trajectories, tests).
template <class F>
class FunctionMotion final : public CameraMotion {
 public:
  explicit FunctionMotion(F f) : f_(std::move(f)) {}
  Eigen::Affine3d at(double t) const override { return f_(t); }

 private:
  F f_;
};

}  // namespace rsd::dsp
