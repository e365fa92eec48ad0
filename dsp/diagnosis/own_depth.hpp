// Each match's own depth in the translation nuisance of matches (translation.hpp). One plane
// describes a wall or a ground; a forward flight past points 20 to 200 m away has inverse depths
// a decade apart, and the plane's misfit (along each match's translation flow, pixels for a near
// point) went into a rotation effect: the independent generator's drone had a gyro bias about
// the pan's axis 29 mrad/s off (13 and 26 on two other seeds). So each match's inverse depth is
// the plane's times (1 + e), e its own under a prior of spread s: eliminating e leaves the match
// the metric P = I - b b^T, b = a / sqrt(|a|^2 + depth_px^2), depth_px = sigma / s (the
// diagnosis's noise, fixed: against each pass's robust scale a parameter that shrank the scale
// loosened the depths and lowered the cost, and the fits found one, a focal length 10% long),
// a its translation flow at the plane's depth in the previous pass's fit. A match whose a is
// large against the noise keeps what lies across a; one that the translation moves by less than
// the noise keeps nearly all. Pure functions of the flows and residuals they are given.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace rsd::dsp {

// The own depth a match may take: its inverse depth the plane's times (1 + e), e within
// [kMinOwnDepth, kMaxOwnDepth]: from a point at infinity to one four times nearer than the plane.
// The Gaussian prior alone lets a mismatch hundreds of pixels long along its flow a take an e of
// tens and leave a tenth of its length: the fit's cost then followed the translation's
// direction through the outliers, not the scene (the independent drone's robust chi-square
// moved by 3000 between two gyro biases over its 5% of mismatches, by 60 over the rest).
inline constexpr double kMinOwnDepth = -1.0;
inline constexpr double kMaxOwnDepth = 3.0;

// Each match's b for its translation flow a (`flow`, px) and what the plane leaves of it (`left`,
// px); empty for none (`depth_px` zero). A match whose own depth, the e that minimises
// |left - a e|^2 / sigma^2 + e^2 / s^2, lies outside [kMinOwnDepth, kMaxOwnDepth] has none
// (b = 0: the plane's depth, its residual whole).
std::vector<Eigen::Vector2d> own_depths(const std::vector<Eigen::Vector2d>& flow, const std::vector<Eigen::Vector2d>& left,
                                        double depth_px);

// x in observation k's own metric, P x: what its own depth leaves of it (x itself without own
// depths).
inline Eigen::Vector2d own_metric(const std::vector<Eigen::Vector2d>& own, size_t k, const Eigen::Vector2d& x) {
  return own.empty() ? x : Eigen::Vector2d(x - own[k] * own[k].dot(x));
}

// The scene's depth spread about the plane as measured from the inliers `in` whose flow a
// exceeds `noise` (px): the residual's energy along a beyond its energy across a, over the energy
// of a (0 when the excess is negative); the excess's z-score against noise alone, under which
// along and across are alike (x^2 - y^2 of two independent N(0, noise^2) has mean 0 and variance
// 4 noise^4); and the inliers' median flow over the noise. `flow` and `left` (what the plane
// leaves) by observation.
struct DepthSpread {
  double spread = 0, z = 0, median_flow = 0;
};
DepthSpread measured_spread(const std::vector<Eigen::Vector2d>& flow, const std::vector<Eigen::Vector2d>& left,
                            const std::vector<bool>& in, double noise);

}  // namespace rsd::dsp
