// Online self-calibration (docs/online-calibration.md): the camera-IMU time offset, the line
// delay and the gyro bias (and, when the motion shows it, the IMU's mount rotation), estimated
// while the camera runs from feature matches between consecutive raw frames and the raw gyro
// stream, over a sliding window.
//
// Each update fits the window with the diagnosis's own model (dsp/diagnosis/model.hpp: a
// frame_b pixel against the transfer of its frame_a pixel through the gyro's rotation between
// the two rows' capture times, recording-v1's "Matches"), so that the estimate and an offline
// rsd-diagnose of the same data mean the same numbers. The model needs rotation: without it
// neither the offset nor the line delay changes any prediction, so a window whose measured
// rate is too small (or whose matches are too few) is not fitted and the last estimate is held.
// The fits of successive windows are combined by a Kalman filter per value, so the estimate
// sharpens beyond what one window holds and follows slow drift; a fit far from it is a step.
//
// Thread contract: none of its own. One thread owns an estimator (the daemon's estimator
// thread); it allocates, and is never on the hot path.
#pragma once

#include <Eigen/Core>
#include <array>
#include <deque>
#include <string>
#include <vector>

#include "dsp/core/line_or_step.hpp"
#include "dsp/diagnosis/model.hpp"
#include "dsp/observation/recording.hpp"
#include "dsp/online/shutter.hpp"

namespace rsd::dsp {

// One value's standing: learning (fitted, not yet known to its tolerance), learned (known to it;
// it stands while later windows do not show it), held (not yet learned, and the windows do not
// show it: kept at its start or its last estimate), fixed (not
// estimated: the camera has no such value). `why` says why held or fixed.
enum class ValueStatus { Learning, Learned, Held, Fixed };
const char* to_string(ValueStatus v);
struct ValueNote {
  ValueStatus status = ValueStatus::Learning;
  std::string why;
};
struct OnlineNotes {
  ValueNote time_offset, line_delay, gyro_bias, mount_rotation, drift;
};

// converging: fitted, not yet stable; converged: the last fits agree within their sigmas and
// the sigmas are small; held: the window could not be fitted (too little rotation, too few
// matches), the last estimate is kept; rejected: the fit was implausible, the last estimate kept.
enum class OnlineState { Converging, Converged, Held, Rejected };
const char* to_string(OnlineState s);

// The calibration the estimator learns (or a 1-sigma of each of its values).
struct OnlineCalibration {
  double time_offset_s = 0;  // t_imu = t_camera + offset (calibration-v1's timeshift_cam_imu)
  double line_delay_s = 0;   // between consecutive rows read
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();  // rad/s, IMU axes: w = w_measured - bias
  // The IMU's mount beyond the nominal's: imu_to_camera = Exp(r) R_nominal (recording-v1's
  // mount_rotation), rad.
  Eigen::Vector3d mount_rotation = Eigen::Vector3d::Zero();
  // The camera clock's rate error against the IMU's (recording-v1's drift_ppm): the offset
  // grows by drift_ppm 1e-6 s each second of camera time from time_offset_s at offset_at_s
  // (camera clock, s; the estimator's: the last fitted window's middle).
  double drift_ppm = 0;
  double offset_at_s = 0;
  // The time offset at camera time t (it moves at the drift's rate).
  double offset_at(double t) const { return time_offset_s + drift_ppm * 1e-6 * (t - offset_at_s); }
};
inline constexpr int kOnlineValues = 8;  // offset, line delay, bias x y z, mount x y z (the drift apart)

// What the window of the last update held.
struct OnlineWindow {
  double t_begin = 0, t_end = 0;  // camera clock, first and last frame
  int frames = 0, matches = 0;    // matches: all in the window (the fit uses a spread subset)
  int fitted = 0, inliers = 0;    // matches fitted, and inliers at the fit
  int gyro_samples = 0;
  double rate_rms_rad_s = 0;      // RMS of the measured rate less the bias, over the window
  double rate_mean_rad_s = 0;     // |mean rate|
  double rate_spread_rad_s = 0;   // the rate's variation about its mean, second principal axis
  double residual_px = 0;         // robust per-coordinate sigma of the residuals at the fit
  double parallax_share = 0;      // residual share a translation explained (then taken out; 0: none)
};

struct OnlineEstimate {
  OnlineCalibration value, sigma;  // sigma: zero until a fit gave one
  OnlineState state = OnlineState::Converging;
  OnlineWindow window;
  bool converged = false;          // the value is a converged one (also while held or rejected)
  bool mount_known = false;        // the mount rotation's sigmas are small (the motion showed it)
  int updates = 0;                 // updates so far
  std::string reason;              // why held or rejected ("" otherwise)
  Shutter shutter = Shutter::Rolling;  // what the estimator was told
  RowsSeen rows = RowsSeen::Undecided;  // what the frames have shown (rolling when told so)
  OnlineNotes notes;               // which values are learned, which are held or fixed, and why
};

struct OnlineEstimatorOptions {
  double window_s = 2;             // the sliding window (camera clock)
  double min_rate_rad_s = 0.15;    // RMS angular rate below which the window is held
  int min_matches = 150;
  int fit_matches = 2500;          // at most this many matches in a fit, spread over the window
  double search_s = 0.05;          // the offset's grid search (+-, 0.25 ms steps) until converged
  // The fits are combined over time (a Kalman filter per value: the calibration a random walk
  // of these rates, per square root of a second), so that the estimate gathers more data than
  // one window holds; a fit further than `step_sigmas` combined sigmas from the estimate is a
  // step (the clock jumped, the firmware changed) once a window that starts a whole window
  // later still says so: that value restarts from the later fit. Until then the estimate is
  // held, so a glitch shorter than a window (which the overlapping windows all see) passes.
  double offset_walk_s = 2e-5;        // s/sqrt(s)
  double line_delay_walk = 2e-4;      // relative, 1/sqrt(s)
  double bias_walk_rad_s = 5e-5;      // rad/s/sqrt(s)
  double mount_walk_rad = 1e-5;       // rad/sqrt(s)
  // The clock drift (issue 36): the offset filter carries the offset's rate of change, so a long
  // flight's offset follows the camera crystal's rate error instead of trailing it in steps.
  // Until the fits span drift_span_s the drift stays at its start (a state file's, or 0) and the
  // offset is filtered alone: a rate fitted over seconds would be known to tens of ppm and widen
  // the offset's sigma beyond its tolerance. Then a straight line through those fits starts it.
  double drift_span_s = 30;
  double max_drift_ppm = 300;         // a crystal's rate error is within about 100 ppm: beyond, not taken
  double drift_walk_ppm = 0.05;       // ppm/sqrt(s): temperature moves the rate slowly
  double step_sigmas = 5;
  // Converged: the estimate's sigmas at most these (line delay: relative) over `settle`
  // updates in a row without a step.
  double converged_offset_sigma_s = 1.5e-4;
  double converged_line_delay_sigma = 0.008;
  double converged_bias_sigma = 7e-4;
  double converged_mount_sigma_rad = 1e-3;  // the mount rotation is known below this
  double learned_drift_sigma_ppm = 5;       // the drift is learned below this (it never holds back convergence)
  double mount_min_spread_rad_s = 0.3;       // rate variation about two axes needed to fit the mount
  int settle = 2;
  // A window whose fit sigma of a value exceeds this many times its converged sigma does not
  // move it (the motion does not show it: a bias while the camera translates past a near scene).
  double unobservable = 10;
  double max_residual_px = 3;      // a robust residual sigma above this: rejected
  double max_parallax_share = 0.5; // a translation explaining more of the residual: held
  double max_bias_rad_s = 0.3;     // |bias| per axis beyond this: rejected (no gyro is that bad)
  bool global_shutter = false;     // the camera has no line delay (Shutter::Global)
};

class OnlineEstimator {
 public:
  // `nominal`: the camera, its nominal line delay and readout, the IMU's mount (imu_to_camera);
  // its time offset and line delay are replaced by `start`'s. `start`'s line delay says the
  // shutter: positive, rolling; 0, unknown (or global, with opt.global_shutter). Throws
  // std::invalid_argument for options out of range (naming the option).
  // `gyro_scale`: the gyro's known scale (w = diag(scale) (w_measured - bias)), held.
  OnlineEstimator(const NominalModel& nominal, const OnlineCalibration& start, const OnlineEstimatorOptions& opt = {},
                  const Eigen::Vector3d& gyro_scale = Eigen::Vector3d::Ones());

  // A raw gyro measurement (IMU clock and axes, before any bias correction); in time order.
  void add_gyro(double t_imu, const Eigen::Vector3d& w_measured);
  // Matches a[k] in the frame whose first row was read at t_a -> b[k] in the next one, read at
  // t_b (camera clock); pixels of the raw (distorted) image, (0, 0) the top-left pixel's centre.
  void add_matches(double t_a, double t_b, const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b);

  // Drops what left the window, then fits it (or holds) and returns the new estimate.
  const OnlineEstimate& update();
  const OnlineEstimate& estimate() const { return est_; }

 private:
  struct Pair {
    double ta, tb;
    std::vector<Eigen::Vector2d> a, b;
  };
  void prune();
  OnlineWindow window_contents() const;
  Recording window_recording() const;
  // The diagnosis model's parameters at the estimate (its bias, the known gyro scale).
  ModelParams start_params(const NominalModel& n) const;
  // Holds the estimate, saying why.
  const OnlineEstimate& hold(OnlineState s, const std::string& why, const OnlineWindow& w);
  // A window's fit (at the window's middle, t) into the estimate; `with_mount`: the mount was fitted.
  void accept(const OnlineCalibration& fit, const OnlineCalibration& sigma, double t, bool with_mount);
  // The offset and the drift: predicted to t, then updated with the window's offset fit z
  // (variance r, counted `overlap` times); says whether z was a step, or one not yet confirmed.
  enum class OffsetUpdate { Updated, Pending, Stepped };
  OffsetUpdate accept_offset(double z, double r, double t, bool unseen, double overlap);
  // The scale of the line delay's random walk and tolerance: the estimate (rolling), at least
  // the frame period's share of a row (unknown: the estimate may be 0).
  double line_delay_scale(double fit) const;
  // Whether the rows' timing is decided, from the line delay's estimate and sigma.
  RowsSeen decide_rows(double tolerance) const;
  // Each value's note after a window's fit: its sigma against its tolerance, and whether the
  // window showed it.
  void note_values(const std::array<double, kOnlineValues>& sd, const std::array<double, kOnlineValues>& small,
                   const std::array<bool, kOnlineValues>& unseen, bool with_mount);

  NominalModel nominal_;
  OnlineEstimatorOptions opt_;
  Eigen::Vector3d gyro_scale_;
  OnlineEstimate est_;
  std::deque<Pair> pairs_;
  std::deque<GyroSample> gyro_;
  // The filter: per value (offset, line delay, bias x y z, mount x y z) the estimate and its variance.
  std::array<double, kOnlineValues> x_{}, var_{};
  // The drift (s/s) beside the offset x_[0]: their joint covariance (P(0,0) is var_[0]); the drift
  // fitted (drift_on_) once the offset fits (t, z, variance) span opt_.drift_span_s.
  double drift_ = 0;
  Eigen::Matrix2d offset_drift_cov_ = Eigen::Matrix2d::Zero();
  bool drift_on_ = false;
  std::vector<TimedValue> offset_fits_;  // (t, offset fit, its variance)
  // Fits the line through offset_fits_ and starts the drift from it at t, unless its slope is
  // beyond max_drift_ppm or a fit lies beyond 4 sigmas of it (a step, not a rate); whether started.
  bool start_drift(double t);
  // Per value, the time of the first fit beyond step_sigmas not yet confirmed (NaN: none);
  // whether the fit at t confirms it (a whole window later), noting it if it is the first.
  std::array<double, kOnlineValues> step_seen_at_;
  bool step_confirmed(int i, double t);
  double t_fit_ = 0;  // the last fit's window end
  int settled_ = 0;   // updates in a row with small sigmas and no step
  bool have_fit_ = false;
};

}  // namespace rsd::dsp
