// Where a residual lives: the signals its pattern follows.
#pragma once

#include <string>
#include <vector>

#include "dsp/diagnosis/model.hpp"

namespace rsd::dsp {

// Where the residual lives: `strength` is the share (0..1) of the inlier residual energy a
// signal's pattern explains. Signals: image_velocity, row, radius, image_scale, time_trend,
// time, fast_rotation and angular_rate (gyro recordings), depth (trajectory recordings); see
// dsp/diagnosis/locate.cpp. Uses at most 3000 of `idx`.
struct Located {
  std::string signal;
  double strength;
  std::string detail;
};
std::vector<Located> locate(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx);

}  // namespace rsd::dsp
