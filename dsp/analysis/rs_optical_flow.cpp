#include "dsp/analysis/rs_optical_flow.hpp"

#include <cmath>

namespace rsd::dsp {

namespace {

// Velocity of the normalised image point xn = (x, y) = (X/Z, Y/Z) of a static point at depth z
// under dX_c/dt = [w]x X_c + v: the classic perspective motion field, in 1/s.
Eigen::Vector2d normalised_flow(const Twist& tw, const Eigen::Vector2d& xn, double z) {
  const double x = xn.x(), y = xn.y();
  const Eigen::Vector3d& v = tw.v;
  const Eigen::Vector3d& w = tw.w;
  return {(v.x() - x * v.z()) / z + w.y() * (1 + x * x) - w.z() * y - w.x() * x * y,
          (v.y() - y * v.z()) / z + w.z() * x - w.x() * (1 + y * y) + w.y() * x * y};
}

// |r - vdot_p| below this fraction of |r| counts as degenerate: the flow would exceed the
// perspective flow by a factor of 1e9, far beyond any physical meaning.
constexpr double kDegenerate = 1e-9;

}  // namespace

Eigen::Vector2d perspective_flow(const CameraModel& cam, const Twist& tw, const Eigen::Vector2d& pixel,
                                 double depth_z) {
  const Eigen::Vector2d xn((pixel.x() - cam.cx) / cam.fx, (pixel.y() - cam.cy) / cam.fy);
  const Eigen::Vector2d f = normalised_flow(tw, xn, depth_z);
  return {cam.fx * f.x(), cam.fy * f.y()};
}

std::optional<Eigen::Vector2d> rs_optical_flow(const CameraModel& cam, const RowTiming& timing,
                                               const Twist& tw, const Eigen::Vector2d& rs_pixel,
                                               double depth_z_at_capture) {
  if (!(depth_z_at_capture > 0)) return std::nullopt;
  const auto xn = cam.from_pixel(rs_pixel);
  if (!xn) return std::nullopt;
  // Image velocity at the capture instant, in recorded (distorted) pixels/s.
  const Eigen::Vector2d fn = cam.distort_jacobian(*xn) * normalised_flow(tw, *xn, depth_z_at_capture);
  const Eigen::Vector2d qdot_p(cam.fx * fn.x(), cam.fy * fn.y());
  // Implicit differentiation of eq. (3) in the frame start t0 gives
  // ds/dt0 = r / (r - vdot_p): the corrected eq. (6).
  const double r = timing.r();
  const double den = r - qdot_p.y();
  if (!(std::abs(den) > kDegenerate * std::abs(r))) return std::nullopt;
  return Eigen::Vector2d(qdot_p * (r / den));
}

Eigen::Vector2d rs_optical_flow_paper(const Eigen::Vector2d& uv_n, double z, const Twist& tw,
                                      double r_n) {
  // eq. (6) as printed, K = I, v0 = 0.
  const double u = uv_n.x(), v = uv_n.y(), r = r_n;
  const double vx = tw.v.x(), vy = tw.v.y(), wz = tw.w.z();
  const double udot_p = vx / z - wz * v, vdot_p = vy / z + wz * u;
  const double s = r * z / (v * vx * wz + r * z * (r - vdot_p));
  return {s * (r * udot_p + wz * v * vdot_p), s * (r * vdot_p + wz * v * udot_p)};
}

Eigen::Vector2d rs_optical_flow_linearised(const Eigen::Vector2d& uv_n, double z, const Twist& tw,
                                           double r_n) {
  // The t0-derivative of the linearised model (Table 1 case a): eq. (6) with the
  // sign of wz v udot_p in the second component corrected. Derivation in docs/optical-flow.md.
  const double u = uv_n.x(), v = uv_n.y(), r = r_n;
  const double vx = tw.v.x(), vy = tw.v.y(), wz = tw.w.z();
  const double udot_p = vx / z - wz * v, vdot_p = vy / z + wz * u;
  const double s = r * z / (v * vx * wz + r * z * (r - vdot_p));
  return {s * (r * udot_p + wz * v * vdot_p), s * (r * vdot_p - wz * v * udot_p)};
}

}  // namespace rsd::dsp
