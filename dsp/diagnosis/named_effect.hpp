// A named effect the diagnosis found (docs/formats/recording-v1.md, "Named effects"), with
// its fitted parameters.
#pragma once

#include <string>
#include <vector>

namespace rsd::dsp {

struct EffectParam {
  std::string name;
  double value = 0;
  std::string text;  // non-empty for a non-numeric value (readout direction)
};
struct NamedEffect {
  std::string name;  // the spec's effect name
  std::vector<EffectParam> params;
  std::string explains;
  double rms_px = 0;    // fitting-set RMS once this effect (and those before it) is in
  double bic_drop = 0;  // how much BIC fell when it was added
  double heldout_drop = 0;  // how much the held-out robust chi-square fell when it was added
  // The robust chi-square drop on the unseen half of the blocked halves, in time and in angular
  // rate (the worse direction; NaN where not applicable).
  double blocked_time_drop = 0, blocked_rate_drop = 0;
  // Effects the data cannot tell from this one (head to head within the BIC threshold).
  std::vector<std::string> rivals;
};

}  // namespace rsd::dsp
