// Which named effects (docs/formats/recording-v1.md, "Named effects") explain a
// recording: BIC forward selection with a backward check. Candidates are screened on a
// subsample of the fitting observations; only the winner of a round is refitted on them all.
#pragma once

#include <string>
#include <vector>

#include "dsp/diagnosis/model.hpp"

namespace rsd::dsp {

enum class Effect : int {
  RollingShutter, TimeOffset, ReadoutDirection, ClockDrift, LensDistortion, FocalLength, GyroBias, LeverArm,
  MountRotation, GyroScale, PrincipalPoint, Count
};
const char* effect_name(Effect e);
// The continuous parameters an effect frees (readout_direction: none, it is the flip).
ParamMask effect_params(Effect e);
// The effects that apply to the recording: gyro_bias needs a gyro, lever_arm a trajectory.
std::vector<Effect> applicable_effects(const DiagnosisModel& m);

struct SelectionOptions {
  double min_bic_drop = 10;
  int max_iterations = 30;         // final fits
  int screen_iterations = 8;       // candidate fits on the subsample
};

struct SelectedEffect {
  Effect effect;
  double rms_px;    // fitting-set RMS once it (and those before it) is in
  double bic_drop;  // how much BIC fell when it was added
  double heldout_drop;  // how much the held-out robust chi-square fell (0: nothing held out)
};

struct Selection {
  std::vector<SelectedEffect> effects;  // in order of selection
  ModelParams params;                   // fitted; nominal values for the effects not selected
};

// `start` holds the gross estimates (gross_start) the candidates start from; `nominal` the
// values of the effects not selected. An effect is added only when it lowers BIC on `fit` by
// more than min_bic_drop AND lowers the robust chi-square of the `held` observations, which
// no fit saw (an over-fitted parameter explains noise of the fitting set only).
Selection select_effects(const DiagnosisModel& m, const std::vector<int>& fit, const std::vector<int>& held,
                         const std::vector<int>& screen,
                         const ModelParams& nominal, const ModelParams& start, double sigma_px,
                         const SelectionOptions& opt);

}  // namespace rsd::dsp
