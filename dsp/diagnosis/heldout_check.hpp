// The diagnosis's first invariant (issue 34 (a)): the final model predicts the frames no fit saw
// no worse than the nominal model, in all and in each half in time beyond its uncertainty.
// Effects that do worse there describe the fitting frames only, or one stretch of the recording
// (stand-ins for physics outside the table): none is named, and the remainder says why. Under
// parallax the comparison takes each held-out pair's translation out (Diagnosis::heldout_nominal),
// and the final model must not predict them worse with the parallax in either, beyond its
// uncertainty.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "dsp/diagnosis/model.hpp"
#include "dsp/diagnosis/robust_stats.hpp"

namespace rsd::dsp {

struct Diagnosis;

// The change from residuals `before` to `after` of the observations `idx` (in that order),
// paired over their frame pairs: the parallax a model leaves in, or a frame pair's gyro noise,
// moves all of a pair's residuals together (paired_change).
PairedChange paired_over_frame_pairs(const DiagnosisModel& m, const std::vector<int>& idx,
                                     const std::vector<Eigen::Vector2d>& before, const std::vector<Eigen::Vector2d>& after);

// Whether `after` predicts the observations `held` worse than `before` with the camera's
// translation left in (both with the translation nuisance off), by over selection::kWorseSigmas
// standard errors paired over the frame pairs (the parallax moves a pair's residuals together):
// "(a -> b px RMS; t standard errors over n frame pairs)", "" when not.
std::string worse_with_parallax(const DiagnosisModel& m, const std::vector<int>& held, ModelParams before,
                                ModelParams after);

// Given `d` with its effects, fitted model, heldout_nominal and held-out RMS filled: withdraws
// every effect (the fitted model the nominal one, `withheld` saying why) where the invariant
// fails, and fills d.heldout_halves. `nominal`: the nominal model without a translation; `held`:
// the held-out observations, `use_all`: every usable one.
void check_heldout(const DiagnosisModel& m, const ModelParams& nominal, const std::vector<int>& use_all,
                   const std::vector<int>& held, Diagnosis& d);

}  // namespace rsd::dsp
