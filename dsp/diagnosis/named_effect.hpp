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
};

}  // namespace rsd::dsp
