// What the diagnosis knows about its own numbers: the held-out split, and the uncertainty of
// every named effect's parameters at the fit.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "dsp/diagnosis/model.hpp"
#include "dsp/diagnosis/named_effect.hpp"

namespace rsd::dsp {

// Every n-th frame in time order is held out of the fit (0 or 1: none).
inline constexpr int kHeldoutEvery = 5;

// One fitted parameter of a named effect with its 1-sigma uncertainty (nullopt when it has
// none: the discrete readout direction, or a parameter the model does not expose).
struct ParamUncertainty {
  std::string effect, param;
  double value = 0;
  std::string text;  // non-numeric value (direction)
  std::optional<double> sigma;
};

// Whether observation i is in the held-out set: its frame is every n-th in time order.
bool held_out(const DiagnosisModel& m, int i, int heldout_every);

// Under the translation nuisance the sandwich is taken clustered by blocks of this many
// consecutive frames too (about a third of a second at 30 fps; when the recording has at least
// 20 of them), and the larger taken: the velocity spline is shared by the pairs its knots span,
// and what it takes of their errors (the gyro's, its own misfit) is shared with them. Fits of
// the suite's walk (`outside: parallax + phone`) from the truth on eight seeds scattered by
// 0.30% in focal length; the sigma clustered by frame pair said 0.16-0.27%, by blocks of 8 and
// 15 frames 0.22-0.37% and 0.19-0.38%.
inline constexpr int kNuisanceClusterFrames = 10;
// Fewer clusters than this make an estimate from their spread (a sandwich covariance, a drop's
// standard error) itself too noisy to use.
inline constexpr int kMinClusters = 20;

// Uncertainties of every named effect's parameters at the fit: numeric Jacobian (central
// differences) of the fitting-set inlier residuals with respect to all named effects'
// continuous parameters at once (so correlations between effects widen them); per parameter
// the larger of the classic s^2 (J^T J)^-1 (s the per-coordinate RMS of those residuals) and
// the sandwich estimate with residuals clustered by frame (errors a frame shares: gyro noise,
// stamp jitter), under the translation nuisance also by blocks of kNuisanceClusterFrames frames.
// Derived parameters (frame_readout_s = line_delay_s x height) are propagated.
// `fit`: the observations the fit saw; `fitted` as it was fitted (its translation nuisance on if
// it was: the spline is refitted at every step, and parallax left in would widen every sigma).
std::vector<ParamUncertainty> effect_uncertainties(const DiagnosisModel& m, const std::vector<NamedEffect>& effects,
                                                   const ModelParams& fitted, const std::vector<int>& fit);

// The covariance of some fitted parameters, two ways (parameter_covariance): the classic
// s^2 (J^T J)^-1 and the clustered sandwich (empty when there are too few clusters for it).
struct ParameterCovariance {
  Eigen::MatrixXd classic, sandwich;
  // The variance of g . parameters: the larger of the two estimates'.
  double variance_of(const Eigen::VectorXd& g) const;
  // Each parameter's: the larger of the two estimates' diagonals.
  Eigen::VectorXd variances() const;
  // How far `delta` (parameters `rows` of this covariance's order) lies from zero in their own
  // uncertainty: the Wald statistic delta^T C^-1 delta over those rows, the smaller of the two
  // estimates' (the more cautious); 0 when the rows' block is singular.
  double wald(const std::vector<int>& rows, const Eigen::VectorXd& delta) const;
};

// Under the translation nuisance (`as_fitted`'s on) the clock offset's sigma in `uncertainties`
// holds, beside the fit's, how far the minimum of its profile with the translation taken out afresh
// lies from where the fit stopped (profile_time_offset, its points the fit's sigma apart), in
// quadrature: the two costs are the same estimator's and do not agree there (the translation's
// passes are a fixed number of alternations between the velocity and each match's own depth, not a
// minimum over both), and where they disagree neither value is better known than their distance.
// The independent generator's drone with a steadier gimbal said -64.8 +- 1.4 ms for -58 ms; now
// +- 5.8 (the profile clamped to four sigmas: at most sqrt(17) times the fit's sigma).
//
// Where the scene's depths spread (translation_depth_spread) it holds too, in quadrature, how far
// the offset moves when the named effects (`named`) are fitted again on `fitted_on` under the
// other depth model: one plane where each match has its own depth, own depths where the plane
// was taken for a small flow (the reasons and measurements: uncertainty.cpp).
void widen_offset_sigma(const DiagnosisModel& m, const std::vector<int>& fitted_on, const ModelParams& as_fitted,
                        const ParamMask& named, double sigma_px, int max_iterations,
                        std::vector<ParamUncertainty>& uncertainties);

// The chi-square with k degrees of freedom that a k-parameter deviation exceeds with the
// probability of a 3-sigma one-parameter deviation (0.0027): 9 for one parameter, 11.8 for two,
// 14.2 for three (Wilson and Hilferty's cube-root approximation, within 1.5% from one up).
double wald_at_three_sigmas(int k);

// The covariances effect_uncertainties takes the larger variances of, from one Jacobian of the
// inliers of `fit` at `fitted` (the parameters `free`, in that order): clustered by frame and,
// under the translation nuisance, by blocks of kNuisanceClusterFrames frames when it has enough
// of them. Empty when the parameters are not identifiable there.
std::vector<ParameterCovariance> fitted_covariances(const DiagnosisModel& m, const ModelParams& fitted,
                                                    const std::vector<Param>& free, const std::vector<int>& fit);

// The variances of the parameters `free` at `fitted` (in their own units, the order of
// `free`), from the inliers among observations idx, as effect_uncertainties computes them:
// the larger of the classic and the frame-clustered sandwich estimate. nullopt when the
// parameters are not identifiable from these observations (singular information).
// With `cluster_frames` > 1 the sandwich's clusters are blocks of that many consecutive frames,
// and it must have at least 20 of them (else nullopt): errors that persist over a block (a model
// that is not quite the camera's, whose misfit follows the motion) widen it as they widen the
// spread of values fitted on different stretches of the recording.
std::optional<Eigen::VectorXd> parameter_variances(const DiagnosisModel& m, const ModelParams& fitted,
                                                   const std::vector<Param>& free, const std::vector<int>& idx,
                                                   int cluster_frames = 1);

// The whole covariance behind parameter_variances (the same observations, clusters and rules),
// for values that combine several parameters (a lens's radial curve).
std::optional<ParameterCovariance> parameter_covariance(const DiagnosisModel& m, const ModelParams& fitted,
                                                        const std::vector<Param>& free, const std::vector<int>& idx,
                                                        int cluster_frames = 1);

// d residual / d parameter (px per unit) of the observations idx at `at`: rows 2k, 2k + 1 are
// idx[k]'s, a column per parameter of `free`. Central differences of a hundredth of the
// parameter's typical change: well above the rolling-shutter root-finder's tolerance, well
// inside the linear range. A failed prediction has zero rows. Under the translation nuisance
// both steps hold the inliers, slope and own depths it settled on at `at` (residuals_near).
Eigen::MatrixXd residual_jacobian(const DiagnosisModel& m, const ModelParams& at, const std::vector<Param>& free,
                                  const std::vector<int>& idx);

// The ModelParams index of a spec parameter name ("line_delay_s", "k1", "x", ...), if the
// diagnosis model has one by that name.
std::optional<Param> param_by_name(const std::string& name);

}  // namespace rsd::dsp
