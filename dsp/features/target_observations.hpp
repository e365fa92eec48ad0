// Landmark observations of a calibration target in one frame, for recording-v1's landmarks
// kind: a checkerboard (OpenCV's sector-based detector, sub-pixel) or an AprilGrid of tag36h11
// tags (OpenCV's aruco detector with sub-pixel corner refinement).
//
// Target frame (points.csv), the same as rsd-sim's targets (dsp/sim/calibration_target.hpp): origin at
// the centre of the target, x along a row of corners (to the right as printed), y down the
// columns, z = 0 on the target's surface and positive behind it (right-handed). Ids:
//   checkerboard: inner corner (row i, column j) has id i * cols + j, row 0 at the top;
//   AprilGrid (dsp/sim/aprilgrid.hpp's layout): tag ids row-major from the top-left, corner
//   id = 4 * tag + k, k = 0 top-left, 1 top-right, 2 bottom-right, 3 bottom-left.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <string>
#include <vector>

#include "dsp/observation/recording.hpp"
#include "dsp/sim/calibration_target.hpp"

namespace rsd::dsp {

// The target's corners in the target frame. AprilGrid geometry is exact (not quantised to a
// bitmap), so it matches a simulated grid whenever the gap is a whole number of bitmap pixels
// (tag_spacing a multiple of 1/96, e.g. 0.25).
std::vector<dsp::Landmark> target_points(const TargetSpec& spec);

struct CornerObservation {
  int id;
  Eigen::Vector2d px;
};

// Detects the target in an 8-bit grey frame; empty when it is not found. A checkerboard must
// be wholly visible, and because its pattern repeats, its orientation is taken from the image:
// corner 0 is the one nearer the image's top-left (the camera must not be rolled more than
// 90 degrees from the target's rows), so boards with cols == rows are refused.
std::vector<CornerObservation> detect_target(const cv::Mat& grey, const TargetSpec& spec);

}  // namespace rsd::dsp
