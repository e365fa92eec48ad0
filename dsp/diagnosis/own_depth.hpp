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
// Past the bounds an own depth fades out, over kOwnDepthFade in e beyond kMaxOwnDepth and half
// of it below kMinOwnDepth, instead of switching off: switched, every match whose e crossed a
// bound between two parameter values moved its residual by up to 3 |a| at once, and the
// independent drone's robust chi-square jumped by 20 to 50 between clock offsets 0.5 ms apart,
// more than the offset itself moves it there: the fits stopped where they started.
inline constexpr double kOwnDepthFade = 1.0;
// The own depths' prior spread s in measured spreads (measured_spread): twice as wide as the
// scene's inverse depths spread about the plane. At the measured spread, the shrinkage of each
// match's own depth towards the plane's (by |a|^2 / (|a|^2 + (sigma / s)^2)) left what it did
// not take of a flight's skewed depths (most points far, a tail of near ones) along the flow, and
// the clock offset the independent drone named from a pan came out early on average (docs/
// diagnosis.md, "Each match's own depth"); five times as wide, the own depths take up what the pan
// shows and nothing is named.
inline constexpr double kOwnDepthPriorWidth = 2.0;

// The share of its own depth's flow a e that a match whose own depth is e gives up: 1 within
// [kMinOwnDepth, kMaxOwnDepth], 0 beyond the fades (kOwnDepthFade), linear between.
double own_depth_kept(double e);

// Each match's b for its translation flow a (`flow`, px) and what the plane leaves of it (`left`,
// px); empty for none (`depth_px` zero). b b^T takes out own_depth_kept(e) a e, e the own depth
// that minimises |left - a e|^2 / sigma^2 + e^2 / s^2: all of it within [kMinOwnDepth,
// kMaxOwnDepth], none past the fades (b = 0: the plane's depth, its residual whole).
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
