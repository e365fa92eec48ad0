// Rolling-shutter projection: solve the paper's rolling-shutter constraint, eq. (3),
//     pi_y(P(t_c) X) = r t_c - v0 = v,
// for the capture time t_c of a point X, then project it at t_c. One function per row of
// the paper's Table 1 (cases a-c use the linearised P(t), d and e the exact motion).
//
// Every solver looks for t_c inside a capture window (by default the times at which the
// readout passes rows -H/2 .. 1.5 H) and returns the earliest root there: the paper's
// "smallest positive root" when the window starts at the frame start. A root outside the
// window, a vanishing denominator or a negative discriminant is reported as NoSolution,
// never as a number.
#pragma once

#include <Eigen/Core>
#include <limits>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::dsp {

enum class RsStatus {
  Ok,
  NoSolution,         // the constraint has no root in the capture window
  BehindCamera,       // the root puts the point behind the camera
  UnsupportedMotion,  // the case's assumptions on (v, w) or lens distortion do not hold
};
const char* to_string(RsStatus s);

struct RsProjection {
  RsStatus status = RsStatus::NoSolution;
  Eigen::Vector2d pixel = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  double t_c = std::numeric_limits<double>::quiet_NaN();  // capture time after frame start
  bool ok() const { return status == RsStatus::Ok; }
};

struct CaptureWindow {
  double t_begin = 0, t_end = 0;
  bool contains(double t) const { return t >= t_begin && t <= t_end; }
};
// Times at which the readout passes rows [-margin_rows, height - 1 + margin_rows].
CaptureWindow capture_window(const RowTiming& timing, double margin_rows);
CaptureWindow default_capture_window(const RowTiming& timing);

// (a) v = (vx, vy, 0), w = (0, 0, wz), linearised P(t): the closed form eq. (4),
//     generalised to K and v0; exact when w = 0. X is in the camera frame at t = 0.
RsProjection project_fronto_parallel(const CameraModel& cam, const RowTiming& timing,
                                     const Twist& tw, const Eigen::Vector3d& X);
RsProjection project_fronto_parallel(const CameraModel& cam, const RowTiming& timing,
                                     const Twist& tw, const Eigen::Vector3d& X,
                                     const CaptureWindow& win);

// (b) v = (0, 0, vz), w = 0: quadratic in t_c, earliest root in the window.
RsProjection project_axial(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                           const Eigen::Vector3d& X);
RsProjection project_axial(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                           const Eigen::Vector3d& X, const CaptureWindow& win);

// (c) general v and w with linearised P(t): quadratic in t_c.
RsProjection project_linearised(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                                const Eigen::Vector3d& X);
RsProjection project_linearised(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                                const Eigen::Vector3d& X, const CaptureWindow& win);

// (d) constant v and w without linearisation (screw motion): root finder. Lens distortion
//     is honoured (the row is the distorted row).
RsProjection project_screw(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                           const Eigen::Vector3d& X);
RsProjection project_screw(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                           const Eigen::Vector3d& X, const CaptureWindow& win);

// (e) any motion given as pose over time: bracketed root finder (scan for the first sign
//     change of the constraint's residual, then Brent). X is in the motion's reference frame.
RsProjection project_trajectory(const CameraModel& cam, const RowTiming& timing,
                                const CameraMotion& motion, const Eigen::Vector3d& X);
RsProjection project_trajectory(const CameraModel& cam, const RowTiming& timing,
                                const CameraMotion& motion, const Eigen::Vector3d& X,
                                const CaptureWindow& win);

// Global-shutter (perspective) projection of X at time t: the limit of every case as r -> inf.
RsProjection project_perspective(const CameraModel& cam, const CameraMotion& motion,
                                 const Eigen::Vector3d& X, double t = 0.0);

}  // namespace rsd::dsp
