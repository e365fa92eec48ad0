// A drone's flight for simulated recordings (MotionSource::Samples): forward along the camera's
// optical axis at a constant speed, drifting sideways slowly, the camera on a gimbal that leaves
// a shake of a few milliradians and pans about the vertical axis once. The case the diagnosis
// of a drone's recording must handle: a near scene's parallax in every frame pair, and the
// clock offset visible only in the pan (issue 34).
#pragma once

#include <vector>

#include "dsp/observation/recording.hpp"

namespace rsd::dsp {

struct FlightPath {
  double speed_m_s = 8;       // forward, along the camera's z axis at rest
  double pan_rad = 0.8;       // the gimbal's pan about the camera's y axis...
  double pan_at_s = 4;        // ...starting this long after the first frame...
  double pan_s = 2;           // ...and lasting this long (a smoothstep in angle)
  double shake_rad = 0.004;   // the gimbal's residual shake, per axis (1.7-3.1 Hz)
  double drift_m = 0.3;       // the sideways drift's amplitude (0.7 rad/s)
};

// World-from-body poses every millisecond over [t_begin, t_end]; `t_first_frame` is the first
// frame's time on the motion clock (the pan starts pan_at_s after it).
std::vector<PoseSample> flight_poses(const FlightPath& f, double t_first_frame, double t_begin, double t_end);

}  // namespace rsd::dsp
