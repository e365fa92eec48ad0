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
// [kMinOwnDepth, kMaxOwnDepth], as far either way. The Gaussian prior alone lets a mismatch
// hundreds of pixels long along its flow a take an e of tens and leave a tenth of its length: the
// fit's cost then followed the translation's direction through the outliers, not the scene (the
// independent drone's robust chi-square moved by 3000 between two gyro biases over its 5% of
// mismatches, by 60 over the rest). The bounds are symmetric although no point lies beyond
// infinity (e < -1): a match's e is its depth plus the noise's share, and where the flow is about
// the noise that share is about one either way. Cut at -1 (the fifty-eighth to sixty-third
// sessions), the matches the noise carried below it kept the rest of their residual against their
// flow, those it carried above gave theirs up, and what was left pointed towards the focus of
// expansion: the independent generator's drone at 60 fps (the median match moved 1.03-1.08 noises
// between frames) named its clock offset 2.4 to 11.1 ms early on five of six seeds, four of them
// at sigmas of 0.8-1 ms; at -3, 0.2 to 3.5 ms (docs/diagnosis.md, Method step 10, "As far either
// way").
inline constexpr double kMinOwnDepth = -3.0;
inline constexpr double kMaxOwnDepth = 3.0;
// Past the bounds an own depth stays at the bound (own_depth_kept): the match gives up the flow
// of the bound's depth and keeps the rest, the most likely own depth under the prior cut to the
// bounds. Switched off at the bounds, every match whose e crossed one between two parameter
// values moved its residual by up to 3 |a| at once, and the independent drone's robust
// chi-square jumped by 20 to 50 between clock offsets 0.5 ms apart (more than the offset moves
// it there: the fits stopped where they started). Faded out over one unit of e past the bounds
// (the sixtieth session) the residual was continuous, but a match whose e the noise carried into
// the fade lost its own depth: with little flow, e = a.r / (|a|^2 + depth_px^2) is mostly noise
// once the prior is wide. The profile of the drone's cost over the offset was jagged by a robust
// chi-square of 3 to 6 (which hid where its trend lay, below), and with the prior four times as
// wide it had no minimum at all, its cost 7% higher. Held at the bound, the jag is 1 to 2.
//
// The own depths' prior spread s in measured spreads (measured_spread): four times as wide as the
// scene's inverse depths spread about the plane. Narrower, the shrinkage of each match's own depth
// towards the plane's (by |a|^2 / (|a|^2 + (sigma / s)^2)) leaves what it does not take of a
// flight's skewed depths (most points far, a tail of near ones) along the flow, and the clock
// offset the independent drone names from its pan comes out early. The minimum of a quadratic
// through the profile of its cost over the offset (-61.5 to -55.5 ms, the translation refitted
// at each), on seeds 1, 3, 6 and 7 (truth -58 ms): -57.9, -59.6, -60.0 and -61.4 ms with the
// prior twice as wide and the fade; held at the bounds, -58.7, -59.8, -60.4 and -61.2 twice as
// wide, -58.0, -59.4, -59.4 and -59.0 three times, -57.4, -58.7, -58.8 and -57.9 four times. Six
// times as wide the cost has no minimum again: the prior no longer pins the plane, and the own
// depths and the velocity trade their common scale.
inline constexpr double kOwnDepthPriorWidth = 4.0;

// The share of its own depth's flow a e that a match whose own depth is e gives up: 1 within
// [kMinOwnDepth, kMaxOwnDepth], the bound's share beyond (kMaxOwnDepth / e above, kMinOwnDepth /
// e below): what it gives up is a times the bound. None (0) for an e that is not finite.
double own_depth_kept(double e);

// Each match's b for its translation flow a (`flow`, px) and what the plane leaves of it (`left`,
// px); empty for none (`depth_px` zero). b b^T takes out own_depth_kept(e) a e, e the own depth
// that minimises |left - a e|^2 / sigma^2 + e^2 / s^2: all of it within [kMinOwnDepth,
// kMaxOwnDepth], the bound's flow beyond.
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
