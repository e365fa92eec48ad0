// The searches of the time offset that put it, and the focal length, near their values before
// the local fits (fit.hpp), so that those start in the right valley: the gross grid, the
// offset settled at the noise's scale, and the fine refinement a time_offset hypothesis starts
// from.
#pragma once

#include <functional>
#include <vector>

#include "dsp/diagnosis/fit.hpp"

namespace rsd::dsp {

// Global search of the time offset (others held at `p`): a coarse scan over the offsets that
// keep the frames inside the motion data (at most +-1 s around p's), then a fine one.
double scan_time_offset(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p,
                        double sigma_px);
// Fine scan only: 0.25 ms steps over +-`half_width_s` around p's offset.
double refine_time_offset(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p,
                          double sigma_px, double half_width_s = 5e-3);

// Between the gross grid and the local fits, at the noise's scale: the offset within two frame
// periods of p's at 2.5 ms steps under a cost truncated at 5 sigma, then refined; p's own when
// no step of that grid costs less or the best lies within half a frame period of it (where a
// rolling shutter left out puts it). The gross grid's steps and its cost truncated at 2% of the
// image see an offset only where the motion turns fast for long; a forward flight's clock shows
// only in its closing pan's first frames, tens of milliseconds that the grid cannot tell from
// the flight's flow, and the local fits, started there, do not cross the translation's jagged
// cost to reach it.
double settle_time_offset(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, double sigma);
// The minimum of the clock offset's profile about a fit under the translation nuisance: the
// vertex of the quadratic through the robust chi-square (robust_chi2) at p's offset + k step,
// k = -4..4 (the other parameters held at p's, the translation taken out afresh at each), clamped
// to those points; p's own where the quadratic has no minimum or a point has no finite cost.
// At a fit's minimum it is the fit's offset, up to the cost's jag (a robust chi-square of 1 or 2
// where a match crosses an inlier's or an own depth's bound, which a quadratic over points a
// sigma apart, rising by 16 at the ends, does not follow). The fits' Jacobian holds the
// translation as it settled (translation.hpp) while this cost takes it out afresh, and the two
// can disagree: on the independent generator's drone with a steadier gimbal the fit stopped at
// -64.8 ms where the held cost had a second shallow minimum, and this profile's lay towards
// -58 ms, the truth (at the clamp, four sigmas away); at 60 fps the fit, at -58.7 ms, was the
// nearer, and this profile's minimum 3.2 ms further.
double profile_time_offset(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, double sigma_px,
                           double step_s);

// Gross errors first: a joint grid of the time offset (as scan_time_offset) and a common focal
// scale (0.8 .. 1.2 of p's fx, fy in 5% steps) under a truncated cost that a wrong offset or a
// focal length 20% off both saturate. Returns p with the best offset and focal lengths: start
// values for the time_offset and focal_length hypotheses, not a claim that either is present.
// With p's translation nuisance on, on 600 observations rather than 150: the translation's
// velocity spline (translation.hpp) needs a few observations per knot.
// `step(done, total)`, if given, after each focal scale of the grid.
ModelParams gross_start(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, double sigma_px,
                        const std::function<void(int, int)>& step = nullptr);

}  // namespace rsd::dsp
