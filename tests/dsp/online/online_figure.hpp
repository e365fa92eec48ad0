// docs/online-calibration.md's figures: the online estimate over time (time offset, line delay,
// gyro bias), each with its 1-sigma band and the simulator's truth.
#pragma once

#include <string>
#include <vector>

#include "dsp/online/online_estimator.hpp"

namespace rsd::test {

struct OnlineTrace {
  std::vector<double> t;  // s since the first frame
  std::vector<dsp::OnlineEstimate> est;
};

// The truth may change at `step_at_s` (< 0: never) from `truth` to `truth_after`.
struct OnlineTruth {
  dsp::OnlineCalibration before, after;
  double step_at_s = -1;
  double nominal_line_delay_s = 0;  // the line delay is drawn relative to it
};

// Writes a PNG with three panels; nothing when the trace is empty.
void plot_online_trace(const std::string& file, const std::string& title, const OnlineTrace& trace, const OnlineTruth& truth);

}  // namespace rsd::test
