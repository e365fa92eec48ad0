// Optical flow of a rolling-shutter camera: the paper's subsection "Optical flow equations",
// eq. (6), and the exact flow of the constant-twist model that replaces it.
//
// The flow is the rate at which the rolling-shutter image of a static point moves when the
// frame start t0 moves. With frame start t0 the point is captured at the absolute time s
// solving eq. (3), pi_y(X_c(s)) = r (s - t0) - v0. Differentiating in t0,
//     (d pi_y/ds) ds/dt0 = r (ds/dt0 - 1)   =>   ds/dt0 = r / (r - vdot_p),
// so the image q = pi(X_c(s)) moves with
//     qdot = (udot_p, vdot_p) * r / (r - vdot_p),
// where (udot_p, vdot_p) is the perspective (global-shutter) image velocity of the point at
// its capture instant, i.e. at the rolling-shutter pixel itself with the depth it has then.
// This is exact for any constant twist (v, w), any K, any v0 and either readout direction.
// The printed eq. (6) agrees with it only when w_z = 0; see docs/optical-flow.md.
//
// Units: pixels and pixels/s; r in signed rows/s (RowTiming::r()); twist in camera axes
// (m/s, rad/s) with dX_c/dt = [w]x X_c + v, as dsp/geometry/camera_motion.hpp.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::dsp {

// Motion field of a pinhole (global-shutter) camera, in pixels/s: the image velocity of a
// static point seen at `pixel` with camera-frame depth `depth_z` while the camera moves with
// twist `tw`. With (x, y) = ((u - cx)/fx, (v - cy)/fy):
//     xdot = (vx - x vz)/z + wy (1 + x^2) - wz y - wx x y
//     ydot = (vy - y vz)/z + wz x - wx (1 + y^2) + wy x y
// and (udot, vdot) = (fx xdot, fy ydot). Only K is used: `pixel` and the result are pinhole
// (undistorted) pixels; with cam.dist zero these are the camera's own pixels. For the
// fronto-parallel case and K = I this is the paper's (vx/z - wz v, vy/z + wz u).
Eigen::Vector2d perspective_flow(const CameraModel& cam, const Twist& tw, const Eigen::Vector2d& pixel,
                                 double depth_z);

// Exact rolling-shutter optical flow (pixels/s) at the rolling-shutter pixel `rs_pixel` of a
// static point whose camera-frame depth at its capture instant is `depth_z_at_capture`:
//     qdot = qdot_p r / (r - vdot_p),   qdot_p = image velocity at the capture instant,
// the correct form of eq. (6) for any constant twist. Lens distortion is
// honoured: `rs_pixel` is the (distorted) pixel the camera records, qdot_p is the velocity of
// the distorted image (diag(fx, fy) * distort_jacobian * normalised velocity) and the result
// is the velocity of the recorded pixel; with zero distortion qdot_p = perspective_flow().
// nullopt when r - vdot_p vanishes (the image runs with the readout: the capture time is not a
// differentiable function of the frame start, the point is caught at most tangentially), when
// the depth is not positive, or when the pixel cannot be undistorted.
std::optional<Eigen::Vector2d> rs_optical_flow(const CameraModel& cam, const RowTiming& timing,
                                               const Twist& tw, const Eigen::Vector2d& rs_pixel,
                                               double depth_z_at_capture);

// The printed eq. (6), literally, for comparison only:
//     qdot(u, v) = r z / (v vx wz + r z (r - vdot_p)) * (r udot_p + wz v vdot_p,
//                                                        r vdot_p + wz v udot_p),
//     (udot_p, vdot_p) = (vx/z - wz v, vy/z + wz u).
// Paper units (K = I, v0 = 0): `uv_n` = normalised rolling-shutter image point
// ((u - cx)/fx, (v - cy)/fy), `r_n` = r / fy in 1/s, z in m; the result is in normalised
// units per second (multiply by (fx, fy) for pixels/s). It presumes v0_n = (v0 + cy)/fy = 0,
// i.e. the readout starts at the principal point's row, as the paper assumes. Only vx, vy, wz
// of `tw` are read (fronto-parallel motion). No guard: a zero denominator gives inf/NaN.
// Differs from the exact flow by O(wz t_c) when wz != 0; see docs/optical-flow.md.
Eigen::Vector2d rs_optical_flow_paper(const Eigen::Vector2d& uv_n, double z, const Twist& tw,
                                      double r_n);

// What the paper's procedure actually yields: the exact t0-derivative of the paper's own
// linearised fronto-parallel model (Table 1 case a, P(t) ~ [(I + t [w]x) | v t], as
// project_fronto_parallel), same units and assumptions as rs_optical_flow_paper. It is the
// printed formula with the sign of wz v udot_p in the second component reversed:
//     r z / (v vx wz + r z (r - vdot_p)) * (r udot_p + wz v vdot_p, r vdot_p - wz v udot_p).
// Still an approximation of the exact flow (error O(wz t_c), from the linearised rotation).
Eigen::Vector2d rs_optical_flow_linearised(const Eigen::Vector2d& uv_n, double z, const Twist& tw,
                                           double r_n);

}  // namespace rsd::dsp
