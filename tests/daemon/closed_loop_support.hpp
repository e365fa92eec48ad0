// The closed loop's shared parts (docs/closed-loop.md, docs/online-calibration.md): a simulated
// rig recorded as an images recording, the daemon's replay of it, the offline diagnosis of its
// pictures, and the error of rectified frames against the simulator's global-shutter truth.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>

#include "daemon/config.hpp"
#include "drivers/sim_source.hpp"
#include "dsp/sim/rs_renderer.hpp"
#include "dsp/observation/recording.hpp"
#include "formats/calibration_v1.hpp"
#include "tests/daemon/closed_loop_figure.hpp"

namespace rsd::test {

constexpr int kW = 640, kH = 480;

// The camera as it is (the simulator's) and as the daemon is told it is (the nominal).
struct SimRig {
  drivers::SimSourceConfig truth;
  dsp::NominalModel nominal;
};

// Captures the simulated camera into an images recording in `dir`; returns the simulator's time
// zero on the camera clock. As on a rig, the gyro runs before the first frame kept and after the
// last one (the frames of the first and last 10 are left out), so that any clock offset within
// a few frame periods keeps every frame's motion inside the data.
int64_t record(const SimRig& r, int frames, const std::filesystem::path& dir);

// Renders the global-shutter truth at a time on the camera clock (s).
using TruthRender = std::function<void(double t_camera_s, const dsp::ImageView&)>;

// The simulated rig's global-shutter truth: its scene and motion rendered by its true camera
// with every row at once, at a camera-clock time; t0_ns: the recording's time zero (record()'s).
class SimTruth {
 public:
  SimTruth(const SimRig& r, int64_t t0_ns);
  void operator()(double t_camera_s, const dsp::ImageView& v);

 private:
  drivers::SimSource sim_;
  std::unique_ptr<dsp::RsRenderer> gs_;
  double t0_s_;
};

// Plays the recording through the daemon's replay source, velocity input and rectifier with
// `cal`, and measures every other frame (but the first two) against the truth at its reference
// time: each frame rectifies, while the truth's render and the tracking, most of a closed loop's
// time, go to half of them (still thousands of features a replay).
Measured rectified_rms(daemon::Config cfg, const formats::Calibration& cal, const TruthRender& render_truth);

// An images recording played as the daemon plays it (rsd --replay DIR --speed fast).
daemon::Config replay_of(const std::filesystem::path& dir);

// The diagnosis, from the pictures on disk, and the calibration file it writes, read back.
formats::Calibration learn(const std::filesystem::path& dir, const char* name);

// What the simulated camera hid, as a calibration file would say it.
formats::Calibration true_calibration(const drivers::SimSourceConfig& t, const dsp::NominalModel& nominal);

}  // namespace rsd::test
