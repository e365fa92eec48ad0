// What a diagnosis learned, as a calibration file (docs/formats/calibration-v1.md): the
// recording's nominal model composed with every named effect's full fitted value, each key's
// 1-sigma from the fit where the fit gives one for every element of the key.
#pragma once

#include <string>

#include "dsp/diagnosis/diagnosis.hpp"
#include "formats/calibration_v1.hpp"

namespace rsd::tools {

formats::Calibration calibration_from(const dsp::Recording& rec, const dsp::Diagnosis& d, const std::string& source);

}  // namespace rsd::tools
