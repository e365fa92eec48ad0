// The closed-loop test's figure (docs/closed-loop.md): each frame's rectified error against the
// global-shutter truth with the nominal, the learned and the true calibration.
#pragma once

#include <string>
#include <vector>

namespace rsd::test {

// One calibration's measurement: RMS over every tracked feature, and per frame.
struct Measured {
  double rms = 0;
  std::vector<double> t, frame_rms;  // frame time (camera clock, s), its RMS (px)
};

// Writes a PNG: the three per-frame RMS curves on a logarithmic axis.
void plot_closed_loop(const std::string& file, const std::string& name, const Measured& nominal, const Measured& learned,
                      const Measured& truth);

}  // namespace rsd::test
