#include "dsp/geometry/rs_backprojection.hpp"

#include <Eigen/LU>

namespace rsd::dsp {

std::optional<RsRay> backproject(const CameraModel& cam, const RowTiming& timing,
                                 const CameraMotion& motion, const Eigen::Vector2d& pixel) {
  const auto d_cam = cam.ray(pixel);
  if (!d_cam) return std::nullopt;
  const double t_c = timing.row_time(pixel.y());
  // X_c = A X + b at t_c, so X = A^-1 (X_c - b): the centre is A^-1(-b), the direction A^-1 d.
  const Eigen::Affine3d g = motion.at(t_c);
  const Eigen::Matrix3d Ainv = g.linear().inverse();
  RsRay ray;
  ray.t_c = t_c;
  ray.origin = -(Ainv * g.translation());
  ray.direction = (Ainv * *d_cam).normalized();
  return ray;
}

std::optional<Eigen::Vector4d> intersect(const RsRay& ray, const DepthModel& depth) {
  if (depth.infinite) return Eigen::Vector4d(ray.direction.x(), ray.direction.y(), ray.direction.z(), 0);
  const double denom = depth.normal.dot(ray.direction);
  if (std::abs(denom) < 1e-12) return std::nullopt;
  const double lambda = (depth.distance - depth.normal.dot(ray.origin)) / denom;
  if (!(lambda > 0)) return std::nullopt;
  const Eigen::Vector3d X = ray.point_at(lambda);
  return Eigen::Vector4d(X.x(), X.y(), X.z(), 1);
}

std::optional<Eigen::Vector2d> rectify_pixel(const CameraModel& cam, const RowTiming& timing,
                                             const CameraMotion& motion, const DepthModel& depth,
                                             const Eigen::Vector2d& pixel, double t_ref) {
  const auto ray = backproject(cam, timing, motion, pixel);
  if (!ray) return std::nullopt;
  const auto Xh = intersect(*ray, depth);
  if (!Xh) return std::nullopt;
  const Eigen::Affine3d g = motion.at(t_ref);
  // A point at infinity moves only with the rotation part of the motion.
  const Eigen::Vector3d Xc = g.linear() * Xh->head<3>() + Xh->w() * g.translation();
  return cam.project(Xc);
}

}  // namespace rsd::dsp
