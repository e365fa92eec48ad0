// The robust summary every layer of the diagnosis judges residuals by.
#pragma once

#include <Eigen/Core>

#include <vector>

namespace rsd::dsp {

// Robust summary of 2-D pixel residuals. The scale is the per-coordinate sigma estimated
// from the median residual length (a 2-D Gaussian's length is Rayleigh distributed);
// residuals longer than `kOutlierSigmas` scales, and failed predictions (NaN), are outliers.
struct RobustStats {
  double rms_px = 0;      // per-coordinate RMS of the inliers
  double scale_px = 0;    // robust per-coordinate sigma
  int observations = 0;   // all, inliers and outliers
  int outliers = 0;
};
constexpr double kOutlierSigmas = 5.0;
RobustStats robust_stats(const std::vector<Eigen::Vector2d>& residuals);

// Observations closer than this (pixels) may share pixels of the tracker's window (ours is 21 px
// square, OpenCV's default 21, KLT's usual 15-31), and their errors with them: in rsd-sim's 1080p
// rendering most features had a twin 8-10 px away whose error correlated 0.35 with its own, past
// this 0.01 (docs/diagnosis.md, "The noise the remainder is measured against"). The remainder
// measures its noise past them; the design effect counts what they share.
constexpr double kSharedWindowPx = 32;

// The inlier rule every layer uses: finite and within kOutlierSigmas robust scales.
std::vector<bool> inliers(const std::vector<Eigen::Vector2d>& residuals);

// The change from residuals `before` to `after` (the same observations, in the same order),
// paired by group: observations that move together (a frame pair's, with the camera's
// translation left in) are one sample, not many. Per group, the sum of |after|^2 - |before|^2
// over the observations both put within kOutlierSigmas robust scales of `before`; `t` is the
// mean over the groups over its standard error (+-infinity when every group changes alike, 0
// with fewer than 3 groups). Positive: `after` is worse.
struct PairedChange {
  int groups = 0;
  double mean = 0;  // px^2 per group
  double t = 0;
};
PairedChange paired_change(const std::vector<Eigen::Vector2d>& before, const std::vector<Eigen::Vector2d>& after,
                           const std::vector<int>& group);

}  // namespace rsd::dsp
