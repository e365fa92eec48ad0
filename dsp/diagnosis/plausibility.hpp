// What a real rig can plausibly have, as a penalty on a hypothesis (in chi-square units, added
// to its BIC): an effect whose fitted value lies beyond what the physics allows is more likely
// standing in for something else. Each bound is soft: every `width` beyond it costs one
// sigma squared. (Pixels are square by construction: the focal length is one scale, set_param.)
//   - gyro_bias: a MEMS gyro's bias stays within 0.1 rad/s (about 6 deg/s; width 0.02 rad/s).
//     A bias of 66-86 mrad/s stood in for parallax.
//   - gyro_scale: a scale factor within 5% of one per axis (width 1%).
//   - lever_arm: within 0.5 m of the tracked origin (width 0.1 m).
//   - clock_drift: within 1000 ppm (width 250 ppm). A crystal keeps 100 ppm; a drift of 3755 ppm
//     stood in for a drone clip's offset that only its closing pan shows (12 s: 45 ms at the end).
#pragma once

#include <string>
#include <vector>

#include "dsp/diagnosis/model.hpp"

namespace rsd::dsp {

enum class Effect : int;

// The penalty of the effects' values in `p` (0 when all are plausible).
double implausibility(const ModelParams& p, const std::vector<Effect>& effects);
// Why, in words, for an effect whose value is implausible ("" when it is plausible).
std::string implausible_because(const ModelParams& p, Effect e);

class DiagnosisModel;
// Why an effect fitted to `p` has a value beyond what real hardware has ("" when it has not):
// more than two widths past a bound above, or a focal length over 25% from the nominal.
std::string beyond_hardware_because(const ModelParams& p, Effect e, const DiagnosisModel& m);
// Why an effect fitted to `p` must not be named ("" when it may): a value beyond what real
// hardware has (beyond_hardware_because), or a parameter on the fit's bound (param_bounds: the
// data pushed it there, they do not measure it; a line delay of zero is a global shutter, a
// measurement).
std::string unnameable_because(const ModelParams& p, Effect e, const DiagnosisModel& m);

}  // namespace rsd::dsp
