// A calibration target named on the command line, as rsd-extract's --target takes it.
#pragma once

#include <string>

#include "dsp/sim/calibration_target.hpp"

namespace rsd::formats {

// "checkerboard:COLSxROWS:SQUARE_M" (inner corners, square size in metres) or
// "aprilgrid:COLSxROWS:TAG_M[:SPACING]" (tags, tag size in metres, gap / tag size, default
// 0.3 as Kalibr's tagSpacing). Throws std::invalid_argument saying what was expected.
dsp::TargetSpec parse_target(const std::string& text);


}  // namespace rsd::formats
