// Simulated observation recordings (docs/formats/recording-v1.md): the nominal model
// that the recording's header states, and data generated from a "true" model that differs
// from it by any of the spec's named effects. Pure computation, deterministic per seed; the
// rsd-sim tool reads the scenario and writes the files.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/observation/observation_model.hpp"
#include "dsp/observation/recording.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::dsp {

// The spec's named effects, each with its true parameters; unset = as nominal.
struct Effects {
  std::optional<double> line_delay_s;     // rolling_shutter
  bool flip_readout = false;              // readout_direction
  std::optional<double> time_offset_s;    // time_offset
  std::optional<double> drift_ppm;        // clock_drift
  std::optional<Eigen::Vector2d> k1k2;    // lens_distortion: k1, k2 of the nominal lens
  std::optional<Eigen::Vector2d> k3k4;    // lens_distortion: k3, k4 (a pinhole-equi nominal lens)
  std::optional<Distortion> lens;         // lens_model: a lens of the other family, all its terms
  std::optional<Eigen::Vector2d> fxfy;    // focal_length
  std::optional<Eigen::Vector3d> gyro_bias;  // gyro_bias (IMU axes)
  std::optional<Eigen::Vector3d> lever_arm;  // lever_arm (body axes)
  std::optional<Eigen::Vector3d> mount_rotation;   // mount_rotation: rotation vector r
  std::optional<Eigen::Vector3d> gyro_scale;       // gyro_scale: w_true = diag(s) (w_measured - b)
  std::optional<Eigen::Vector2d> principal_point;  // principal_point: cx, cy
  bool any() const;
  std::vector<std::string> names() const;  // spec names of the effects switched on
};

struct GyroSampling {
  double rate_min_hz = 200, rate_max_hz = 200;  // each interval drawn in between
  double gap_probability = 0;     // chance that a sample starts a gap of 5-20 missing samples
  double repeat_probability = 0;  // chance that a sample repeats the previous timestamp
  double jitter_s = 0;            // timestamp noise (sorted afterwards)
  double noise_rad_s = 0;
};

// Where the body's motion comes from.
enum class MotionSource {
  Smooth,    // sums of sinusoids about a rest pose (default)
  Constant,  // constant velocity in body axes: a screw motion from the rest pose
  Samples,   // given poses (e.g. a trajectory file), interpolated linearly and by slerp
};

// Physics outside the named effects: what a diagnosis must report as a remainder and never
// name as one of the table's effects (docs/formats/recording-v1.md, "remainder").
struct Unmodelled {
  // Matches: the features lie on a plane this far along frame_a's optical axis (0: at
  // infinity, the rotation-only model's world). The body's translation then gives parallax.
  double scene_depth_m = 0;
  // The plane's slope: its inverse depth is (1 + slope . (x, y)) / scene_depth_m at the
  // normalised image coordinates (x, y) of frame_a (a ground ahead: slope.y() > 0, nearer
  // towards the image's bottom); no feature where the plane lies behind the camera or beyond
  // ten times the depth. Zero: the plane faces the camera.
  Eigen::Vector2d scene_slope = Eigen::Vector2d::Zero();
  // The plane stays in the world where it lay before the camera at the recording's middle
  // instant (a wall or the ground: its depth and slope in the camera change as the camera turns
  // and moves) instead of lying the same way before every pair's frame_a, the translation
  // nuisance's own model (docs/diagnosis.md, "Parallax"), which the latter thus meets by
  // construction.
  bool scene_fixed_in_world = false;
  double gyro_saturation_rad_s = 0;  // the gyro clips each axis at +- this (0: never)
  // The frame stamps jump by clock_jump_s from clock_jump_at_s after the first frame on.
  double clock_jump_s = 0;
  double clock_jump_at_s = 0;
  // Matches: the camera stabilises its video (as an action camera does): the pictures follow the
  // orientation smoothed by a zero-phase low-pass of this corner frequency (forward and backward
  // first-order passes), the gyro the real one (0: no stabilisation).
  double stabilisation_hz = 0;
  // false: the stabiliser does not look ahead (the forward pass alone, a causal low-pass): the
  // pictures lag the motion, by 1 / (2 pi stabilisation_hz) at frequencies well under the corner.
  bool stabilisation_looks_ahead = true;
  bool any() const {
    return scene_depth_m > 0 || gyro_saturation_rad_s > 0 || clock_jump_s != 0 || stabilisation_hz > 0;
  }
};

struct SimConfig {
  ObservationKind kind = ObservationKind::Landmarks;
  NominalModel nominal;
  Effects effects;
  Unmodelled unmodelled;
  unsigned seed = 1;
  double duration_s = 2.0;
  double start_time_s = 100.0;     // camera clock of the first frame
  double noise_px = 0.5;
  // Motion: smooth random translation/rotation about a rest pose.
  double translation_amplitude_m = 0.1;
  double rotation_amplitude_rad = 0.15;
  double motion_frequency_hz = 1.0;
  double trajectory_rate_hz = 500;
  MotionSource motion_source = MotionSource::Smooth;
  Eigen::Vector3d constant_velocity = Eigen::Vector3d::Zero();      // m/s, body axes
  Eigen::Vector3d constant_angular_rate = Eigen::Vector3d::Zero();  // rad/s, body axes
  std::vector<PoseSample> pose_samples;  // MotionSource::Samples: world-from-body poses
  GyroSampling gyro;
  // Landmarks: the given points (world frame; the body rests at (0, 0, -target_distance_m)
  // looking along +z), or if none are given a planar grid of rows x cols points at z = 0,
  // `spacing_m` apart.
  std::vector<Landmark> points;
  int target_rows = 7, target_cols = 9;
  double target_spacing_m = 0.1;
  double target_distance_m = 1.2;
  // Matches: features per consecutive frame pair, outlier share.
  int matches_per_pair = 150;
  double outlier_fraction = 0.0;
};

struct SimulatedRecording {
  Recording rec;
  Effects truth;                  // the effects that were switched on
  std::vector<bool> match_outlier;  // ground truth per match
};

// The camera as it really is: the nominal model with every switched-on effect applied.
struct TrueModel {
  CameraModel cam;
  TimeModel time;
  Eigen::Vector3d lever_arm = Eigen::Vector3d::Zero(), gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Matrix3d mount = Eigen::Matrix3d::Identity();  // Exp(r) of mount_rotation
  Eigen::Vector3d gyro_scale = Eigen::Vector3d::Ones();
};
TrueModel true_model(const NominalModel& nominal, const Effects& effects);

// Validates the config (throws std::invalid_argument naming the field) and simulates.
SimulatedRecording simulate_recording(const SimConfig& cfg);

}  // namespace rsd::dsp
