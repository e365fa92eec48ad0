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

// The inlier rule every layer uses: finite and within kOutlierSigmas robust scales.
std::vector<bool> inliers(const std::vector<Eigen::Vector2d>& residuals);

}  // namespace rsd::dsp
