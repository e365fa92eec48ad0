// Fitting the effect parameters of a DiagnosisModel: a robust Levenberg-Marquardt fit (Ceres)
// within the parameters' physical bounds. The searches that put the time offset and the focal
// length near their values first are offset_search.hpp's.
#pragma once

#include <utility>

#include <functional>
#include <vector>

#include "dsp/diagnosis/model.hpp"

namespace rsd::dsp {

// A failed prediction costs as much as a residual this many sigmas long, per coordinate:
// far into the robust loss's linear part, so it neither dominates nor vanishes.
constexpr double kFailSigmas = 20.0;
// Huber threshold in sigmas: quadratic (Gaussian) within, linear (outlier-tolerant) beyond;
// past kTailSigmas the loss grows logarithmically (a redescending influence).
constexpr double kHuberSigmas = 2.0;
constexpr double kTailSigmas = 20.0;

// -2 log-likelihood (up to a constant) of 2-D residuals under the robust loss on their length,
// in sigma units: the quantity the fit minimises, so that BIC compares fits on their own terms.
double robust_chi2(const std::vector<Eigen::Vector2d>& residuals, double sigma_px);
// One residual's share of robust_chi2.
double robust_loss(const Eigen::Vector2d& residual, double sigma_px);

// How much the residuals of one frame move together, as the factor by which it shrinks the
// information in a chi-square: D = 1 + (n - 1) rho, n the mean inliers per frame, rho the share
// of the residual variance that is common to a frame (frame-mean residual variance beyond
// what independent noise gives). Errors of the motion data (gyro timestamp jitter, a
// trajectory's interpolation) are common to all of a frame's observations; BIC, which
// assumes independent residuals, would otherwise name tiny spurious effects on long
// recordings. Observations closer than kSharedWindowPx (a tracker's twin features, sharing
// its window) add k rho_near, k the mean count of such neighbours an observation has and
// rho_near their residuals' correlation beyond the frame's common part, measured on their
// pairs. 1 for independent residuals.
double design_effect(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx, double sigma_px);

// Fits the parameters in `free` (starting at `start`, clamped into their physical bounds) with
// Ceres: Levenberg-Marquardt within those bounds on the robust cost (robust_chi2's loss, one
// residual block per observation), with a forward-difference Jacobian in param_scale units.
// Returns the fitted parameters.
// The fit's limits of a parameter (the physical ones: a line delay within the frame period, an
// offset inside the motion data, focal lengths within a factor two, |k| <= 1, ...).
std::pair<double, double> param_bounds(Param p, const DiagnosisModel& m);

// How a fit ended, when asked (fit_params's `end`): whether it converged, so that a larger
// max_iterations from the same start gives the same fit (the cap is the only thing it changes),
// and the iterations it took.
struct FitEnd {
  bool converged = false;
  int iterations = 0;
};
ModelParams fit_params(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& start,
                       const ParamMask& free, double sigma_px, int max_iterations = 30, FitEnd* end = nullptr);

// Every `n`-th of idx, at most `count` (spread over the whole recording).
std::vector<int> subsample(const std::vector<int>& idx, size_t count);

}  // namespace rsd::dsp
