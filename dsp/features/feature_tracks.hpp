// Feature matches between consecutive frames for recording-v1's matches kind and the online
// estimator: Shi-Tomasi corners spread over the image by grid bucketing (each a corner at the
// tracking window's scale too, not only at the detector's), tracked with pyramidal
// Lucas-Kanade into the second frame turned back onto the first (a homography from a coarse
// tracking, so that LK's windows do not turn; no match is judged by it), and kept only when
// tracking back from the second frame lands where it started
// (forward-backward check) and the patches around both ends correlate (LK can settle
// consistently both ways on an unrelated texture, e.g. where something moved in front). No
// geometric outlier rejection: the diagnosis is robust, and a model-based filter would throw
// away exactly the rolling-shutter residual it is meant to find.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <optional>
#include <vector>

namespace rsd::dsp {

struct TrackOptions {
  int max_per_pair = 300;        // matches kept per frame pair (after bucketing)
  int grid_cols = 8, grid_rows = 6;  // buckets; each keeps its strongest max_per_pair / cells
  double quality = 0.01;         // corner strength relative to the image's strongest corner
  double min_distance_px = 8;    // between detected corners
  int window_px = 21;            // LK window (odd)
  // A corner is tracked only when its window holds structure in two directions: the structure
  // tensor's smaller eigenvalue over its larger, summed over the LK window, at least this. The
  // detector's 3x3 corner measure fires on the steps of a rendered or aliased slanted edge, where
  // LK's window sees one edge and slides along it: 40% of the matches of rsd-sim's checkerboard
  // scene lay 0.5-15 px along an edge, through the round trip and the correlation (1.2% with the
  // test). 0.2 took too many of a real drone clip's matches (docs/extract.md).
  double min_corner_ratio = 0.1;
  // LK follows a translation: where the picture turns between the frames, a window whose
  // structure sits off its centre (an edge ending in a corner at its rim) follows the structure
  // and errs by the turn times that offset, which made rsd-sim's rendered pictures turn 0.13% less
  // than the gyro about the optical axis (docs/extract.md). So when a first, coarse tracking of
  // a few corners shows the picture's corners moving by at least this (pixels) beyond its
  // centre's shift, and most corners agree on one homography, the second picture is turned back
  // onto the first by it before the tracking proper, and the matches mapped back; 0 always,
  // infinity never.
  double align_above_px = 1.0;
  int pyramid_levels = 3;
  int max_iterations = 40;       // LK's per level (it stops sooner once a step is below 0.001 px)
  double max_fb_error_px = 0.25; // forward-backward round trip; more is a tracking failure
  double min_ncc = 0.9;          // patches (window_px square) around both ends must correlate
                                 // (true matches in simulated rolling-shutter video: > 0.95)
  int border_px = 4;             // matches this close to the edge are dropped (window clipped)
  // FeatureTracker only: carry a pair's surviving features into the next pair instead of
  // detecting afresh every frame; corners are detected again only when fewer than
  // refill_below * max_per_pair survive, and then only in the grid cells that ran short.
  bool carry = false;
  double refill_below = 0.8;
  int detect_level = 0;          // corners found in this pyramid level (1: half size, a quarter the cost)
};

struct PairTracks {
  std::vector<Eigen::Vector2d> a, b;  // matched pixels in the first and second frame
  int detected = 0;     // corners detected in the first frame (after bucketing)
  int lost = 0;         // LK lost them, or they left the image
  int fb_rejected = 0;  // failed the forward-backward check
  int ncc_rejected = 0; // the two ends do not look alike (LK settled on something else)
};

// Tracks features through a chain of frames, each frame's image pyramid (and its derivatives)
// built once and used both as the second frame of one pair and the first of the next.
// Thread contract: none of its own; one thread feeds it.
class FeatureTracker {
 public:
  // Throws std::invalid_argument on options no tracker can use.
  explicit FeatureTracker(const TrackOptions& opt = {});
  // Matches between the frame before (if the chain holds one) and `frame`, which is kept for the
  // next call. `frame`: 8-bit single-channel, the size of the chain's frames; the tracker copies
  // what it keeps. Pixel (0, 0) is the centre of the top-left pixel, as in OpenCV and
  // recording-v1. Throws std::invalid_argument on a bad frame.
  PairTracks next(const cv::Mat& frame);
  // The chain breaks (a gap, a dropped frame): the next frame starts a new one.
  void restart();
  bool holds_frame() const { return !prev_.empty(); }

 private:
  std::vector<cv::Point2f> corners(const std::vector<cv::Mat>& pyr, const std::vector<cv::Point2f>& have) const;
  TrackOptions o_;
  std::optional<cv::Mat> turn_between(const std::vector<cv::Point2f>& pa) const;
  std::vector<cv::Mat> prev_, cur_;      // pyramids with derivatives (cv::buildOpticalFlowPyramid)
  std::vector<cv::Mat> aligned_;         // the second frame's, turned back onto the first's (align_above_px)
  cv::Mat aligned_image_;
  std::vector<cv::Point2f> carried_;     // features of the frame held, to track into the next
  bool carried_detected_ = false;        // carried_ came from detection, not from tracking
};

// Matches between two frames a and b of equal size (a chain of two).
PairTracks track_pair(const cv::Mat& a, const cv::Mat& b, const TrackOptions& opt = {});

}  // namespace rsd::dsp
