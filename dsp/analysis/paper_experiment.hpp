// The paper's simulation (Meingast, Geyer, Sastry 2005, Sec. 4 "Simulation", fig. simfigs):
// random points seen by two rolling-shutter cameras moving with v = (0, v_y, 0), observed
// with pixel noise, and the relative pose recovered by two-view bundle adjustment with the
// rolling-shutter model and with the perspective model. Pure computation, deterministic
// given a seed; docs/paper-experiment.md states every choice and shows the results.
//
// Common random numbers: trial k of every cell uses the same scene, initial guess and unit
// noise (drawn from the seed and k alone), so cells differ only in v_y and sigma and the
// curves over sigma and v_y are smooth without more trials.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "dsp/analysis/two_view_bundle_adjustment.hpp"

namespace rsd::dsp {

// The paper's velocities (km/h) and pixel noises (standard deviation per image coordinate).
inline constexpr std::array<double, 4> kPaperSpeedsKmh = {1.875, 3.75, 5.625, 7.5};
inline constexpr std::array<double, 6> kPaperSigmasPx = {0.5, 1.33, 2.16, 3.0, 3.83, 4.66};

struct ExperimentSetup {
  // The paper's Figure 1 camera: 640 x 480, 40 deg horizontal field of view
  // (fx = fy = 879.19 px), no distortion; 15 fps with the readout filling the frame
  // (r = 480 x 15 = 7200 rows/s, top to bottom, d = 0).
  CameraModel cam = CameraModel::from_hfov(640, 480, 40.0 * 3.14159265358979323846 / 180.0);
  RowTiming timing = RowTiming::full_frame(480, 15.0);
  int points = 100;
  // Points uniform in a ball about the origin, clipped to what both cameras see: at 10 m
  // the image spans 7.3 m x 5.5 m, so the points fill the images and have +-3 m of depth
  // relief (a smaller cloud is flatter and its relative rotation less well determined).
  double cloud_radius_m = 3.0;
  double distance_min_m = 9.0;  // camera centre to cloud centre, uniform in [min, max]
  double distance_max_m = 11.0;
  double view_angle_min_deg = 15.0;  // angle between the cameras' viewing directions
  double view_angle_max_deg = 45.0;
  // A point is kept only if both cameras see it inside the image at v_y = 0 and at this
  // speed, hence (the rolling-shutter shift grows monotonically with v_y) at every speed
  // in between: every cell then uses the same 100 points.
  double max_speed_kmh = 7.5;
  // The initial guess is the truth perturbed: camera 2's rotation by this angle about a
  // random axis, its translation direction by this angle (length kept: it is the gauge),
  // every point coordinate by Gaussian noise of this standard deviation.
  double init_rotation_deg = 2.0;
  double init_direction_deg = 2.0;
  double init_point_sigma_m = 0.1;
  double huber_px = 0;  // 0: plain least squares (no outliers in this experiment)
};

// One trial's random draw, independent of v_y and sigma.
struct TrialDraw {
  TwoViewEstimate truth;    // camera 2's pose and the points in camera 1's frame
  TwoViewEstimate initial;  // where both bundle adjustments start
  std::array<std::vector<Eigen::Vector2d>, 2> unit_noise;  // N(0, 1) per pixel coordinate
};

// Trial `trial` of the experiment seeded by `seed`.
TrialDraw draw_trial(const ExperimentSetup& setup, std::uint64_t seed, int trial);

// The paper's motion: v = (0, v_y, 0) m/s in the camera frame, w = 0 (eq. (4)
// is exact). Positive v_y moves the image down, along the top-to-bottom readout.
Twist paper_motion(double vy_kmh);

// The cameras' observations of the draw: eq. (4) for both cameras, each
// moving with paper_motion(vy_kmh) in its own frame, plus sigma_px times the unit noise.
TwoViewData observe(const ExperimentSetup& setup, const TrialDraw& draw, double vy_kmh,
                    double sigma_px);

// The paper's error measures: |log(R0^-1 R_hat)| and the angle between t_hat and t0, in
// degrees. The angle is computed as atan2(|a x b|, a . b), equal to the paper's
// acos(a . b / (|a| |b|)) but accurate for tiny angles.
double rotation_error_deg(const Eigen::Quaterniond& truth, const Eigen::Quaterniond& estimate);
double direction_error_deg(const Eigen::Vector3d& truth, const Eigen::Vector3d& estimate);

struct ModelErrors {
  double reproj_px = 0;  // RMS reprojection error of the fit (two_view_rms)
  double rot_deg = 0;
  double trans_deg = 0;
  bool converged = false;
};

// Both bundle adjustments of one trial, indexed by ProjectionModel.
using TrialErrors = std::array<ModelErrors, 2>;
TrialErrors run_trial(const ExperimentSetup& setup, const TrialDraw& draw, double vy_kmh,
                      double sigma_px);

struct Stats {
  double mean = 0, std = 0, median = 0;  // std: sample standard deviation (n - 1)
};
Stats summarize(std::vector<double> values);

struct ModelSummary {
  int trials = 0;
  int not_converged = 0;  // trials that stopped on the iteration limit (still counted)
  Stats reproj_px, rot_deg, trans_deg;
};

struct Cell {
  double vy_kmh = 0, sigma_px = 0;
};

struct CellResult {
  Cell cell;
  std::array<ModelSummary, 2> models;  // indexed by ProjectionModel
};

// The paper's 24 cells, speed-major: (1.875, 0.5), (1.875, 1.33), ..., (7.5, 4.66).
std::vector<Cell> paper_cells();

// Trials 0 .. trials - 1 of one cell, aggregated.
CellResult run_cell(const ExperimentSetup& setup, std::uint64_t seed, const Cell& cell, int trials);

}  // namespace rsd::dsp
