// A Kalibr-style AprilGrid target: rows x cols AprilTag 36h11 tags (OpenCV's dictionary),
// `spacing` x tag size apart, with black squares where the gaps cross. Rendered to a bitmap
// for the simulator; its corner positions are the landmarks.
//
// Plane coordinates (s right, t down, metres) start at the grid's outer corner. Tag ids run
// row-major from the top-left; corner id = 4 tag id + k with k = 0 top-left, 1 top-right,
// 2 bottom-right, 3 bottom-left (OpenCV's marker corner order).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "dsp/core/image.hpp"

namespace rsd::dsp {

struct AprilGridSpec {
  int rows = 6, cols = 6;
  double tag_size_m = 0.088;  // black border to black border
  double spacing = 0.3;       // gap between tags as a fraction of the tag size
};

struct AprilGridTarget {
  dsp::Image bitmap;          // white quiet zone of one gap around the grid
  double pixels_per_m = 0;
  Eigen::Vector2d grid_origin_in_bitmap_m;  // where plane coordinate (0, 0) sits in the bitmap
  double width_m = 0, height_m = 0;        // the grid itself
  std::vector<int> corner_ids;
  std::vector<Eigen::Vector2d> corners;    // plane coordinates of each corner id
};

// `pixels_per_bit`: bitmap resolution, one tag bit (1/8 of the tag) in pixels.
AprilGridTarget make_aprilgrid(const AprilGridSpec& spec, int pixels_per_bit = 12);

}  // namespace rsd::dsp
