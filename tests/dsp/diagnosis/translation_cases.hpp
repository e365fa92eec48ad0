// The simulated flights and hand-held shakes the translation nuisance's tests share
// (test_diagnosis_translation.cpp, its parts; test_translation_diagnoses.cpp, whole diagnoses).
#pragma once

#include <Eigen/Dense>

#include "dsp/diagnosis/diagnosis.hpp"
#include "dsp/sim/flight_path.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"

namespace rsd::test {

using namespace rsd::dsp;

// A drone flying forward at 8 m/s past a scene `depth_m` ahead (a plane facing each frame pair's
// first camera), panning by 0.8 rad over the 2 s from 4 s on (flight_path.hpp); 10 s of the VGA
// camera, 0.5 px noise.
inline SimConfig forward_flight(unsigned seed, double depth_m) {
  SimConfig c = simulation(ObservationKind::Matches, seed, 10.0, 0.5);
  c.motion_source = MotionSource::Samples;
  c.pose_samples = flight_poses(FlightPath{}, c.start_time_s, c.start_time_s - 3, c.start_time_s + c.duration_s + 3);
  c.unmodelled.scene_depth_m = depth_m;
  c.gyro.noise_rad_s = 0.002;
  return c;
}

inline ModelParams with_offset(const SimulatedRecording& sim, double offset_s, bool nuisance) {
  ModelParams p = nominal_params(sim.rec.nominal);
  p[Param::TimeOffset] = offset_s;
  p.translation_nuisance = nuisance;
  return p;
}

// A ground ahead of the drone, as a tilted plane: its inverse depth grows towards the image's
// bottom (and a little to the right), from 0.4 to 1.6 times the depth's at the image's top and
// bottom rows (VGA, f 500 px).
inline const Eigen::Vector2d kGround(0.3, 1.25);

// The suite's `outside: parallax` rig (rsd-diagnose-suite, matches): a hand-held 1080p camera
// (f 1450 px, an irregular gyro on a phone's axes, 10% outliers) 4 m from a wall, shaken by
// 5 cm with terms up to about 2.7 Hz, 20 s: a velocity spline with knots every 0.5 s cannot
// follow the shake. The seeds are the suite's `parallax + focal_length` case's on seed shifts 1 and 2.
inline constexpr unsigned kShakeSeeds[] = {759513, 759514};
inline SimConfig hand_held_shake(unsigned seed) {
  SimConfig c = simulation(ObservationKind::Matches, seed, 20.0, 0.7);
  c.nominal.cam.width = 1920, c.nominal.cam.height = 1080;
  c.nominal.cam.fx = c.nominal.cam.fy = 1450, c.nominal.cam.cx = 959.5, c.nominal.cam.cy = 539.5;
  c.nominal.imu_to_camera << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  c.start_time_s = 1000;
  c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2, c.translation_amplitude_m = 0.05;
  c.gyro = {20, 200, 0.01, 0.03, 0.0005, 0.002};
  c.matches_per_pair = 120, c.outlier_fraction = 0.1;
  c.unmodelled.scene_depth_m = 4.0;
  return c;
}

}  // namespace rsd::test
