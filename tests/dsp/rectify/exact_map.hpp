// Shared by the rectifier's tests: the motions they rectify, and the exact source position of
// an output pixel computed independently of the rectifier's map: the output pixel's ray meets
// the depth model in a Euclidean point, which the paper's bracketed root finder
// (project_trajectory, eq. (3)) projects with the exact screw motion.
#pragma once

#include <cmath>
#include <vector>

#include "dsp/geometry/rs_projection.hpp"
#include "dsp/rectify/rs_rectifier.hpp"

namespace rsd::dsp::test {

using Eigen::Vector2d;
using Eigen::Vector3d;

struct Case {
  const char* name;
  CameraModel cam;
  RowTiming timing;
  Twist tw;
  DepthModel depth;
  double t_ref;
};

inline CameraModel camera(int w, int h, double hfov_deg) { return CameraModel::from_hfov(w, h, hfov_deg * M_PI / 180); }

inline Twist twist(Vector3d v, Vector3d w) {
  Twist t;
  t.v = v, t.w = w;
  return t;
}

// The motions of the map test: fast rotations, translation before a plane, the ground plane
// with its horizon in view, and a distorted lens read bottom to top.
inline std::vector<Case> cases() {
  const CameraModel cam = camera(480, 360, 60);
  const RowTiming tb = RowTiming::full_frame(360, 30);
  const double mid = reference_time(tb, ReferenceRow::Middle);
  CameraModel distorted = cam;
  distorted.dist = {-0.2, 0.05, 0.0005, -0.0003, 0};
  const RowTiming bt = RowTiming::full_frame(360, 30, Readout::BottomToTop);
  CameraModel fisheye = cam;  // 143 degrees across, kept in the output
  fisheye.fx = fisheye.fy = 0.4 * cam.width;
  fisheye.dist = Distortion::equidistant(0.0469, -0.0135, 0.0021, -0.0003);
  return {
      {"fast_pan", cam, tb, twist({0, 0, 0}, {0.3, 6.0, 0.2}), DepthModel::at_infinity(), mid},
      {"fast_roll", cam, tb, twist({0, 0, 0}, {0.2, -0.4, 2 * M_PI}), DepthModel::at_infinity(), 0.0},
      {"plane_translation", cam, tb, twist({2.0, 0.5, 1.0}, {0.2, -0.3, 0.1}), DepthModel::fronto_parallel(2.0), mid},
      {"ground_plane", cam, tb, twist({0.3, 0, 15.0}, {0.05, 0.5, 0.1}), ground_plane(1.2), mid},
      {"distorted_bottom_to_top", distorted, bt, twist({0.3, 0.1, 0}, {1.0, 2.0, 0.5}),
       DepthModel::fronto_parallel(3.0), 0.0},
      // Maps whose coarse grid holds the tolerance in most cells: those that miss are split
      // (the fisheye's edges; the rows read last in a brisk pan).
      {"fisheye_split_cells", fisheye, tb, twist({0.3, 0, 0}, {0.3, 4.0, 0.4}), DepthModel::at_infinity(), mid},
      {"pan_split_cells", cam, tb, twist({0.3, 0, 0}, {0.3, 2.0, 0.4}), DepthModel::at_infinity(), mid},
  };
}

// Exact source position of output pixel p, the independent way (see the file comment).
inline RsProjection exact_source(const Case& c, const CameraMotion& motion, const Vector2d& p) {
  const Eigen::Affine3d g = motion.at(c.t_ref);
  const Eigen::Matrix3d Rt = g.linear().transpose();
  const Vector3d o = -(Rt * g.translation()), d = (Rt * c.cam.ray(p).value()).normalized();
  Vector3d X = o + 1e9 * d;  // infinitely far: translation moves it by < 1e-8 px
  if (!c.depth.infinite) {
    const double lambda = (c.depth.distance - c.depth.normal.dot(o)) / c.depth.normal.dot(d);
    if (lambda > 0) X = o + lambda * d;
  }
  return project_trajectory(c.cam, c.timing, motion, X);
}

}  // namespace rsd::dsp::test
