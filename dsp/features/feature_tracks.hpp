// Feature matches between two consecutive frames for recording-v1's matches kind: Shi-Tomasi
// corners spread over the image by grid bucketing, tracked with pyramidal Lucas-Kanade and kept
// only when tracking back from the second frame lands where it started (forward-backward
// check) and the patches around both ends correlate (LK can settle consistently both ways on
// an unrelated texture, e.g. where something moved in front). No geometric outlier rejection: the diagnosis is robust, and a model-based filter
// would throw away exactly the rolling-shutter residual it is meant to find.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <vector>

namespace rsd::dsp {

struct TrackOptions {
  int max_per_pair = 300;        // matches kept per frame pair (after bucketing)
  int grid_cols = 8, grid_rows = 6;  // buckets; each keeps its strongest max_per_pair / cells
  double quality = 0.01;         // corner strength relative to the image's strongest corner
  double min_distance_px = 8;    // between detected corners
  int window_px = 21;            // LK window (odd)
  int pyramid_levels = 3;
  double max_fb_error_px = 0.25; // forward-backward round trip; more is a tracking failure
  double min_ncc = 0.9;          // patches (window_px square) around both ends must correlate
                                 // (true matches in simulated rolling-shutter video: > 0.95)
  int border_px = 4;             // matches this close to the edge are dropped (window clipped)
};

struct PairTracks {
  std::vector<Eigen::Vector2d> a, b;  // matched pixels in the first and second frame
  int detected = 0;     // corners detected in the first frame (after bucketing)
  int lost = 0;         // LK lost them, or they left the image
  int fb_rejected = 0;  // failed the forward-backward check
  int ncc_rejected = 0; // the two ends do not look alike (LK settled on something else)
};

// a and b: 8-bit single-channel frames of equal size. Pixel (0, 0) is the centre of the
// top-left pixel, as in OpenCV and recording-v1. Throws std::invalid_argument on bad input.
PairTracks track_pair(const cv::Mat& a, const cv::Mat& b, const TrackOptions& opt = {});

}  // namespace rsd::dsp
