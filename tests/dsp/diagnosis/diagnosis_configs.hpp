// Building blocks of the diagnosis tests' simulated recordings: a 640x480 camera at 30 fps
// (f = 500 px) and a 5x6 target 1 m away, shaken by hand.
#pragma once

#include "dsp/sim/recording_simulation.hpp"

namespace rsd::test {

// A simulation of `kind` with the VGA camera, seeded, with per-coordinate noise in px.
inline dsp::SimConfig simulation(dsp::ObservationKind kind, unsigned seed, double duration_s, double noise_px);

inline void vga_camera(dsp::NominalModel& n) {
  n.cam.width = 640, n.cam.height = 480;
  n.cam.fx = n.cam.fy = 500, n.cam.cx = 319.5, n.cam.cy = 239.5;
  n.frame_rate_hz = 30;
}

inline void small_target(dsp::SimConfig& c) {
  c.target_rows = 5, c.target_cols = 6, c.target_spacing_m = 0.12, c.target_distance_m = 1.0;
  c.translation_amplitude_m = 0.1, c.rotation_amplitude_rad = 0.15;
}

inline dsp::SimConfig simulation(dsp::ObservationKind kind, unsigned seed, double duration_s, double noise_px) {
  dsp::SimConfig c;
  c.kind = kind;
  c.seed = seed;
  c.duration_s = duration_s;
  c.noise_px = noise_px;
  vga_camera(c.nominal);
  return c;
}

// The small target (small_target) filmed by the VGA camera.
inline dsp::SimConfig target_simulation(unsigned seed, double duration_s, double noise_px) {
  dsp::SimConfig c = simulation(dsp::ObservationKind::Landmarks, seed, duration_s, noise_px);
  small_target(c);
  return c;
}

// Matches from the VGA camera shaken by hand at 1.2 Hz (0.25 rad), 80 a frame pair, 0.5 px
// noise, 4 s, its IMU turned on the camera: the invariants' and the stabiliser's recordings.
inline dsp::SimConfig shaken(unsigned seed) {
  dsp::SimConfig c = simulation(dsp::ObservationKind::Matches, seed, 4.0, 0.5);
  c.matches_per_pair = 80;
  c.nominal.imu_to_camera << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2;
  return c;
}

}  // namespace rsd::test
