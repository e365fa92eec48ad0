// The named effects the diagnosis can explain a recording with (docs/formats/recording-v1.md,
// "Named effects"), and the model parameters each one frees.
#pragma once

#include <vector>

#include "dsp/diagnosis/model.hpp"

namespace rsd::dsp {

enum class Effect : int {
  RollingShutter, TimeOffset, ReadoutDirection, ClockDrift, LensDistortion, FocalLength, GyroBias, LeverArm,
  MountRotation, GyroScale, PrincipalPoint, LensModel, Count
};
const char* effect_name(Effect e);
// The continuous parameters an effect frees for a nominal lens of family `nominal_lens`
// (readout_direction: none, it is the flip; lens_distortion: the nominal family's radial terms,
// radtan k1 k2 or equi k1..k4; lens_model: the other family's, besides its switch).
ParamMask effect_params(Effect e, LensModel nominal_lens);
// The effects that apply to the recording: gyro_bias needs a gyro, lever_arm a trajectory.
std::vector<Effect> applicable_effects(const DiagnosisModel& m);
// The parameters a set of effects frees together.
ParamMask mask_of(const std::vector<Effect>& effects, LensModel nominal_lens);

}  // namespace rsd::dsp
