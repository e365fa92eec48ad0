#include "dsp/geometry/camera_motion.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rsd::dsp {

Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d m;
  m << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return m;
}

Eigen::Matrix3d exp_so3(const Eigen::Vector3d& phi) {
  const double th = phi.norm();
  if (th < 1e-8) return Eigen::Matrix3d::Identity() + hat(phi) + 0.5 * hat(phi) * hat(phi);
  return Eigen::AngleAxisd(th, phi / th).toRotationMatrix();
}

Eigen::Vector3d log_so3(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

Eigen::Affine3d LinearisedMotion::at(double t) const {
  Eigen::Affine3d a = Eigen::Affine3d::Identity();
  a.linear() = Eigen::Matrix3d::Identity() + t * hat(tw_.w);
  a.translation() = t * tw_.v;
  return a;
}

// SE(3) exponential: R = exp([t w]x), T = V (t v) with the left Jacobian
// V = I + (1 - cos th)/th^2 W + (th - sin th)/th^3 W^2, W = [t w]x, th = |t w|.
Eigen::Affine3d ScrewMotion::at(double t) const {
  const Eigen::Vector3d phi = t * tw_.w;
  const double th = phi.norm();
  const Eigen::Matrix3d W = hat(phi);
  double a, b;
  if (th < 1e-3) {  // series: the closed forms cancel catastrophically at small angles
    const double th2 = th * th;
    a = 0.5 - th2 / 24.0 + th2 * th2 / 720.0;
    b = 1.0 / 6.0 - th2 / 120.0 + th2 * th2 / 5040.0;
  } else {
    a = (1 - std::cos(th)) / (th * th);
    b = (th - std::sin(th)) / (th * th * th);
  }
  const Eigen::Matrix3d V = Eigen::Matrix3d::Identity() + a * W + b * W * W;
  Eigen::Affine3d g = Eigen::Affine3d::Identity();
  g.linear() = exp_so3(phi);
  g.translation() = V * (t * tw_.v);
  return g;
}

namespace {

// Rates linear over [0, dt] from (w0, v0) to (w1, v1): the pose change over [0, s], the rates'
// mean over [0, s] taken as constant (the screw motion, exact for constant rates; second order
// otherwise, and exact in angle about a fixed axis). dQ/dt = Q [w]x, dP/dt = Q v.
void advance(const Eigen::Matrix3d& Q, const Eigen::Vector3d& P, const Eigen::Vector3d& w0, const Eigen::Vector3d& w1,
             const Eigen::Vector3d& v0, const Eigen::Vector3d& v1, double dt, double s, Eigen::Matrix3d& Qo,
             Eigen::Vector3d& Po) {
  const double a = dt > 0 ? s / dt : 0.0;
  const Eigen::Vector3d w_mean = w0 + 0.5 * a * (w1 - w0), v_mean = v0 + 0.5 * a * (v1 - v0);
  const Eigen::Affine3d g = ScrewMotion(Twist{v_mean, w_mean}).at(s);
  Po = P + Q * g.translation();
  Qo = Q * g.linear();
}

}  // namespace

IntegratedMotion::IntegratedMotion(const Knot* knots, int n) : n_(n) {
  if (n < 1 || n > kMaxKnots) throw std::invalid_argument("IntegratedMotion: 1 to 32 knots");
  for (int k = 0; k < n; ++k) {
    knots_[k] = knots[k];
    if (k > 0 && !(knots_[k].t > knots_[k - 1].t)) throw std::invalid_argument("IntegratedMotion: knot times must increase");
  }
  at_knot_[0] = {Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()};
  for (int k = 0; k + 1 < n; ++k) {
    const Knot &a = knots_[k], &b = knots_[k + 1];
    const double dt = b.t - a.t;
    advance(at_knot_[k].Q, at_knot_[k].P, a.w, b.w, a.v, b.v, dt, dt, at_knot_[k + 1].Q, at_knot_[k + 1].P);
  }
  origin_ = pose(0.0);
}

IntegratedMotion::Pose IntegratedMotion::pose(double t) const {
  Pose out;
  if (t <= knots_[0].t) {  // before the first knot: its rates held
    const Knot& a = knots_[0];
    advance(at_knot_[0].Q, at_knot_[0].P, a.w, a.w, a.v, a.v, 0.0, t - a.t, out.Q, out.P);
    return out;
  }
  int k = 0;
  while (k + 1 < n_ && knots_[k + 1].t < t) ++k;
  const Knot& a = knots_[k];
  if (k + 1 == n_) {  // after the last knot: its rates held
    advance(at_knot_[k].Q, at_knot_[k].P, a.w, a.w, a.v, a.v, 0.0, t - a.t, out.Q, out.P);
    return out;
  }
  const Knot& b = knots_[k + 1];
  advance(at_knot_[k].Q, at_knot_[k].P, a.w, b.w, a.v, b.v, b.t - a.t, t - a.t, out.Q, out.P);
  return out;
}

Eigen::Affine3d IntegratedMotion::at(double t) const {
  const Pose p = pose(t);
  // Relative to the camera at t = 0; a static point X maps to Q^T (X - P).
  const Eigen::Matrix3d Q = origin_.Q.transpose() * p.Q;
  const Eigen::Vector3d P = origin_.Q.transpose() * (p.P - origin_.P);
  Eigen::Affine3d g = Eigen::Affine3d::Identity();
  g.linear() = Q.transpose();
  g.translation() = -Q.transpose() * P;
  return g;
}

SampledTrajectory::SampledTrajectory(std::vector<Sample> samples) : samples_(std::move(samples)) {
  if (samples_.empty()) throw std::invalid_argument("SampledTrajectory: no samples");
  for (size_t i = 1; i < samples_.size(); ++i)
    if (!(samples_[i].t >= samples_[i - 1].t))
      throw std::invalid_argument("SampledTrajectory: sample times must not decrease");
}

Eigen::Affine3d SampledTrajectory::at(double t) const {
  auto hi = std::upper_bound(samples_.begin(), samples_.end(), t,
                             [](double tt, const Sample& s) { return tt < s.t; });
  Eigen::Quaterniond q;
  Eigen::Vector3d p;
  if (hi == samples_.begin()) {
    q = samples_.front().q_wc, p = samples_.front().p_wc;
  } else if (hi == samples_.end()) {
    q = samples_.back().q_wc, p = samples_.back().p_wc;
  } else {
    const Sample& s0 = *(hi - 1);
    const Sample& s1 = *hi;
    const double dt = s1.t - s0.t;
    const double a = dt > 0 ? (t - s0.t) / dt : 0.0;
    q = s0.q_wc.slerp(a, s1.q_wc);
    p = (1 - a) * s0.p_wc + a * s1.p_wc;
  }
  // camera-from-world: X_c = R^T (X_w - p)
  Eigen::Affine3d g = Eigen::Affine3d::Identity();
  g.linear() = q.normalized().toRotationMatrix().transpose();
  g.translation() = -g.linear() * p;
  return g;
}

}  // namespace rsd::dsp
