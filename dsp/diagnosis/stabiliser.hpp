// A video stabilised in the camera (electronic or optical stabilisation): the pictures follow
// the camera's orientation smoothed over time, the gyro the real one. Below the stabiliser's
// corner a zero-phase smoothing passes the motion at a gain a little under one, which a gyro
// scale (or, in matches, a shorter focal length) imitates at the frequency the motion has most
// of: a hand-held clip moving near 1 Hz under a 5 Hz stabiliser named a gyro scale (0.972,
// 0.939, 0.954) that took the held-out frames from 2.03 to 1.07 px. A scale is one gain at every
// frequency and on each axis its own; a smoothing is one kernel for all axes whose gain falls
// with the frequency. Where the pictures follow the gyro smoothed better than the scale
// explains them, the scale stands in for the stabiliser (Selector, selector.hpp), and the
// remainder says so (remainder.hpp).
//
// The smoothing is a Gaussian kernel in time on the orientation: a family apart from any
// stabiliser's own filter, which the test does not assume (a first-order low-pass run forward
// and back at 5 Hz and a Gaussian of 45 ms agree to second order in the frequency).
#pragma once

#include <limits>
#include <optional>
#include <vector>

#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/model.hpp"
#include "dsp/observation/observation_model.hpp"

namespace rsd::dsp {

// `gyro` (its times increasing, as DiagnosisModel::gyro_samples gives them; else
// std::invalid_argument) as the rates of its
// orientation smoothed by a Gaussian of sigma_s: each sample's orientation moved to the
// kernel-weighted mean of the orientations around it (one Gauss-Newton step of the Karcher mean;
// the kernel integrated over +-4 sigma on a grid of its own, not over the samples, which an
// irregular gyro would make uneven), and the rates the smoothed orientation turns at. The
// smoothing is of where the camera points, not of the body rates one axis at a time, which
// differ from it by the angle turned times the rate. Throws std::invalid_argument unless sigma_s > 0.
// Only the samples within [from, to] are smoothed (the rest are as they were: a caller that looks
// at part of the record keeps 4 sigma of it and a frame's span clear of the edges, where the
// smoothing steps).
std::vector<GyroSample> smoothed_rates(const std::vector<GyroSample>& gyro, double sigma_s,
                                       double from = -std::numeric_limits<double>::infinity(),
                                       double to = std::numeric_limits<double>::infinity());

// The smoothing over which the pictures follow the gyro best, and what the model `p` leaves
// seen through it.
struct StabiliserFit {
  double sigma_s = 0;  // the kernel's standard deviation
  double chi2 = 0;     // robust chi-square on idx (robust_chi2), `free` refitted through the smoothed gyro
};
// Searches sigma_s from 10 ms to 640 ms on the observations `search` with `p` held (doubling,
// then a golden section within a factor two of the best), then refits the parameters `free`
// of p on idx through the gyro smoothed so (up to `iterations`). Requires a matches recording.
StabiliserFit fit_stabiliser(const DiagnosisModel& m, const std::vector<int>& search, const std::vector<int>& idx,
                             const ModelParams& p, const ParamMask& free, double sigma_px, int iterations);

// Whether, from `p` (its translation nuisance off) on the observations of `all` within the
// recording's first kProbeSeconds, the pictures follow
// the gyro smoothed (the focal length refitted through it, the smoothing searched from p's focal
// length and from the nominal one) better than a gain explains them (a
// gyro scale per axis and the focal length fitted together), by over min_drop (the chi-square
// drop over the design effect). Asked before the parallax test sends a selection under the
// translation nuisance, which takes a stabiliser's misfit up as a translation. False under 40
// observations in the probe's span (ten per parameter of the gain's fit).
bool smoothing_beats_a_gain(const DiagnosisModel& m, const std::vector<int>& all, ModelParams p, double sigma_px,
                            double min_drop);
inline constexpr double kProbeSeconds = 20;

// After a selection that found no gain standing in for a stabiliser (nothing under one was
// proposed, as on a stabilised clip whose misfit no effect takes up): the smoothing's sigma when
// the final model `p` (its translation nuisance off) seen through the gyro smoothed (searched on
// `search`) fits `idx` better by over min_drop (the chi-square drop over the design effect) and
// by at least kStabiliserShare of its robust chi-square there; nullopt otherwise. The share keeps
// a gyro's own filtering and its stamps' jitter, which a 10-20 ms smoothing mends by a few
// tenths of a percent on real clips, from being called a stabiliser.
std::optional<double> stabiliser_after_selection(const DiagnosisModel& m, const std::vector<int>& search,
                                                 const std::vector<int>& idx, ModelParams p, double sigma_px,
                                                 double min_drop);
inline constexpr double kStabiliserShare = 0.1;

}  // namespace rsd::dsp
