#include "dsp/geometry/camera_model.hpp"

#include "dsp/core/input_limits.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace rsd::dsp {

CameraModel CameraModel::from_hfov(int width, int height, double hfov_rad, const Distortion& lens) {
  CameraModel c;
  c.width = width;
  c.height = height;
  c.dist = lens;
  c.fx = c.fy = 0.5 * width / distorted_radius(lens, 0.5 * hfov_rad);
  c.cx = 0.5 * (width - 1);
  c.cy = 0.5 * (height - 1);
  return c;
}

CameraModel scaled_camera(const CameraModel& c, int width, int height) {
  const double sx = static_cast<double>(width) / c.width, sy = static_cast<double>(height) / c.height;
  CameraModel s = c;
  s.width = width, s.height = height;
  s.fx = c.fx * sx, s.fy = c.fy * sy;
  s.cx = (c.cx + 0.5) * sx - 0.5, s.cy = (c.cy + 0.5) * sy - 0.5;
  return s;
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
  const std::pair<const char*, double> d[] = {{"k1", c.dist.k1}, {"k2", c.dist.k2}, {"p1", c.dist.p1},
                                               {"p2", c.dist.p2}, {"k3", c.dist.k3}, {"k4", c.dist.k4}};
  for (const auto& [name, v] : d)
    if (!limits::kDistortion.contains(v)) return {P::Distortion, name, outside(name, v, limits::kDistortion)};
  // Each lens's own terms only: radtan has no k4, the equidistant lens no tangential terms.
  if (c.dist.model == LensModel::PinholeRadtan && c.dist.k4 != 0)
    return {P::Distortion, "k4", "k4 is not a term of the pinhole-radtan lens"};
  if (c.dist.model == LensModel::PinholeEqui && (c.dist.p1 != 0 || c.dist.p2 != 0))
    return {P::Distortion, c.dist.p1 != 0 ? "p1" : "p2", "the pinhole-equi lens has no tangential terms (p1, p2)"};
  return {};
}

double widest_ray_angle(const CameraModel& cam) {
  double angle = 0;
  for (const Eigen::Vector2d& c : {Eigen::Vector2d(0, 0), Eigen::Vector2d(cam.width, 0), Eigen::Vector2d(0, cam.height),
                                  Eigen::Vector2d(cam.width, cam.height)})
    if (const auto ray = cam.ray(c)) angle = std::max(angle, std::acos(std::clamp(ray->normalized().z(), -1.0, 1.0)));
  return angle > 0 ? angle : 0.5;
}

}  // namespace rsd::dsp
