// The paper's Figure 1 (Meingast, Geyer, Sastry 2005): limit lines z_min(v_y) of the pinhole
// model for a rolling-shutter camera, drawn with PLplot to a PNG or SVG file.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>

#include "dsp/analysis/applicability.hpp"

namespace rsd::tools {

struct LimitLinesInput {
  dsp::CameraModel cam;
  // The user's timing. Lines are drawn for the paper's 3.75, 7.5 and 15 fps with this
  // readout direction and the readout filling the frame, plus one for this timing
  // unless it equals one of those.
  dsp::RowTiming user_timing;
  dsp::ApplicabilityOptions opt;  // threshold N and reference; the grid is not used
  std::optional<Eigen::Vector2d> user_point;  // (|v_y| m/s, z m), marked if given
};

// For v = (0, v_y, 0), per timing: the paper's line z = |v_y| fy^2 / (N |r|) (solid) and
// the exact bound of dsp::min_depth_for (dashed). Depth above speed, legend at the right.
// `file` must end in ".svg" for SVG; anything else is written as PNG.
void plot_limit_lines(const LimitLinesInput& in, const std::string& file);

}  // namespace rsd::tools
