#include "dsp/geometry/camera_model.hpp"

#include "dsp/core/input_limits.hpp"

#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <utility>

namespace rsd::dsp {

CameraModel CameraModel::from_hfov(int width, int height, double hfov_rad) {
  CameraModel c;
  c.width = width;
  c.height = height;
  c.fx = c.fy = 0.5 * width / std::tan(0.5 * hfov_rad);
  c.cx = 0.5 * (width - 1);
  c.cy = 0.5 * (height - 1);
  return c;
}

Eigen::Vector2d CameraModel::distort(const Eigen::Vector2d& xn) const {
  const double x = xn.x(), y = xn.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (dist.k1 + r2 * (dist.k2 + r2 * dist.k3));
  return {x * radial + 2 * dist.p1 * x * y + dist.p2 * (r2 + 2 * x * x),
          y * radial + dist.p1 * (r2 + 2 * y * y) + 2 * dist.p2 * x * y};
}

Eigen::Matrix2d CameraModel::distort_jacobian(const Eigen::Vector2d& xn) const {
  const double x = xn.x(), y = xn.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (dist.k1 + r2 * (dist.k2 + r2 * dist.k3));
  // d(radial)/d(r2); d(r2)/dx = 2x, d(r2)/dy = 2y.
  const double dradial = dist.k1 + r2 * (2 * dist.k2 + 3 * r2 * dist.k3);
  Eigen::Matrix2d J;
  J(0, 0) = radial + x * dradial * 2 * x + 2 * dist.p1 * y + dist.p2 * 6 * x;
  J(0, 1) = x * dradial * 2 * y + 2 * dist.p1 * x + dist.p2 * 2 * y;
  J(1, 0) = y * dradial * 2 * x + dist.p1 * 2 * x + 2 * dist.p2 * y;
  J(1, 1) = radial + y * dradial * 2 * y + dist.p1 * 6 * y + 2 * dist.p2 * x;
  return J;
}

std::optional<Eigen::Vector2d> CameraModel::undistort(const Eigen::Vector2d& xd) const {
  if (dist.is_zero()) return xd;
  Eigen::Vector2d xn = xd;  // distortion is a perturbation of identity: start there
  for (int it = 0; it < 50; ++it) {
    const Eigen::Vector2d err = distort(xn) - xd;
    if (err.norm() < 1e-15) return xn;
    const Eigen::Matrix2d J = distort_jacobian(xn);
    if (std::abs(J.determinant()) < 1e-12) return std::nullopt;
    xn -= J.partialPivLu().solve(err);
    if (!xn.allFinite()) return std::nullopt;
  }
  if ((distort(xn) - xd).norm() < 1e-12) return xn;
  return std::nullopt;
}

Eigen::Vector2d CameraModel::to_pixel(const Eigen::Vector2d& xn) const {
  const Eigen::Vector2d xd = distort(xn);
  return {fx * xd.x() + cx, fy * xd.y() + cy};
}

std::optional<Eigen::Vector2d> CameraModel::from_pixel(const Eigen::Vector2d& px) const {
  return undistort({(px.x() - cx) / fx, (px.y() - cy) / fy});
}

std::optional<Eigen::Vector2d> CameraModel::project(const Eigen::Vector3d& Xc) const {
  if (!(Xc.z() > 0)) return std::nullopt;
  return to_pixel(Xc.head<2>() / Xc.z());
}

std::optional<Eigen::Vector3d> CameraModel::ray(const Eigen::Vector2d& px) const {
  const auto xn = from_pixel(px);
  if (!xn) return std::nullopt;
  return Eigen::Vector3d(xn->x(), xn->y(), 1.0);
}

namespace {

std::string outside(const char* name, double v, const limits::Range& r) {
  char text[96];
  std::snprintf(text, sizeof text, "%s %.9g is outside %s", name, v, r.text);
  return text;
}

}  // namespace

CameraOutOfRange out_of_range(const CameraModel& c) {
  using P = CameraOutOfRange;
  if (!limits::side_ok(c.width)) return {P::Size, "width", outside("width", c.width, limits::kSide)};
  if (!limits::side_ok(c.height)) return {P::Size, "height", outside("height", c.height, limits::kSide)};
  if (!limits::kFocalPx.contains(c.fx)) return {P::Focal, "fx", outside("fx", c.fx, limits::kFocalPx)};
  if (!limits::kFocalPx.contains(c.fy)) return {P::Focal, "fy", outside("fy", c.fy, limits::kFocalPx)};
  if (!limits::kPrincipalPointSizes.contains(c.cx / c.width))
    return {P::PrincipalPoint, "cx", outside("cx / width", c.cx / c.width, limits::kPrincipalPointSizes)};
  if (!limits::kPrincipalPointSizes.contains(c.cy / c.height))
    return {P::PrincipalPoint, "cy", outside("cy / height", c.cy / c.height, limits::kPrincipalPointSizes)};
  const std::pair<const char*, double> d[] = {{"k1", c.dist.k1}, {"k2", c.dist.k2}, {"p1", c.dist.p1}, {"p2", c.dist.p2}, {"k3", c.dist.k3}};
  for (const auto& [name, v] : d)
    if (!limits::kDistortion.contains(v)) return {P::Distortion, name, outside(name, v, limits::kDistortion)};
  return {};
}

}  // namespace rsd::dsp
