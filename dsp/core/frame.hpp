// What a camera source delivers with each frame: its format, its stamp and, for sources
// that know it, the camera's own motion. Plain data shared by drivers, the recorded-frame
// codec and the daemon.
#pragma once

#include <cstddef>
#include <cstdint>

#include "dsp/core/image.hpp"

namespace rsd::dsp {

struct FrameFormat {
  int width = 0, height = 0;
  PixelFormat format = PixelFormat::Mono8;
  size_t bytes() const { return frame_bytes(format, width, height); }
};

struct FrameMeta {
  int64_t first_row_ns = 0;  // CLOCK_MONOTONIC: start of exposure of the first row read
  int64_t wall_ns = 0;       // the same instant in Unix time (CLOCK_REALTIME); 0: not yet known
  uint64_t sequence = 0;     // the source's own counter; gaps mean the source dropped frames
  double exposure_s = 0;     // row exposure, if the source knows it
};

// The camera's own motion, as some sources know it (the simulator's truth, a replayed log).
struct VelocitySample {
  int64_t t_ns = 0;  // CLOCK_MONOTONIC (or the replayed clock)
  double w[3] = {0, 0, 0};  // rad/s, camera axes
  double v[3] = {0, 0, 0};  // m/s, camera axes
  bool has_linear = false;
  // The motion sensor's own measurement: rates in its axes, stamped on its clock. The daemon's
  // velocity input applies the calibration (clock offset, bias, scale, rotation) to it, as to
  // an rsd.velocity_t in FRAME_IMU. false: already the camera's motion on the camera clock.
  bool imu_frame = false;
};
}  // namespace rsd::dsp
