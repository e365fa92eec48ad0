// Two-view bundle adjustment with Ceres, with either projection model of the paper's
// simulation (Meingast, Geyer, Sastry 2005, Sec. 4):
//   * RollingShutter: each camera is a rolling-shutter camera moving with a known constant
//     twist v = (vx, vy, 0), w = (0, 0, wz) in its own frame during its readout, imaged by
//     the closed form eq. (4) (rs_closed_form.hpp; exact when w = 0);
//   * Perspective: the same cameras taken as global-shutter pinholes, q = pi(K X_c).
//
// Unknowns: the pose of camera 2 and the 3-D points. Gauge: camera 1 is the reference
// frame (identity pose at its frame start), and the length of camera 2's translation stays
// at its initial value (the translation moves on a sphere, ceres::SphereManifold<3>), so
// the scale is fixed and only its direction is estimated. Camera 2's rotation is a unit
// quaternion on ceres::QuaternionManifold. Intrinsics, row timing and velocities are known.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <optional>
#include <vector>

#include <ceres/rotation.h>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/geometry/row_timing.hpp"
#include "dsp/geometry/rs_closed_form.hpp"

namespace rsd::dsp {

enum class ProjectionModel { RollingShutter, Perspective };
const char* to_string(ProjectionModel m);

// A rigid transform into a camera's frame at its frame start: X_c = R X + t.
struct RigidPose {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Vector3d apply(const Eigen::Vector3d& X) const { return q * X + t; }
};

// What the cameras are and what they saw. Both cameras share intrinsics and row timing;
// motion[i] is camera i's twist in its own frame over its frame readout (ignored by the
// perspective model). pixels[i][j] is point j observed in camera i (every point in both).
struct TwoViewData {
  CameraModel cam;  // distortion-free
  RowTiming timing;
  std::array<Twist, 2> motion;
  std::array<std::vector<Eigen::Vector2d>, 2> pixels;
};

// Camera 2's pose and the points, both in camera 1's frame at its frame start.
struct TwoViewEstimate {
  RigidPose cam2;
  std::vector<Eigen::Vector3d> points;
};

struct TwoViewBaOptions {
  ProjectionModel model = ProjectionModel::RollingShutter;
  // Huber loss with this scale (pixels) when > 0; 0 means plain least squares, the
  // maximum-likelihood choice for Gaussian pixel noise without outliers.
  double huber_px = 0;
  int max_iterations = 200;
};

struct TwoViewBaResult {
  TwoViewEstimate estimate;
  double rms_px = 0;       // sqrt(mean over observations of |predicted - observed|^2)
  bool converged = false;  // Ceres stopped on a tolerance, not on the iteration limit
  int iterations = 0;
};

// ---------------------------------------------------------------- cost functors
//
// One observation's residual (predicted minus observed pixel, 2 values) as Ceres functors
// over the parameter blocks q (camera rotation, unit quaternion in Ceres' (w, x, y, z)
// order), t (camera translation) and X (the point in camera 1's frame), for
// ceres::AutoDiffCostFunction<Functor, 2, 4, 3, 3>. They return false where the model has
// no image, so that Ceres rejects the step instead of using a meaningless residual.

// X_c = R(q) X + t.
template <class T>
Eigen::Vector3<T> transform_to_camera(const T* q, const T* t, const T* X) {
  Eigen::Vector3<T> Xc;
  ceres::UnitQuaternionRotatePoint(q, X, Xc.data());
  return Xc + Eigen::Vector3<T>(t[0], t[1], t[2]);
}

// The rolling-shutter model: eq. (4) with known twist and row timing.
struct RollingShutterReprojection {
  CameraModel cam;
  NormalisedReadout readout;
  Twist motion;
  Eigen::Vector2d observed;

  template <class T>
  bool operator()(const T* q, const T* t, const T* X, T* residual) const {
    const Eigen::Vector3<T> Xc = transform_to_camera(q, t, X);
    // Behind the camera, or the image outruns the readout (the denominator changes sign
    // against the readout direction): eq. (4) gives no capture.
    const T den = fronto_parallel_denominator(Xc, readout, motion);
    if (!(Xc.z() > T(0)) || !(den * readout.r_n > T(0))) return false;
    const Eigen::Vector2<T> px = fronto_parallel_pixel(cam, readout, motion, Xc);
    residual[0] = px.x() - observed.x();
    residual[1] = px.y() - observed.y();
    return true;
  }
};

// The perspective (global-shutter) model: the limit r -> inf of eq. (4).
struct PerspectiveReprojection {
  CameraModel cam;
  Eigen::Vector2d observed;

  template <class T>
  bool operator()(const T* q, const T* t, const T* X, T* residual) const {
    const Eigen::Vector3<T> Xc = transform_to_camera(q, t, X);
    if (!(Xc.z() > T(0))) return false;
    const Eigen::Vector2<T> px =
        pinhole_pixel(cam, Eigen::Vector2<T>(Xc.x() / Xc.z(), Xc.y() / Xc.z()));
    residual[0] = px.x() - observed.x();
    residual[1] = px.y() - observed.y();
    return true;
  }
};

// ---------------------------------------------------------------- bundle adjustment

// Refines `initial` by minimising the reprojection error of the chosen model. |cam2.t| of
// `initial` must be non-zero: it is the scale the solution keeps.
TwoViewBaResult two_view_bundle_adjust(const TwoViewData& data, const TwoViewEstimate& initial,
                                       const TwoViewBaOptions& options);

// The model's prediction of point X (camera 1 frame) in camera `cam_index` with pose
// `pose` (identity for camera 1); nullopt where the model has no image (behind the camera,
// or never caught by the readout). The cost functors' arithmetic in double.
std::optional<Eigen::Vector2d> two_view_predict(const TwoViewData& data, ProjectionModel model,
                                                int cam_index, const RigidPose& pose,
                                                const Eigen::Vector3d& X);

// Root-mean-square reprojection error of `est` under `model` (pixels); inf if a point has
// no image.
double two_view_rms(const TwoViewData& data, ProjectionModel model, const TwoViewEstimate& est);

}  // namespace rsd::dsp
