// What the named effects leave (docs/formats/recording-v1.md, "remainder"): is the final
// residual noise, or does structure remain that the effect table does not hold (parallax in
// matches, a gyro that saturates, a clock that jumps)? And where does it live?
//
// Noise here is whatever has no structure: pixel noise independent from observation to
// observation, and errors a frame's observations share (gyro stamp jitter) that are
// independent from frame to frame. Structure is what neither is:
//  - spatial: residuals that vary smoothly across a frame. Neighbouring observations of one
//    frame then agree more than their scatter about the frame's mean says; the differences
//    of nearest neighbours estimate the independent noise whatever smooth field lies beneath.
//  - temporal: frame means that follow each other from frame to frame. The von Neumann ratio
//    of the sequence of frame means (half the mean squared step over the variance) is 1 for
//    independent frame errors and falls towards 0 for a smooth one.
//  - whole frames: frames most of whose observations the model does not predict at all (they
//    fall outside the robust inlier rule). Mismatched features are scattered over the frames;
//    frames lost whole (a gyro that clips in its fastest swings puts every match of those frames
//    several pixels off) are not, and the other tests, which look at the inliers, never see them.
// Each must be statistically clear (4 sigma) and material (its variance at least a fifth of
// the noise's, and its RMS the instrument's own bias, instrument.hpp; lost frames: a twentieth
// of the observations), so that the motion data's own errors, the tracker's or detector's, and a
// remainder too small to matter are not called physics.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "dsp/diagnosis/locate.hpp"
#include "dsp/diagnosis/model.hpp"

namespace rsd::dsp {

struct Remainder {
  bool significant = false;
  double rms_px = 0;           // per-coordinate RMS of the final residual's inliers
  double expected_rms_px = 0;  // what noise alone leaves (the data's own, from the tests below)
  double stated_noise_px = 0;  // the recording's noise floor per coordinate (0: not stated)
  // Share of the baseline's mismatch beyond noise (energy) that the named effects removed;
  // 1 when the nominal model already fitted within noise (nothing_to_explain).
  double explained_share = 0;
  bool nothing_to_explain = false;
  // Spatial test: the variance of differences with an observation anywhere in the frame over
  // that of differences with the nearest one outside its window (a smooth field cancels only in
  // the second), and its z.
  double spatial_ratio = 1, spatial_z = 0;
  // Temporal test: von Neumann ratio of the frame means, and its z.
  double temporal_ratio = 1, temporal_z = 0;
  double spatial_rms_px = 0, temporal_rms_px = 0;  // RMS of the structured parts (0: none)
  // The larger structured part that is clear and a share of the noise but under the instrument's
  // own bias (instrument.hpp), so not called physics (0: none).
  double instrument_px = 0;
  // Whole-frames test: frames (of those with 8 observations or more) most of whose observations
  // are outliers, how many the frames' median outlier share makes expected (binomial), its z,
  // and the share of the tested observations those frames hold.
  int lost_frames = 0, tested_frames = 0;
  double lost_expected = 0, lost_z = 0, lost_share = 0;
  bool spatial = false, temporal = false, lost = false;  // which test found structure
  // A video stabilised in the camera (stabiliser.hpp): the selection found a gain standing in for
  // the pictures following the gyro smoothed over stabiliser_sigma_s. Significant whatever the
  // tests above say: the rotation model, which has the pictures follow the gyro, does not hold.
  bool stabilised = false;
  double stabiliser_sigma_s = 0;
  // A clock offset was named beside the stabiliser: a stabiliser that does not look ahead lags
  // the motion (a first-order one by 1 / (2 pi f_corner) under its corner), which the offset takes
  // up, so the summary says it may be the stabiliser's delay rather than the clocks'.
  bool offset_beside_stabiliser = false;
  std::vector<Located> located;  // where the remainder lives (empty when not significant)
  std::string summary;           // plain words for the report
};

// The remainder of `fitted` over the observations `idx` (at most 20000 used), given the
// recording's stated per-coordinate noise floor (0: unknown) and the nominal model's RMS; with
// `stabiliser_sigma_s`, the smoothing the selection found the pictures follow (Remainder::stabilised);
// `offset_named`: the named effects include the clock offset.
Remainder assess_remainder(const DiagnosisModel& m, const ModelParams& fitted, const std::vector<int>& idx,
                           double noise_floor_px, double baseline_rms_px,
                           std::optional<double> stabiliser_sigma_s = std::nullopt, bool offset_named = false);

}  // namespace rsd::dsp
