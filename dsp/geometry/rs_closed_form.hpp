// The closed form of eq. (4) (Meingast, Geyer, Sastry 2005, Sec. 2.1,
// Table 1 row a), written once as templates so that the same arithmetic serves the double
// solver project_fronto_parallel and Ceres' automatic differentiation (T = ceres::Jet).
//
// For v = (vx, vy, 0), w = (0, 0, wz) and the linearised P(t) (exact when w = 0), a point
// X = (x, y, z) in the camera frame at the frame start is captured at
//     t_c = (y + v0_n z) / (r_n z - vy - wz x)
// and appears at
//     q(t_c) = (x/z + t_c (vx - wz y) / z,  y/z + t_c (vy + wz x) / z),
// on the unit-focal image plane; r_n = r / fy and v0_n = (v0 + cy) / fy carry the paper's
// K = I form over to a camera with intrinsics K (docs/geometry.md).
//
// The templates do no checks: callers test the denominator and depth in double
// (project_fronto_parallel) or reject the step (the bundle adjuster's cost functors).
#pragma once

#include <Eigen/Core>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::dsp {

// The readout on the unit-focal image plane: eq. (1) with K removed, y_n = r_n t - v0_n.
struct NormalisedReadout {
  double r_n = 0, v0_n = 0;
};

inline NormalisedReadout normalised_readout(const CameraModel& cam, const RowTiming& timing) {
  return {timing.r() / cam.fy, (timing.v0() + cam.cy) / cam.fy};
}

// r_n z - vy - wz x: the rate at which the readout gains on the point's image (times z).
// It vanishes when the image runs down with the readout, which then never catches it.
template <class T>
T fronto_parallel_denominator(const Eigen::Vector3<T>& X, const NormalisedReadout& ro,
                              const Twist& tw) {
  return ro.r_n * X.z() - tw.v.y() - tw.w.z() * X.x();
}

// Capture time t_c after the frame start, eq. (4).
template <class T>
T fronto_parallel_capture_time(const Eigen::Vector3<T>& X, const NormalisedReadout& ro,
                               const Twist& tw) {
  return (X.y() + ro.v0_n * X.z()) / fronto_parallel_denominator(X, ro, tw);
}

// The image q(t_c) on the unit-focal plane: the perspective image q(0) plus t_c times the
// perspective optical flow ((vx - wz y) / z, (vy + wz x) / z), eq. (4).
template <class T>
Eigen::Vector2<T> fronto_parallel_image(const Eigen::Vector3<T>& X, const T& t_c, const Twist& tw) {
  return {X.x() / X.z() + t_c * (tw.v.x() - tw.w.z() * X.y()) / X.z(),
          X.y() / X.z() + t_c * (tw.v.y() + tw.w.z() * X.x()) / X.z()};
}

// K applied to a unit-focal point; lens distortion is outside the closed form's assumptions.
template <class T>
Eigen::Vector2<T> pinhole_pixel(const CameraModel& cam, const Eigen::Vector2<T>& q) {
  return {cam.fx * q.x() + cam.cx, cam.fy * q.y() + cam.cy};
}

// eq. (4) in pixels, for a distortion-free camera.
template <class T>
Eigen::Vector2<T> fronto_parallel_pixel(const CameraModel& cam, const NormalisedReadout& ro,
                                        const Twist& tw, const Eigen::Vector3<T>& X) {
  return pinhole_pixel(cam, fronto_parallel_image(X, fronto_parallel_capture_time(X, ro, tw), tw));
}

}  // namespace rsd::dsp
