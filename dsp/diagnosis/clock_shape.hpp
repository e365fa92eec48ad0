// The clock's offset window by window: whether a clock drift is a rate. clock_drift (recording
// v1: the offset grows by drift_ppm 1e-6 s per second) draws the offset along a line over the
// recording; a clock that jumps (outside the table) holds one offset, then another, and a line
// stands in for most of it (a 3 ms jump half-way through ten seconds: three quarters of its
// energy, the remainder then under the noise's fifth that remainder.hpp calls material). The
// offset fitted on short windows of time, every other value held, shows which it is
// (dsp/core/line_or_step.hpp).
#pragma once

#include <vector>

#include "dsp/core/line_or_step.hpp"
#include "dsp/diagnosis/model.hpp"

namespace rsd::dsp {

struct ClockShape {
  // Per window: its middle frame time, the clock's offset there (the window's fitted time offset
  // plus p's drift up to that time), and its variance (clustered by frame).
  std::vector<TimedValue> windows;
  LineOrStep verdict;
};

// The offset over windows of at least kClockWindowS (at most kClockWindows of them) of the
// observations idx, each fitted from p with the time offset alone free. Windows too thin to
// measure it (no motion, too few observations) are left out.
ClockShape clock_shape(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx, double sigma_px);

inline constexpr double kClockWindowS = 1.0;
inline constexpr int kClockWindows = 20;

}  // namespace rsd::dsp
