// The inverse of rolling-shutter projection: a pixel's row fixes its capture time exactly,
// t_c = (v + v0) / r (eq. (1)), and the motion at t_c turns the pixel's viewing ray
// into a ray in the reference frame. Intersecting that ray with a scene-depth model and
// projecting at a reference time gives the global-shutter pixel: rectification.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::dsp {

struct RsRay {
  Eigen::Vector3d origin;     // camera centre at t_c, in reference coordinates
  Eigen::Vector3d direction;  // unit direction of the viewing ray, reference coordinates
  double t_c;                 // capture time after frame start
  Eigen::Vector3d point_at(double lambda) const { return origin + lambda * direction; }
};

// nullopt where the lens distortion cannot be inverted at that pixel.
std::optional<RsRay> backproject(const CameraModel& cam, const RowTiming& timing,
                                 const CameraMotion& motion, const Eigen::Vector2d& pixel);

// Scene depth for rectification, in the reference frame: a plane n . X = d, or infinitely
// far (only rotation matters).
struct DepthModel {
  bool infinite = true;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double distance = 1.0;
  static DepthModel at_infinity() { return {}; }
  static DepthModel fronto_parallel(double z) { return {false, Eigen::Vector3d::UnitZ(), z}; }
  static DepthModel plane(const Eigen::Vector3d& n, double d) { return {false, n, d}; }
};

// Point where the ray meets the depth model, homogeneous (w = 0 for a point at infinity);
// nullopt if the ray is parallel to the plane or meets it behind the camera.
std::optional<Eigen::Vector4d> intersect(const RsRay& ray, const DepthModel& depth);

// Rectify one pixel: where a global-shutter camera at time t_ref would have seen what the
// rolling-shutter camera recorded at `pixel`.
std::optional<Eigen::Vector2d> rectify_pixel(const CameraModel& cam, const RowTiming& timing,
                                             const CameraMotion& motion, const DepthModel& depth,
                                             const Eigen::Vector2d& pixel, double t_ref);

}  // namespace rsd::dsp
