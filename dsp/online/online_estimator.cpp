#include "dsp/online/online_estimator.hpp"

#include <algorithm>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/model.hpp"
#include "dsp/diagnosis/offset_search.hpp"
#include "dsp/diagnosis/parallax.hpp"
#include "dsp/diagnosis/robust_stats.hpp"
#include "dsp/diagnosis/uncertainty.hpp"

namespace rsd::dsp {

const char* to_string(OnlineState s) {
  switch (s) {
    case OnlineState::Converging: return "converging";
    case OnlineState::Converged: return "converged";
    case OnlineState::Held: return "held";
    case OnlineState::Rejected: return "rejected";
  }
  return "?";
}

const char* to_string(ValueStatus v) {
  switch (v) {
    case ValueStatus::Learning: return "learning";
    case ValueStatus::Learned: return "learned";
    case ValueStatus::Held: return "held";
    case ValueStatus::Fixed: return "fixed";
  }
  return "?";
}

namespace {

// The parameters the estimator frees, in the order of its values and variances.
const std::vector<Param> kFree = {Param::TimeOffset, Param::LineDelay, Param::BiasX,  Param::BiasY,
                                  Param::BiasZ,      Param::MountX,    Param::MountY, Param::MountZ};
constexpr int kBias = 2, kMount = 5;  // the first bias and mount values

void require(bool ok, const char* option, const char* rule) {
  if (!ok) throw std::invalid_argument(std::string("online calibration: ") + option + " must be " + rule);
}

using Values = std::array<double, kOnlineValues>;

Values values(const OnlineCalibration& c) {
  return {c.time_offset_s,  c.line_delay_s,        c.gyro_bias.x(),       c.gyro_bias.y(),
          c.gyro_bias.z(),  c.mount_rotation.x(),  c.mount_rotation.y(),  c.mount_rotation.z()};
}

OnlineCalibration calibration(const Values& v) {
  return {v[0], v[1], {v[2], v[3], v[4]}, {v[5], v[6], v[7]}};
}

OnlineCalibration from_params(const ModelParams& p) {
  Values v{};
  for (int i = 0; i < kOnlineValues; ++i) v[i] = p[kFree[i]];
  return calibration(v);
}

OnlineCalibration from_variances(const Eigen::VectorXd& var) {
  Values v{};
  for (int i = 0; i < kOnlineValues; ++i) v[i] = std::sqrt(std::max(var[i], 0.0));
  return calibration(v);
}

}  // namespace

OnlineEstimator::OnlineEstimator(const NominalModel& nominal, const OnlineCalibration& start,
                                 const OnlineEstimatorOptions& opt, const Eigen::Vector3d& gyro_scale)
    : nominal_(nominal), opt_(opt), gyro_scale_(gyro_scale) {
  step_seen_at_.fill(std::numeric_limits<double>::quiet_NaN());
  require(opt.window_s > 0, "window_s", "positive");
  require(opt.min_rate_rad_s >= 0, "min_rate_rad_s", "zero or positive");
  require(opt.min_matches >= 10, "min_matches", "at least 10");
  require(opt.fit_matches >= opt.min_matches, "fit_matches", "at least min_matches");
  require(opt.search_s >= 0, "search_s", "zero or positive");
  require(opt.settle >= 1, "settle", "at least 1");
  require(opt.step_sigmas > 0, "step_sigmas", "positive");
  require(opt.offset_walk_s >= 0 && opt.line_delay_walk >= 0 && opt.bias_walk_rad_s >= 0 && opt.drift_walk_ppm >= 0,
          "the random walks", "zero or positive");
  require(opt.drift_span_s >= opt.window_s, "drift_span_s", "at least window_s");
  require(opt.max_drift_ppm > 0 && opt.max_drift_ppm <= 1000, "max_drift_ppm", "within (0, 1000]");
  require(start.line_delay_s >= 0, "the starting line delay", "zero or positive");
  require(!(opt.global_shutter && start.line_delay_s > 0), "the starting line delay of a global shutter", "0");
  require(start.line_delay_s > 0 || (nominal.frame_rate_hz > 0 && nominal.cam.height > 0),
          "the camera's frame rate and height (they bound an unknown line delay)", "positive");
  est_.value = start;
  drift_ = start.drift_ppm * 1e-6;
  est_.notes.drift = {ValueStatus::Learning, ""};
  est_.shutter = opt.global_shutter ? Shutter::Global : start.line_delay_s > 0 ? Shutter::Rolling : Shutter::Unknown;
  est_.rows = est_.shutter == Shutter::Rolling ? RowsSeen::Rolling : est_.shutter == Shutter::Global ? RowsSeen::Global : RowsSeen::Undecided;
  if (est_.shutter == Shutter::Global) est_.notes.line_delay = {ValueStatus::Fixed, "a global shutter: the rows are read at once"};
  est_.notes.mount_rotation = {ValueStatus::Held, "the rate has not yet varied about two axes"};
}

double OnlineEstimator::line_delay_scale(double fit) const {
  const double ld = have_fit_ ? x_[1] : fit;
  if (est_.shutter == Shutter::Rolling) return ld;
  // A row's share of the frame period: the longest line delay a camera can have.
  const double row_period = 1.0 / (nominal_.frame_rate_hz * nominal_.cam.height);
  return std::max(ld, row_period);
}

RowsSeen OnlineEstimator::decide_rows(double tolerance) const {
  if (est_.shutter != Shutter::Unknown) return est_.rows;
  const double ld = x_[1], sd = std::sqrt(var_[1]);
  if (ld > 3 * sd) return RowsSeen::Rolling;
  return sd <= tolerance ? RowsSeen::Global : RowsSeen::Undecided;
}

void OnlineEstimator::add_gyro(double t_imu, const Eigen::Vector3d& w_measured) {
  if (!gyro_.empty() && t_imu < gyro_.back().t) return;  // out of order: the caller's stream restarted
  gyro_.push_back({t_imu, w_measured});
}

void OnlineEstimator::add_matches(double t_a, double t_b, const std::vector<Eigen::Vector2d>& a,
                                  const std::vector<Eigen::Vector2d>& b) {
  if (a.size() != b.size()) throw std::invalid_argument("online calibration: matches a and b differ in length");
  if (!(t_b > t_a) || (!pairs_.empty() && t_a < pairs_.back().tb)) return;  // not the next pair in time
  pairs_.push_back({t_a, t_b, a, b});
}

void OnlineEstimator::prune() {
  if (pairs_.empty()) return;
  const double t_end = pairs_.back().tb;
  while (pairs_.front().ta < t_end - opt_.window_s) pairs_.pop_front();
  // Gyro a little before the window's first frame on the IMU clock, within any offset searched.
  const double keep = pairs_.front().ta + est_.value.time_offset_s - opt_.search_s - 0.2;
  while (!gyro_.empty() && gyro_.front().t < keep) gyro_.pop_front();
}

OnlineWindow OnlineEstimator::window_contents() const {
  OnlineWindow w;
  if (pairs_.empty()) return w;
  w.t_begin = pairs_.front().ta, w.t_end = pairs_.back().tb;
  double prev = -1;
  for (const Pair& p : pairs_) {
    w.frames += (p.ta == prev ? 1 : 2);
    prev = p.tb;
    w.matches += static_cast<int>(p.a.size());
  }
  const double off = est_.value.time_offset_s;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sum2 = Eigen::Matrix3d::Zero();
  for (const GyroSample& g : gyro_)
    if (g.t >= w.t_begin + off && g.t <= w.t_end + off) {
      const Eigen::Vector3d r = g.w - est_.value.gyro_bias;
      ++w.gyro_samples, sum += r, sum2 += r * r.transpose();
    }
  if (w.gyro_samples == 0) return w;
  const double n = w.gyro_samples;
  const Eigen::Vector3d mean = sum / n;
  w.rate_rms_rad_s = std::sqrt(sum2.trace() / n);
  w.rate_mean_rad_s = mean.norm();
  // The rate's variation about its mean: the second largest of its principal spreads.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(sum2 / n - mean * mean.transpose());
  w.rate_spread_rad_s = std::sqrt(std::max(eig.eigenvalues()[1], 0.0));  // ascending order
  return w;
}

Recording OnlineEstimator::window_recording() const {
  Recording rec;
  rec.kind = ObservationKind::Matches;
  rec.motion = MotionKind::Gyro;
  rec.nominal = nominal_;
  rec.nominal.time.time_offset_s = est_.value.time_offset_s;
  rec.nominal.time.line_delay_s = est_.value.line_delay_s;
  std::map<double, int> frame;
  for (const Pair& p : pairs_) frame.try_emplace(p.ta, 0), frame.try_emplace(p.tb, 0);
  int id = 0;
  for (auto& [t, f] : frame) f = id++, rec.frames.push_back({f, t});
  size_t total = 0;
  for (const Pair& p : pairs_) total += p.a.size();
  // Every n-th match, so that the subset spreads over the whole window.
  const size_t every = std::max<size_t>(1, (total + opt_.fit_matches - 1) / opt_.fit_matches);
  size_t k = 0;
  for (const Pair& p : pairs_)
    for (size_t i = 0; i < p.a.size(); ++i, ++k)
      if (k % every == 0) rec.matches.push_back({frame.at(p.ta), p.a[i], frame.at(p.tb), p.b[i]});
  rec.gyro.assign(gyro_.begin(), gyro_.end());
  return rec;
}

const OnlineEstimate& OnlineEstimator::hold(OnlineState s, const std::string& why, const OnlineWindow& w) {
  est_.state = s;
  est_.reason = why;
  est_.window = w;
  // Every value not yet learned is held, for the window's reason (a learned one stands).
  for (ValueNote* n : {&est_.notes.time_offset, &est_.notes.line_delay, &est_.notes.gyro_bias, &est_.notes.mount_rotation, &est_.notes.drift})
    if (n->status != ValueStatus::Fixed && n->status != ValueStatus::Learned) *n = {ValueStatus::Held, why};
  return est_;
}

void OnlineEstimator::accept(const OnlineCalibration& fit, const OnlineCalibration& sigma, double t, bool with_mount) {
  const Values z = values(fit), s = values(sigma), start = values(est_.value);
  const double ld = line_delay_scale(fit.line_delay_s);
  // Per value: its random walk per square root of a second, and the sigma it converges to.
  const double b = opt_.bias_walk_rad_s, m = opt_.mount_walk_rad;
  const Values walk = {opt_.offset_walk_s, opt_.line_delay_walk * ld, b, b, b, m, m, m};
  const double sb = opt_.converged_bias_sigma, sm = opt_.converged_mount_sigma_rad;
  const Values small = {opt_.converged_offset_sigma_s, opt_.converged_line_delay_sigma * ld, sb, sb, sb, sm, sm, sm};
  const double dt = have_fit_ ? std::max(t - t_fit_, 1e-3) : 0;
  // Successive windows overlap: a fit shares most of its data with the one before, so it
  // carries the information of only the new part of its window.
  const double overlap = have_fit_ ? std::max(1.0, opt_.window_s / dt) : 1.0;
  bool stepped = false, pending = false;
  std::array<bool, kOnlineValues> unseen{};  // values this window says next to nothing of
  const bool global = est_.shutter == Shutter::Global;
  for (int i = 0; i < kOnlineValues; ++i) {
    if (i == 1 && global) {  // no line delay: 0, known exactly
      x_[i] = 0, var_[i] = 0;
      continue;
    }
    if (i == 0) {
      unseen[0] = s[0] > opt_.unobservable * small[0];
      const OffsetUpdate u = accept_offset(unseen[0] && !have_fit_ ? start[0] : z[0], s[0] * s[0], t, unseen[0], overlap);
      stepped = stepped || u == OffsetUpdate::Stepped, pending = pending || u == OffsetUpdate::Pending;
      continue;
    }
    const double prior = var_[i] + walk[i] * walk[i] * dt, r = s[i] * s[i], nu = z[i] - x_[i];
    if (s[i] > opt_.unobservable * small[i]) {  // this window says next to nothing of it: held
      const double known = opt_.unobservable * small[i];  // what a start is taken to be good to
      if (!have_fit_) x_[i] = start[i], var_[i] = std::min(r, known * known);
      else var_[i] = prior;
      unseen[i] = true;
    } else if (!have_fit_ || nu * nu > opt_.step_sigmas * opt_.step_sigmas * (prior + r)) {
      // The first fit, or a value whose fit lies beyond step_sigmas of the estimate: a step once
      // confirmed, restarting from the fit; held until then.
      if (!have_fit_ || step_confirmed(i, t)) {
        stepped = stepped || have_fit_;
        x_[i] = z[i], var_[i] = r;
      } else {
        var_[i] = prior, pending = true;
      }
    } else {
      const double k = prior / (prior + r * overlap);
      x_[i] += k * nu, var_[i] = (1 - k) * prior;
      step_seen_at_[i] = std::numeric_limits<double>::quiet_NaN();
    }
  }
  have_fit_ = true, t_fit_ = t;
  const bool unseen_bias = unseen[kBias] || unseen[kBias + 1] || unseen[kBias + 2];
  Values sd{};
  for (int i = 0; i < kOnlineValues; ++i) sd[i] = std::sqrt(var_[i]);
  est_.value = calibration(x_), est_.sigma = calibration(sd);
  est_.value.drift_ppm = drift_ * 1e6, est_.sigma.drift_ppm = std::sqrt(offset_drift_cov_(1, 1)) * 1e6;
  est_.value.offset_at_s = t;
  // Converged: the offset, the line delay and the bias known to their thresholds; a bias the
  // motion does not show (the camera translates) is held and does not keep the others from
  // converging. The mount rotation refines when the motion shows it (rotation about several
  // axes) and never holds the rest back.
  bool settled = true;
  for (int i = 0; i < kMount; ++i) settled = settled && (sd[i] <= small[i] || (i >= kBias && unseen_bias));
  est_.mount_known = sd[kMount] <= sm && sd[kMount + 1] <= sm && sd[kMount + 2] <= sm;
  settled_ = settled && !stepped ? settled_ + 1 : 0;
  est_.state = settled_ >= opt_.settle ? OnlineState::Converged : OnlineState::Converging;
  est_.converged = est_.state == OnlineState::Converged;
  est_.reason = stepped   ? "a step: restarted from this window's fit"
                : pending ? "a fit far from the estimate: held until a window a whole window later confirms a step"
                : unseen_bias ? "gyro bias held: this window does not show it"
                              : "";
  est_.rows = decide_rows(small[1]);
  note_values(sd, small, unseen, with_mount);
}

OnlineEstimator::OffsetUpdate OnlineEstimator::accept_offset(double z, double r, double t, bool unseen, double overlap) {
  Eigen::Matrix2d& P = offset_drift_cov_;
  if (!have_fit_) {  // the first fit: the drift held at its start (variance 0) until it is fitted
    const double known = opt_.unobservable * opt_.converged_offset_sigma_s;  // what a start is taken to be good to
    x_[0] = z;
    P << (unseen ? std::min(r, known * known) : r), 0, 0, 0;
    var_[0] = P(0, 0);
    if (!unseen) offset_fits_.push_back({t, z, r});
    return OffsetUpdate::Updated;
  }
  // Predicted to t: the offset moves at the drift's rate; both walk.
  const double dt = std::max(t - t_fit_, 1e-3);
  Eigen::Matrix2d F;
  F << 1, dt, 0, 1;
  const double qd = drift_on_ ? opt_.drift_walk_ppm * 1e-6 : 0.0;
  P = F * P * F.transpose() + Eigen::Vector2d(opt_.offset_walk_s * opt_.offset_walk_s * dt, qd * qd * dt).asDiagonal().toDenseMatrix();
  x_[0] += drift_ * dt;
  bool stepped = false;
  const double nu = z - x_[0];
  if (unseen) {
    // held: the prediction stands
  } else if (nu * nu > opt_.step_sigmas * opt_.step_sigmas * (P(0, 0) + r)) {
    // Before the drift is fitted, an offset that walked away from its estimate may be a rate: if
    // a line through the fits so far takes this one too, the drift starts from it now.
    if (!drift_on_ && offset_fits_.size() >= 5) {
      offset_fits_.push_back({t, z, r * overlap});
      if (start_drift(t)) {
        var_[0] = P(0, 0);
        return OffsetUpdate::Updated;
      }
    }
    if (!step_confirmed(0, t)) {  // held: the prediction stands until a later window confirms
      var_[0] = P(0, 0);
      return OffsetUpdate::Pending;
    }
    // A step (the clock jumped): the offset restarts from the fit; the drift, a rate, stands.
    stepped = true;
    x_[0] = z;
    P(0, 0) = r, P(0, 1) = P(1, 0) = 0;
    offset_fits_.clear();
  } else {
    const Eigen::Vector2d k = P.col(0) / (P(0, 0) + r * overlap);
    x_[0] += k[0] * nu, drift_ += k[1] * nu;
    P -= k * P.row(0);
    step_seen_at_[0] = std::numeric_limits<double>::quiet_NaN();
  }
  if (!drift_on_ && !unseen) {
    offset_fits_.push_back({t, z, r * overlap});
    if (t - offset_fits_.front().t >= opt_.drift_span_s) start_drift(t);
  }
  var_[0] = P(0, 0);
  return stepped ? OffsetUpdate::Stepped : OffsetUpdate::Updated;
}

bool OnlineEstimator::step_confirmed(int i, double t) {
  double& seen = step_seen_at_[i];
  if (std::isnan(seen)) {
    seen = t;
    return false;
  }
  if (t - seen < opt_.window_s) return false;
  seen = std::numeric_limits<double>::quiet_NaN();
  return true;
}

// The drift's start: a straight line through the offset fits so far (each weighted by its
// variance), the offset and the drift at t with their covariance. A rate beyond a crystal's is
// not taken: the fits start again.
bool OnlineEstimator::start_drift(double t) {
  const WeightedLine line = fit_line(offset_fits_, t);
  const bool fits = line.valid && std::abs(line.slope) <= opt_.max_drift_ppm * 1e-6 && line.worst_sigmas <= 4;
  offset_fits_.clear();
  if (!fits) return false;
  x_[0] = line.at, drift_ = line.slope;
  offset_drift_cov_ = line.covariance;
  drift_on_ = true;
  return true;
}

void OnlineEstimator::note_values(const Values& sd, const Values& small, const std::array<bool, kOnlineValues>& unseen,
                                  bool with_mount) {
  // A group of values (the bias's three axes, the mount's) is learned when every one is known to
  // its tolerance (whatever this window showed: the estimate stands); otherwise held when this
  // window did not show one of them, else learning.
  auto note = [&](int first, int count, const char* unseen_why) {
    bool learned = true, held = false;
    for (int i = first; i < first + count; ++i) learned = learned && sd[i] <= small[i], held = held || unseen[i];
    if (learned) return ValueNote{ValueStatus::Learned, ""};
    return held ? ValueNote{ValueStatus::Held, unseen_why} : ValueNote{ValueStatus::Learning, ""};
  };
  est_.notes.time_offset = note(0, 1, "this window does not show it");
  est_.notes.drift = !drift_on_ ? ValueNote{ValueStatus::Held, "fitted once the offset's fits span " +
                                                                    std::to_string(static_cast<int>(opt_.drift_span_s)) + " s"}
                     : est_.sigma.drift_ppm <= opt_.learned_drift_sigma_ppm ? ValueNote{ValueStatus::Learned, ""}
                     : unseen[0] ? ValueNote{ValueStatus::Held, "this window does not show the offset"}
                                 : ValueNote{ValueStatus::Learning, ""};
  if (est_.shutter != Shutter::Global) est_.notes.line_delay = note(1, 1, "this window does not show it");
  est_.notes.gyro_bias = note(kBias, 3, "this window does not show it (the camera translates)");
  est_.notes.mount_rotation = est_.mount_known ? ValueNote{ValueStatus::Learned, ""}
                              : with_mount        ? note(kMount, 3, "this window does not show it")
                                                  : ValueNote{ValueStatus::Held, "the rate does not vary about two axes"};
}

namespace {

// One window's fit: the parameters, their variances (nullopt: not identifiable), the residual
// statistics, and whether a translation of the camera had to be taken out.
struct WindowFit {
  ModelParams params;
  std::optional<Eigen::VectorXd> var;
  RobustStats stats;
  double parallax_share = 0;  // 0: no parallax
};

// Fits the window's matches from p: a grid search of the offset first when asked, then the
// robust fit of the values (the mount rotation's only `with_mount`). A camera that also translates past a near scene moves the
// matches by a flow the rotation-only model reads as rotation; where the residuals show that
// parallax (dsp/diagnosis/parallax.hpp), each frame pair's translation flow is taken out and
// the fit repeated. `parallax_share`: the share of the residual energy the translation explains.
WindowFit fit_window(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p0, double search_s,
                     bool with_mount, bool with_line_delay) {
  ModelParams p = p0;
  if (search_s > 0) {
    const std::vector<int> sub = subsample(idx, 300);
    const double guess = std::clamp(robust_stats(m.residuals(p, sub)).scale_px, 0.2, 5.0);
    p[Param::TimeOffset] = refine_time_offset(m, sub, p, guess, search_s);
  }
  const double sigma_px = std::clamp(robust_stats(m.residuals(p, idx)).scale_px, 0.05, 10.0);
  std::vector<int> which;  // indices into kFree of the values fitted
  for (int i = 0; i < (with_mount ? kOnlineValues : kMount); ++i)
    if (i != 1 || with_line_delay) which.push_back(i);
  std::vector<Param> fitted;
  for (int i : which) fitted.push_back(kFree[i]);
  ParamMask free;
  for (Param q : fitted) free.set(static_cast<int>(q));
  WindowFit w;
  w.params = fit_params(m, idx, p, free, sigma_px);
  if (const Parallax px = parallax_signal(m, w.params, idx); px.clear()) {
    w.parallax_share = px.share;
    w.params.translation_nuisance = true;
    w.params = fit_params(m, idx, w.params, free, sigma_px);
  }
  w.stats = robust_stats(m.residuals(w.params, idx));
  if (const auto v = parameter_variances(m, w.params, fitted, idx)) {
    w.var = Eigen::VectorXd::Constant(kOnlineValues, std::numeric_limits<double>::infinity());  // not fitted: unknown
    for (size_t j = 0; j < which.size(); ++j) (*w.var)[which[j]] = (*v)[static_cast<Eigen::Index>(j)];
  }
  return w;
}

}  // namespace

ModelParams OnlineEstimator::start_params(const NominalModel& n) const {
  ModelParams p = nominal_params(n);
  const Values v = values(est_.value);
  for (int i = 0; i < kOnlineValues; ++i) p[kFree[i]] = v[i];
  p[Param::ScaleX] = gyro_scale_.x(), p[Param::ScaleY] = gyro_scale_.y(), p[Param::ScaleZ] = gyro_scale_.z();
  return p;
}

const OnlineEstimate& OnlineEstimator::update() {
  ++est_.updates;
  prune();
  OnlineWindow w = window_contents();
  if (w.matches < opt_.min_matches)
    return hold(OnlineState::Held, "too few matches (" + std::to_string(w.matches) + ")", w);
  if (w.gyro_samples == 0) return hold(OnlineState::Held, "no gyro measurements in the window", w);
  if (w.rate_rms_rad_s < opt_.min_rate_rad_s)
    return hold(OnlineState::Held, "too little rotation (" + std::to_string(w.rate_rms_rad_s) + " rad/s RMS)", w);
  try {
    const Recording rec = window_recording();
    const DiagnosisModel m(rec);
    std::vector<int> idx(m.size());
    for (int i = 0; i < m.size(); ++i) idx[i] = i;
    // Until converged the offset may be far off (a new rig, a step): a grid search first.
    const double search = est_.converged ? 0.0 : opt_.search_s;
    // The mount rotation turns the measured rate: a constant rate's turn is a constant offset,
    // the same as a bias. Only a rate that varies about two axes or more, by more than its mean,
    // tells them apart; otherwise the mount is held as it is.
    const bool with_mount = w.rate_spread_rad_s >= opt_.mount_min_spread_rad_s && w.rate_spread_rad_s >= 0.5 * w.rate_mean_rad_s;
    const WindowFit f = fit_window(m, idx, start_params(rec.nominal), search, with_mount, est_.shutter != Shutter::Global);
    w.fitted = f.stats.observations, w.inliers = f.stats.observations - f.stats.outliers;
    w.residual_px = f.stats.scale_px, w.parallax_share = f.parallax_share;
    OnlineCalibration v = from_params(f.params);
    // A line delay fitted at its bound 0 may come back a rounding error below it.
    if (est_.shutter != Shutter::Rolling && v.line_delay_s < 0 && v.line_delay_s > -1e-6 * line_delay_scale(0)) v.line_delay_s = 0;
    // Over a near scene a translation's flow and the rotation's are nearly the same field: when
    // it dominates, the rotation-only model would bend the calibration to explain it.
    if (f.parallax_share > opt_.max_parallax_share)
      return hold(OnlineState::Held, "the camera translates past a near scene (parallax, " +
                                         std::to_string(static_cast<int>(100 * f.parallax_share)) + "% of the residual)", w);
    if (f.stats.scale_px > opt_.max_residual_px)
      return hold(OnlineState::Rejected, "residuals too large (" + std::to_string(f.stats.scale_px) + " px)", w);
    if (2 * w.inliers < w.fitted) return hold(OnlineState::Rejected, "fewer than half the matches fit", w);
    const bool line_delay_ok = est_.shutter == Shutter::Rolling ? v.line_delay_s > 0 : v.line_delay_s >= 0;
    if (!line_delay_ok || v.gyro_bias.cwiseAbs().maxCoeff() > opt_.max_bias_rad_s)
      return hold(OnlineState::Rejected, "implausible fit (line delay or gyro bias)", w);
    if (!f.var) return hold(OnlineState::Rejected, "parameters not identifiable from this window", w);
    est_.window = w;
    // A window's offset fit holds at its middle (its pairs' offsets averaged): with a drift, the
    // estimate's time is that middle.
    accept(v, from_variances(*f.var), 0.5 * (w.t_begin + w.t_end), with_mount);
    return est_;
  } catch (const std::exception& e) {
    return hold(OnlineState::Rejected, e.what(), w);
  }
}

}  // namespace rsd::dsp
