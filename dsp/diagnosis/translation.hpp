// The translation nuisance of matches recordings: the part of each frame pair's residual that a
// camera translating past the scene explains, taken out so that effects are judged on what a
// translation cannot explain (docs/diagnosis.md, "Parallax").
//
// The translation is a smooth velocity in world axes, not a free vector per frame pair. Over a
// scene at one depth a sideways translation moves the image as a rotation does, so a free
// translation per pair would take up everything a rotation error leaves at the pair's rate: a
// clock offset (its residual follows the angular acceleration), a gyro bias, a focal length
// off under a pan. A vehicle's velocity over the scene's depth changes over about a second; in
// world axes it does not turn when the camera pans (the gyro carries that into camera axes), so
// a pan's residual, which a clock offset or a focal length leaves, stays for the effects.
//
// The scene is one plane (or, where it measurably is not, a depth per match about one): fixed in
// the world before a camera that stays before it (a wall or a ground before a hand-held camera:
// its tilt in each pair's camera follows the camera's turns), lying the same way before each
// pair's camera before one that travels past its scene by more than its distance (a drone's
// forward flight past a landscape that keeps its distance); translation_travel tells which.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

#include "dsp/diagnosis/gyro.hpp"

namespace rsd::dsp {

class DiagnosisModel;
struct ModelParams;

// The knot spacing of the velocity's cubic B-spline (s): it follows changes of velocity over
// depth slower than about 1 / (2 x spacing) Hz. A vehicle's velocity changes over seconds; a
// hand-held camera's shakes at 1-2 Hz, and a spline that cannot follow it leaves the shake for
// rotation effects to stand in for (a mount rotation of 2 degrees, from none, in the suite's
// `parallax + focal_length` on two seeds): translation_knot_spacing chooses among these,
// coarsest first.
constexpr double kTranslationKnotS = 0.5;
inline constexpr std::array<double, 3> kTranslationKnotsS = {kTranslationKnotS, 0.25, 0.125};
// A finer spline is taken when it lowers the robust scale of the residual by more than this
// share: fitting noise with the extra control points lowers it by about the ratio of their
// number to the observations' (a percent), a shake the coarser spline cannot follow by tens of
// percent.
inline constexpr double kFinerKnotsGain = 0.10;

// A gyro's stamps that the rates corrected (gyro_stamps.hpp) keep an error of their own: what
// the estimate could not take out, sqrt(jitter^2 - moved^2) for an estimate under a Gaussian
// spread (0.28-0.34 ms from 0.5 ms on test_gyro_stamps' hand's shake, whose measured errors after
// correction are 0.34-0.40 ms). The rotation between a pair's frames then errs by the rate's
// change over the pair times a shift of its own (measured on that shake, 85-89% of a pair's
// rotation error lies along the angular acceleration; a third without jitter). The velocity
// spline cannot follow an error independent from pair to pair, and it diluted the focal column:
// the walking phone's focal length came out 0.6% low on average over eight seeds
// (docs/diagnosis.md, "Gyro timestamp jitter"). So each frame pair has a time shift, that spread
// its prior, eliminated beside the velocity (remove_translation). Below kMinPairShiftS, the
// estimate's own floor on a gyro sampled on time (0.04 ms), there are none, and nothing changes.
inline constexpr double kMinPairShiftS = 5e-5;
// The prior spread of each frame pair's time shift (s) for the matches of `m`; 0: no shifts.
double pair_shift_sd(const DiagnosisModel& m);

// Removes from `r` (residuals of the observations `idx`, NaN for failed predictions) the flow of
// the camera's translation: per match, the flow over one plane (translation_flow, parallax.hpp,
// times the plane's inverse depth 1 + g . (x, y) at the normalised image coordinates) of
// u dt turned into camera axes by its pair's turn, dt the frames' time apart and u(t) =
// v(t) / depth at the mean time of the match's two rows (to first order about the pair's:
// u(t) + delta u'(t), the readout spreading a pair's matches over 25 ms of a shake), a cubic
// B-spline in world axes fitted to the inliers of every pair at once (four passes; an inlier lies within 4 robust
// scales of the current fit), the slope g (one for the recording: a ground ahead of a vehicle)
// from the second pass on. A pair needs no minimum of observations: the spline pools its
// neighbours. The camera's orientation at frame time T is
// track.camera_at(tm.motion_time(T)) mount_t, mount_t the transpose of the mount rotation
// (model.cpp, "Matches").
//
// With `depth_px` above zero each match's inverse depth is also its own: the plane's times
// (1 + e), e under a prior of spread s, eliminated per match, depth_px = noise / s
// (translation.cpp, own_depths; translation_depth_spread below measures s).
//
// With `world_plane` the plane is fixed in the world: its inverse depth a + g . b at each match's
// ray (b, a) turned, by the camera's orientation when its row was read, into the camera axes of
// the middle pair of its stretch of gyro (between gaps longer than the model's max_gyro_gap),
// taken once per grouping (translation.cpp, ScenePlane, plane_at);
// without, it lies the same way before every pair's first frame (a = 1, b = the normalised image
// coordinates). translation_travel chooses. `ray_cam` gives the rays of the world plane (the
// parameters' camera; the nominal one when null).
//
// With a jittered gyro (pair_shift_sd above zero) and `with_shifts`, each frame pair's rotation
// also shifts in time: per match the flow of the rotation (w_b - w_a) tau, w_a and w_b the
// camera's rate at the pair's two frames and tau one scalar per pair under the prior
// pair_shift_sd (against the noise the pass's robust scale gives), eliminated beside the
// velocity per pair; the slope is fitted to what the shifts leave. The prior's term is not in
// what is left (as the spline's penalty is not): the residual is the data's misfit alone.
//
// What it took out goes to `keep` when given (see TranslationFit). What `keep` held before is a
// hint: its grouping of the observations by frame pair is taken again when it grouped the same
// observations with the same residuals finite (a fit's trial points: a tenth of their time).
struct TranslationFit;
struct CameraModel;
void remove_translation(const DiagnosisModel& m, const std::vector<int>& idx, std::vector<Eigen::Vector2d>& r,
                        const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t,
                        double knot_s = kTranslationKnotS, TranslationFit* keep = nullptr, bool with_shifts = true,
                        double depth_px = 0, bool world_plane = false, const CameraModel* ray_cam = nullptr);

// What remove_translation settled on for one set of residuals: its observations by frame pair,
// the last pass's inliers and the scene's slope. remove_fitted_translation fits the velocity
// spline again in one pass with those held (at the parameters it is given: the pairs' turns
// follow the gyro, the mount and the clock), for the residuals of the same observations at
// nearby parameters, without the passes that chose them. The fits' Jacobian (fit.cpp) is taken
// so: a column then costs one pass over the analytic column of the rotation model's residuals
// (or over the residuals at a step, by differences), not four passes with their medians. What it leaves out is how the inliers (a step
// function) and the slope move with the parameters: a percent or two of a clock offset's or a
// line delay's column; a rotation over a tilted ground (a gyro bias, a mount) moves the image as
// the translation does, and the held slope misses up to a fifth of its change. The fits' trial
// steps use the exact residuals, so that costs iterations (a tenth more), not accuracy.
struct TranslationFit {
  struct State;
  std::shared_ptr<const State> state;  // empty: nothing was taken out
};
// As remove_translation, with `fit`'s inliers and slope (fitted on the same observations idx);
// without a fit, remove_translation itself. Throws std::invalid_argument when idx or `r` is not
// of the size `fit` was fitted to.
void remove_fitted_translation(const DiagnosisModel& m, const std::vector<int>& idx, std::vector<Eigen::Vector2d>& r,
                               const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t, double knot_s,
                               const TranslationFit& fit);

// The part of remove_fitted_translation that is linear in the residuals, taken out of every
// column of `cols` (2 x idx.size() rows: observation k's in rows 2k and 2k + 1) with one
// factorisation: the velocity spline fitted to each column as to residuals, with `fit`'s inliers
// and slope, at the pairs' turns of `track`, `tm`, `mount_t`. A Jacobian column by a parameter
// that moves neither the turns nor the matches' times (the intrinsics, the lens: not the line
// delay, the clock's offset or drift, the mount, the gyro) is so the column of remove_fitted_translation's
// residuals, exactly (fit.cpp). An observation whose column has a NaN is left out of the fit;
// nothing without `fit`'s state. Throws std::invalid_argument when idx or `cols` is not of the
// size `fit` was fitted to.
void remove_fitted_translation_from_columns(const DiagnosisModel& m, const std::vector<int>& idx, Eigen::MatrixXd& cols,
                                            const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t,
                                            double knot_s, const TranslationFit& fit);

// The knot spacing for the translation nuisance of `p` (its translation_nuisance on; the richest
// rotation fit, every applicable effect free, so that a finer spline is not asked to take what an
// effect explains) on the observations idx: kTranslationKnotsS in turn while the finer spline
// lowers the robust scale of the residuals by more than kFinerKnotsGain, and while the frame
// pairs hold it, two pairs per interval on average over the intervals that hold any (frames
// chosen in runs leave intervals between runs empty; a spline finer than its pairs is a free
// translation per pair, which takes up what a rotation error leaves: a clock offset, a focal length).
double translation_knot_spacing(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p);

// The scene's inverse depths spread about the plane's (relative) by less than this, or by an
// excess within kMinDepthSpreadZ standard errors of noise alone, or the translation moves the
// median match by less than the noise (a translation the nuisance fitted to what a rotation
// model left, not a camera's: nothing to measure depths by): the plane is taken as the scene.
// The suite's walls and grounds measure 0.00-0.05. The independent generator's flight past
// points 20-200 m away 0.55-0.58 (z 37-38, the median flow 1.4-1.6 noises), its phone shaken
// past points 2-30 m away 0.37-0.43 (z 30-37, 2.0-2.2); a rendered rotation-only scene whose
// tracker's errors looked like parallax 0.14 (z 0.3, 0.42: it named a mount under a gate by
// the spread alone); a shutter's shear beside a quarter of the image displaced 0.44 (z 18, but
// 0.38: under the own depths a gyro bias and a line delay 70% short came in its stead).
inline constexpr double kMinDepthSpread = 0.3;
inline constexpr double kMinDepthSpreadZ = 5.0;
// The relative spread of the scene's inverse depths about the translation nuisance's plane, for
// `p` (as translation_knot_spacing: the richest rotation fit, its knots chosen) on the
// observations idx: the residual's energy along each match's translation flow beyond its energy
// across it, over the flow's energy, from the matches whose flow exceeds the noise. Zero when
// one plane describes the scene (kMinDepthSpread, kMinDepthSpreadZ). With `ask_flow` false the
// rule on the median match's flow is not asked: the scene's spread however little each pair's
// translation moves its matches (the depth model the clock offset's sigma is asked against,
// uncertainty.cpp, widen_offset_sigma).
double translation_depth_spread(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p,
                                bool ask_flow = true);
// A plane fixed in the world stays before a camera that moves by less than its distance; a camera
// that travels towards the scene by more than this share of its distance (from the middle of the
// recording to either end) would have met any plane it saw, so what it sees is a landscape that
// keeps its distance (a drone's forward flight), and the plane lies the same way before every
// pair's camera. A hand shaking a camera by 5 cm before a wall 4 m away measures 0.15 (the
// spline's errors, added up over 20 s, included); the suite's drone 0.9-2.5 (8 m/s for 5 s, the
// scene 40 m or 15 m ahead).
inline constexpr double kWorldPlaneTravel = 0.5;
// How far the camera travels along the scene's plane's normal over the plane's distance, at most
// from the middle pair's time to any other pair's, under the translation nuisance of `p` (as
// translation_knot_spacing: the richest rotation fit, its knots chosen; the plane before each
// pair's camera) on the observations idx: the velocity spline's velocity over depth (world axes)
// integrated over the pairs' times along the plane's normal at the middle pair. A plane fixed in
// the world (ModelParams::translation_world_plane) when below kWorldPlaneTravel.
double translation_travel(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p);

// The own depths' prior scale for a measured spread (ModelParams::translation_depth_px): the
// noise over kOwnDepthPriorWidth times the spread; 0 (one plane) when the spread is 0.
double own_depth_px(double sigma_px, double spread);

}  // namespace rsd::dsp
