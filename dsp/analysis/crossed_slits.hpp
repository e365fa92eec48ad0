// The rolling-shutter camera under fronto-parallel translation is a crossed-slits camera
// (Meingast, Geyer, Sastry 2005, section "Fronto-parallel motion", Figure "figXslit2"):
// with w = 0 and v = (vx, vy, 0), every back-projected ray meets two fixed lines.
//
// Derivation in our conventions (camera frame at frame start t = 0, X_c(t) = X + v t, the
// readout row at t is r t - v0, eq. (1)). With r_n = r / fy and v0_n = (v0 + cy) / fy a
// pixel with normalised coordinates (u_n, v_n) is captured at t_c = (v_n + v0_n) / r_n and
// its ray is { -v t_c + lambda (u_n, v_n, 1) }:
//   slit 1: every ray origin -v t_c lies on the line through 0 along (vx, vy, 0);
//   slit 2: at lambda = vy / r_n the ray is at y = -v0_n vy / r_n, z = vy / r_n whatever
//           the pixel, so every ray meets the line { (s, -v0_n vy / r_n, vy / r_n) }.
// The paper prints slit 2 through (+-1, v0 vy / r, vy / r): the opposite sign on the v0 term.
// That sign belongs to a row law r t + v0 (v0 "the index of the first exposed scanline",
// as the paper's words say), not to its eq. (1), r t - v0, which its own projection
// formula (4) (numerator y + v0 z) and this library follow. The two agree
// only when v0_n = 0; tests/dsp/analysis/test_crossed_slits.cpp shows that otherwise the printed slit
// misses the rays by millimetres.
//
// Also here: 3-D lines, their distances, and the common transversals of four lines in
// Plücker coordinates, used to test whether a set of rays is a crossed-slits congruence.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <vector>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::dsp {

// A line in R^3: a point on it and a unit direction.
struct Line3 {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();

  // The line through p along dir (normalised here; dir must be nonzero).
  static Line3 through(const Eigen::Vector3d& p, const Eigen::Vector3d& dir) {
    return {p, dir.normalized()};
  }
  Eigen::Vector3d point_at(double s) const { return point + s * direction; }
};

// Distance from a point to a line.
double distance(const Line3& l, const Eigen::Vector3d& X);
// Shortest distance between two lines: along the common perpendicular for skew lines,
// the point-to-line distance for (numerically) parallel ones. Zero iff they meet.
double distance(const Line3& a, const Line3& b);

// Plücker coordinates (d, m) with m = p x d: homogeneous, on the Klein quadric d . m = 0.
using Plucker = Eigen::Matrix<double, 6, 1>;
Plucker to_plucker(const Line3& l);
// Back to point + unit direction (the point nearest the origin); nullopt for a line at
// infinity (d = 0 relative to m).
std::optional<Line3> from_plucker(const Plucker& L);
// Reciprocal product d_a . m_b + d_b . m_a: zero iff the lines meet (or are parallel).
double reciprocal_product(const Plucker& a, const Plucker& b);

// The lines meeting all four given lines. Generically there are 0 or 2 real ones (1 when
// the two coincide); `degenerate` is set when there are infinitely many (the four lines
// are linearly dependent in Plücker space, e.g. on one regulus, or a whole pencil of
// transversals exists), and then `lines` is empty. Transversals at infinity cannot be
// represented as Line3 and are counted in `at_infinity` instead.
struct Transversals {
  std::vector<Line3> lines;
  int at_infinity = 0;
  bool degenerate = false;
};
Transversals common_transversals(const std::array<Line3, 4>& lines);

// The two slits, in camera coordinates at frame start: slit1 through the origin along
// (vx, vy, 0), slit2 along x at y = -v0_n vy / r_n, z = vy / r_n (see above).
struct CrossedSlits {
  Line3 slit1;
  Line3 slit2;
};

// The slits of a rolling-shutter camera translating at constant velocity. Capture times
// are row_time() (row start), as in backproject(). nullopt when the camera is not a
// crossed-slits camera or the slits degenerate:
//   tw.w != 0          rotation bends the ray congruence (the paper's Figure, right);
//   tw.v.z() != 0      forward motion: rays no longer meet a fixed second line;
//   lens distortion    t_c follows the distorted row, not the ray's v_n;
//   tw.v.y() == 0      both slits collapse onto the x axis (pushbroom-like, not two slits).
// Comparisons are exact: any nonzero vy gives two distinct (skew) slits.
std::optional<CrossedSlits> crossed_slits(const CameraModel& cam, const RowTiming& timing,
                                          const Twist& tw);

}  // namespace rsd::dsp
