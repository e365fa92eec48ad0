// The recording's model with every effect parameter of docs/formats/recording-v1.md
// ("Named effects") in one vector, so that the diagnosis can free any subset of them and
// fit it. Residuals are observed minus predicted pixels through the spec's model; with
// nothing changed they are the nominal model's own residuals (the baseline).
//
// Landmarks (motion kind trajectory): observed pixel minus the projection of the point at the
// rolling-shutter fixed point (spec "Landmarks"). Matches (motion kind gyro): observed pixel in
// frame_b minus the transfer of the frame_a pixel, d_b = R_c(t_b)^T R_c(t_a) d_a (spec
// "Matches"), t_a from frame_a's observed row, t_b the fixed point of the predicted row in
// frame_b. The transfer carries frame_a's pixel noise too, so a match residual has
// sqrt(2) x the pixel noise per coordinate (`noise_gain`).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <bitset>
#include <limits>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "dsp/geometry/camera_motion.hpp"
#include "dsp/diagnosis/gyro.hpp"
#include "dsp/diagnosis/gyro_stamps.hpp"
#include "dsp/diagnosis/pose_track.hpp"
#include "dsp/diagnosis/translation.hpp"
#include "dsp/observation/recording.hpp"

namespace rsd::dsp {

// The continuous parameters. Order is fixed; names are the spec's.
enum class Param : int {
  LineDelay, TimeOffset, Drift, K1, K2, Fx, Fy, LeverX, LeverY, LeverZ, BiasX, BiasY, BiasZ,
  K3, K4,                  // the equidistant lens's third and fourth terms (lens_distortion, lens_model)
  MountX, MountY, MountZ,  // mount_rotation: rotation vector r (rad)
  ScaleX, ScaleY, ScaleZ,  // gyro_scale (1 nominal)
  Cx, Cy,                  // principal_point (px)
  Count
};
constexpr int kParamCount = static_cast<int>(Param::Count);
using ParamMask = std::bitset<kParamCount>;

const char* param_name(Param p);
// The parameters a mask holds, in Param order.
std::vector<Param> params_in(const ParamMask& mask);

struct ModelParams {
  std::array<double, kParamCount> v{};
  bool flip_readout = false;  // readout_direction: the opposite of the nominal order
  // lens_model: the lens is of the other family than the nominal one, with K1.. its terms
  // (pinhole-equi K1..K4; pinhole-radtan K1, K2 and no tangential or k3 term).
  bool other_lens = false;
  // Matches: each frame pair's translation flow is taken out of its residuals (parallax.hpp),
  // when the recording shows parallax that the rotation-only model cannot express.
  bool translation_nuisance = false;
  // The knot spacing of its velocity spline (s; translation.hpp).
  double translation_knot_s = kTranslationKnotS;
  // Each match's own depth about the plane: the noise over the scene's depth spread
  // (translation_depth_spread), px; 0: one plane.
  double translation_depth_px = 0;
  // The scene's plane fixed in the world (a wall, a ground: its tilt in each frame pair's camera
  // follows the camera's turns) rather than lying the same way before every pair's first frame
  // (a landscape that keeps its distance from a flying camera); translation_travel chooses.
  bool translation_world_plane = false;
  // With it, each frame pair's time shift under the gyro stamps' remaining error (translation.hpp,
  // pair_shifts); the gross search goes without (gross_start: one observation a pair under a
  // truncated cost, where a shift per pair would cost a rate per observation and decide nothing).
  bool translation_pair_shifts = true;
  double& operator[](Param p) { return v[static_cast<int>(p)]; }
  double operator[](Param p) const { return v[static_cast<int>(p)]; }
};

// The nominal model's values of every parameter (no effect switched on; gyro bias zero).
ModelParams nominal_params(const NominalModel& n);
// `p` with the translation nuisance of `from`: on or off, its spline's knots, own depths and
// pair shifts.
ModelParams with_translation_of(ModelParams p, const ModelParams& from);
// A typical size of a change of each parameter: the fit works in these units so that one
// step size suits all (a line delay of 1e-5 s and a focal length of 900 px alike).
double param_scale(Param p, const NominalModel& n);
// Sets parameter q of p to v. Pixels are square (to far better than a diagnosis resolves), so
// the focal_length effect is one focal scale: setting fx sets fy at the nominal's aspect. Fitted
// apart, fy stood in for the vertical stretch a rolling shutter gives a pan (a 13% focal error
// under parallax came out as fx and fy 5% apart, and was refused). Fy is never free on its own.
void set_param(ModelParams& p, Param q, double v, const NominalModel& n);
// A parameter that is never free on its own follows another as set_param sets it (fy follows fx
// at the nominal's aspect): the one it follows and the factor, so that its uncertainty is that
// factor times the other's. nullopt for a parameter that is free on its own.
struct Follows {
  Param leader;
  double factor;
};
std::optional<Follows> follows(Param q, const NominalModel& n);

// Landmarks recordings with a trajectory, matches recordings with a gyro. Not thread-safe:
// the gyro track of the last few bias values is cached inside.
class DiagnosisModel {
 public:
  // Throws std::invalid_argument for a recording it cannot model (landmarks without a
  // trajectory, matches without a gyro, an observation naming an unknown frame or point).
  explicit DiagnosisModel(const Recording& rec);
  // The same observations seen through another record of the gyro's rates: `gyro` as
  // gyro_samples() of m made it (cleaned, its stamps where the rates put them), its rates
  // changed (a stabilised video's test smooths them: stabiliser.hpp). Stamps and gaps as m's; m's
  // recording must outlive it. Throws std::invalid_argument for landmarks.
  DiagnosisModel(const DiagnosisModel& m, std::vector<GyroSample> gyro);
  ~DiagnosisModel();

  const Recording& recording() const { return rec_; }
  ObservationKind kind() const { return rec_.kind; }
  int size() const { return static_cast<int>(obs_->size()); }
  // Observed minus predicted pixel of observation i; nullopt when the model has no image
  // of the point (behind the camera, no rolling-shutter solution).
  std::optional<Eigen::Vector2d> residual(const ModelParams& p, int i) const;
  // Residuals of the observations `idx`; failed predictions are NaN.
  std::vector<Eigen::Vector2d> residuals(const ModelParams& p, const std::vector<int>& idx) const;
  // Where a match's rolling-shutter fixed point settled: the row and the slope there of the
  // predicted row's offset from it (NaN: not yet, or none).
  struct RowStart {
    double row = std::numeric_limits<double>::quiet_NaN(), slope = std::numeric_limits<double>::quiet_NaN();
  };
  // What residuals settled on at one point, for residuals_near at nearby parameters on the same
  // observations (the fits' Jacobian, fit.cpp: its analytic columns and its steps): each match's fixed
  // point, and under the translation nuisance what remove_translation settled on
  // (translation.hpp).
  struct Settled {
    TranslationFit translation;
    std::vector<RowStart> rows;  // matches: per observation of idx
    // Under the translation nuisance: the residuals before the translation was taken out.
    std::vector<Eigen::Vector2d> rotation;
  };
  // As residuals(p, idx), and what they settled on goes to `settled` (what it held, settled on the
  // same idx, speeds the translation up: remove_translation's hint). With `rows_from` (settled on
  // the same idx at nearby parameters: a fit's trial step from its current point) each match's
  // fixed point starts from its solution there, as residuals_near's do; the translation is taken
  // out afresh. Throws std::invalid_argument when idx is not the size `rows_from` was settled on.
  std::vector<Eigen::Vector2d> residuals(const ModelParams& p, const std::vector<int>& idx, Settled& settled,
                                         const Settled* rows_from = nullptr) const;
  // As residuals(p, idx), at parameters near those `near` was settled at on the same idx: each
  // match's fixed point starts from its solution there (two projections, not three; the row
  // settles to the same 1e-6 px), and the translation is taken out as it settled there
  // (remove_fitted_translation). Throws std::invalid_argument when idx is not the size `near`
  // was settled on.
  std::vector<Eigen::Vector2d> residuals_near(const ModelParams& p, const std::vector<int>& idx, const Settled& near) const;
  // r, residuals of idx as the rotation model leaves them at p (near the point `near` settled
  // at), with the translation taken out as it settled there (remove_fitted_translation): the
  // last step of residuals_near, for a Jacobian column the rotation model's part of which is
  // analytic (fit.cpp). r as it is without the translation nuisance.
  std::vector<Eigen::Vector2d> translation_out_near(const ModelParams& p, const std::vector<int>& idx,
                                                    std::vector<Eigen::Vector2d> r, const Settled& near) const;
  // The linear part of translation_out_near taken out of each column of `cols` (2 x idx.size()
  // rows, remove_fitted_translation_from_columns): the Jacobian columns, under the translation
  // nuisance, of the parameters that do not move the translation pass (moves_translation_pass).
  // Nothing without the nuisance.
  void translation_out_of_columns(const ModelParams& p, const std::vector<int>& idx, Eigen::MatrixXd& cols,
                                  const Settled& near) const;
  // Whether q moves the translation pass of a matches recording: the frame pairs' turns follow
  // the clock's offset and drift, the mount and the gyro's bias and scale (and the lever arm,
  // which matches do not see), the matches' times the line delay; the intrinsics and the lens
  // leave them.
  static bool moves_translation_pass(Param q);
  // Matches: d(residual before the translation) / d(parameter) of each observation of idx for the
  // parameters kAnalyticParams (match_jacobian.hpp), at p where `at` was settled on idx (its
  // fixed points); zero for a failed prediction. Without `gyro` the bias and scale columns are
  // left zero (they need the track's derivative, integrated over all of it once per bias).
  // Throws std::invalid_argument for landmarks or when `at` was settled on other observations.
  std::vector<Eigen::Matrix<double, 2, 20>> rotation_jacobian(const ModelParams& p, const std::vector<int>& idx,
                                                              const Settled& at, bool gyro = true) const;
  // Position of observation i's frame (frame_a for a match) in time order (0 = first frame).
  int frame_rank(int i) const { return (*obs_)[i].rank; }
  double frame_time(int i) const { return (*obs_)[i].T; }
  // The observed pixel the residual is taken at (frame_b's for a match).
  Eigen::Vector2d observed(int i) const { return (*obs_)[i].px; }
  // Matches: the frame_a pixel and frame_b's timestamp (landmarks: observed(i), frame_time(i)).
  Eigen::Vector2d observed_a(int i) const { return (*obs_)[i].px_a; }
  double frame_time_b(int i) const { return (*obs_)[i].T_b; }
  // Time offsets for which every frame stays inside the motion data.
  std::pair<double, double> offset_range() const;
  // Per-coordinate residual sigma over the pixel noise sigma: 1 (landmarks), sqrt(2) (matches).
  double noise_gain() const { return rec_.kind == ObservationKind::Matches ? std::sqrt(2.0) : 1.0; }
  // Matches: the longest gap between gyro samples over observation i's frames (frame_a's
  // start to frame_b's end, on the motion clock of `p`); 0 for landmarks. Inside a long gap the
  // rate is unknown and the transfer a guess.
  double gyro_gap(const ModelParams& p, int i) const;
  // The longest gyro gap a match may span and still be predicted: 1.5 x the 95th percentile
  // of the sampling intervals, at least 20 ms (infinite for landmarks).
  double max_gyro_gap() const { return max_gap_; }
  // Matches: what the gyro's rates said of its stamps, and how far the samples' times were
  // moved to where the rates put them (dsp/diagnosis/gyro_stamps.hpp).
  const StampSpread& gyro_stamps() const { return stamps_; }
  // Matches: the gyro's samples as the model integrates them (cleaned, restamped).
  const std::vector<GyroSample>& gyro_samples() const { return gyro_; }
  // Whether effect parameters apply: gyro bias to gyro motion, lever arm to trajectories.
  bool has_gyro() const { return rec_.motion == MotionKind::Gyro; }

 private:
  struct Obs {
    double T, T_b;  // frame (frame_a) and frame_b timestamps
    int rank;
    Eigen::Vector3d X;          // landmarks: world point
    Eigen::Vector2d px, px_a;   // observed pixel (frame_b's), frame_a's
  };
  struct TrackCache;
  struct RayCache;
  struct MatchSetup;  // what a matches residual needs of the parameters, made once per call
  MatchSetup match_setup(const ModelParams& p) const;
  std::optional<Eigen::Vector2d> landmark_residual(const ModelParams& p, const Obs& o) const;
  // The gyro intervals the last frame_a and frame_b times fell in (GyroTrack's hints).
  struct TrackHints {
    size_t a = 0, b = 0;
  };
  // `row`: where to start the fixed point (its row NaN: the observed row); where it settled.
  std::optional<Eigen::Vector2d> match_residual(const MatchSetup& ms, const GyroTrack& track, int i, TrackHints& at,
                                                RowStart& row) const;
  // The residuals of idx as the rotation model leaves them (no translation taken out).
  std::vector<Eigen::Vector2d> rotation_residuals(const ModelParams& p, const std::vector<int>& idx, Settled* settled,
                                                  const Settled* near) const;
  // `r` (rotation_residuals of idx) with, under p's translation nuisance, the translation taken
  // out; what it took out goes to `keep` when given.
  std::vector<Eigen::Vector2d> translation_out(const ModelParams& p, const std::vector<int>& idx,
                                               std::vector<Eigen::Vector2d> r, TranslationFit* keep) const;
  const GyroTrack& track(const Eigen::Vector3d& bias, const Eigen::Vector3d& scale) const;

  const Recording& rec_;
  double t0_ = 0;  // T_0, the first frame's timestamp (spec "Time model")
  std::optional<PoseTrack> body_;
  std::optional<SampledTrajectory> body_slow_;  // the bracketing solver's fallback
  std::vector<GyroSample> gyro_;
  double max_gap_ = std::numeric_limits<double>::infinity();
  StampSpread stamps_;
  // Shared with the models seen through another gyro record (the stabiliser's test builds
  // dozens over a minute's 200 000 observations).
  std::shared_ptr<std::vector<Obs>> obs_ = std::make_shared<std::vector<Obs>>();
  std::unique_ptr<TrackCache> tracks_;
  std::unique_ptr<RayCache> rays_;
};

// The camera and time model that `p` describes.
LandmarkSetup landmark_setup(const NominalModel& n, const ModelParams& p);
// The lens family `p` describes (the nominal one, or the other with lens_model), and its lens.
LensModel lens_family(const NominalModel& n, const ModelParams& p);
Distortion lens_of(const NominalModel& n, const ModelParams& p);
// K1..K4 of `p` set to lens d's terms (k1, k2, k3, k4).
void set_lens_terms(ModelParams& p, const Distortion& d);
// Exp(r) of the mount rotation (the identity when r is zero).
Eigen::Matrix3d mount_of(const ModelParams& p);

}  // namespace rsd::dsp
