// Model-discrepancy diagnosis of an observation recording (../shared/formats/recording-v1.md):
// how badly the nominal model fits (robust baseline), where the mismatch lives (located
// signals), and which named effects explain it (fitted with Ceres, chosen by BIC forward
// selection with a backward check), with a held-out comparison on frames the fit did not see.
// Pure computation: the rsd-diagnose tool reads the files and writes the JSON and report.
#pragma once

#include <string>
#include <vector>

#include "dsp/diagnosis_model.hpp"

namespace rsd::dsp {

// Robust summary of 2-D pixel residuals. The scale is the per-coordinate sigma estimated
// from the median residual length (a 2-D Gaussian's length is Rayleigh distributed);
// residuals longer than `kOutlierSigmas` scales, and failed predictions (NaN), are outliers.
struct RobustStats {
  double rms_px = 0;      // per-coordinate RMS of the inliers
  double scale_px = 0;    // robust per-coordinate sigma
  int observations = 0;   // all, inliers and outliers
  int outliers = 0;
};
constexpr double kOutlierSigmas = 5.0;
RobustStats robust_stats(const std::vector<Eigen::Vector2d>& residuals);

// Where the residual lives: `strength` is the share (0..1) of the inlier residual energy a
// signal's pattern explains.
struct Located {
  std::string signal;  // image_velocity, row, radius, image_scale, time
  double strength;
  std::string detail;
};
std::vector<Located> locate(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx);

struct EffectParam {
  std::string name;
  double value = 0;
  std::string text;  // non-empty for a non-numeric value (readout direction)
};
struct NamedEffect {
  std::string name;  // the spec's effect name
  std::vector<EffectParam> params;
  std::string explains;
  double rms_px = 0;    // fitting-set RMS once this effect (and those before it) is in
  double bic_drop = 0;  // how much BIC fell when it was added
};

struct Diagnosis {
  RobustStats baseline;
  std::vector<Located> located;
  std::vector<NamedEffect> effects;  // in order of selection; empty = fits within noise
  ModelParams fitted;
  double sigma_px = 0;  // the noise scale the fits and BIC used
  double final_rms_px = 0;
  double heldout_baseline_rms_px = 0, heldout_final_rms_px = 0;
  int heldout_observations = 0;
};

struct DiagnosisOptions {
  int heldout_every = 5;         // every n-th frame is held out of the fit (0: none)
  double min_bic_drop = 10;      // "very strong" evidence on the usual BIC scale
  int max_iterations = 30;
};

// Fits the parameters in `free` (starting at `start`), residuals in units of sigma under a
// Huber loss. Returns the fitted parameters.
ModelParams fit_params(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& start,
                       const ParamMask& free, double sigma_px, int max_iterations = 30);
// Global search of the time offset (others held at `p`): a coarse scan over the offsets that
// keep the frames inside the motion data (at most +-1 s around p's), then a fine one.
double scan_time_offset(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p,
                        double sigma_px);

Diagnosis diagnose(const Recording& rec, const DiagnosisOptions& opt = {});

}  // namespace rsd::dsp
