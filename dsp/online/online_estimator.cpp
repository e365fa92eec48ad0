#include "dsp/online/online_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/model.hpp"
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

namespace {

// The parameters the estimator frees, in the order of its variances.
const std::vector<Param> kFree = {Param::TimeOffset, Param::LineDelay, Param::BiasX, Param::BiasY, Param::BiasZ};

void require(bool ok, const char* option, const char* rule) {
  if (!ok) throw std::invalid_argument(std::string("online calibration: ") + option + " must be " + rule);
}

OnlineCalibration from_params(const ModelParams& p) {
  return {p[Param::TimeOffset], p[Param::LineDelay], {p[Param::BiasX], p[Param::BiasY], p[Param::BiasZ]}};
}

OnlineCalibration from_variances(const Eigen::VectorXd& v) {
  const Eigen::VectorXd s = v.cwiseMax(0).cwiseSqrt();
  return {s[0], s[1], {s[2], s[3], s[4]}};
}

std::array<double, 5> values(const OnlineCalibration& c) {
  return {c.time_offset_s, c.line_delay_s, c.gyro_bias.x(), c.gyro_bias.y(), c.gyro_bias.z()};
}

OnlineCalibration calibration(const std::array<double, 5>& v) { return {v[0], v[1], {v[2], v[3], v[4]}}; }

}  // namespace

OnlineEstimator::OnlineEstimator(const NominalModel& nominal, const OnlineCalibration& start,
                                 const OnlineEstimatorOptions& opt)
    : nominal_(nominal), opt_(opt) {
  require(opt.window_s > 0, "window_s", "positive");
  require(opt.min_rate_rad_s >= 0, "min_rate_rad_s", "zero or positive");
  require(opt.min_matches >= 10, "min_matches", "at least 10");
  require(opt.fit_matches >= opt.min_matches, "fit_matches", "at least min_matches");
  require(opt.search_s >= 0, "search_s", "zero or positive");
  require(opt.settle >= 1, "settle", "at least 1");
  require(opt.step_sigmas > 0, "step_sigmas", "positive");
  require(opt.offset_walk_s >= 0 && opt.line_delay_walk >= 0 && opt.bias_walk_rad_s >= 0, "the random walks", "zero or positive");
  require(start.line_delay_s > 0, "the starting line delay", "positive");
  nominal_.time.time_offset_s = start.time_offset_s;
  nominal_.time.line_delay_s = start.line_delay_s;
  est_.value = start;
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
  double sum2 = 0;
  for (const GyroSample& g : gyro_)
    if (g.t >= w.t_begin + off && g.t <= w.t_end + off) ++w.gyro_samples, sum2 += (g.w - est_.value.gyro_bias).squaredNorm();
  w.rate_rms_rad_s = w.gyro_samples ? std::sqrt(sum2 / w.gyro_samples) : 0;
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
  return est_;
}

void OnlineEstimator::accept(const OnlineCalibration& fit, const OnlineCalibration& sigma, double t) {
  const std::array<double, 5> z = values(fit), s = values(sigma);
  const double ld = have_fit_ ? x_[1] : fit.line_delay_s;
  const std::array<double, 5> walk = {opt_.offset_walk_s, opt_.line_delay_walk * ld, opt_.bias_walk_rad_s,
                                      opt_.bias_walk_rad_s, opt_.bias_walk_rad_s};
  const double dt = have_fit_ ? std::max(t - t_fit_, 1e-3) : 0;
  // Successive windows overlap: a fit shares most of its data with the one before, so it
  // carries the information of only the new part of its window.
  const double overlap = have_fit_ ? std::max(1.0, opt_.window_s / dt) : 1.0;
  const bool first = !have_fit_;
  bool stepped = false;
  for (int i = 0; i < 5; ++i) {
    const double prior = var_[i] + walk[i] * walk[i] * dt, r = s[i] * s[i], nu = z[i] - x_[i];
    // A value whose fit lies beyond step_sigmas of the estimate stepped: it restarts from the fit.
    if (first || nu * nu > opt_.step_sigmas * opt_.step_sigmas * (prior + r)) {
      x_[i] = z[i], var_[i] = r;
      stepped = stepped || !first;
    } else {
      const double k = prior / (prior + r * overlap);
      x_[i] += k * nu, var_[i] = (1 - k) * prior;
    }
  }
  have_fit_ = true, t_fit_ = t;
  est_.value = calibration(x_);
  std::array<double, 5> sd{};
  for (int i = 0; i < 5; ++i) sd[i] = std::sqrt(var_[i]);
  est_.sigma = calibration(sd);
  const bool small = est_.sigma.time_offset_s <= opt_.converged_offset_sigma_s &&
                     est_.sigma.line_delay_s <= opt_.converged_line_delay_sigma * est_.value.line_delay_s &&
                     est_.sigma.gyro_bias.maxCoeff() <= opt_.converged_bias_sigma;
  settled_ = small && !stepped ? settled_ + 1 : 0;
  est_.state = settled_ >= opt_.settle ? OnlineState::Converged : OnlineState::Converging;
  est_.converged = est_.state == OnlineState::Converged;
  est_.reason = stepped ? "a step: restarted from this window's fit" : "";
}

const OnlineEstimate& OnlineEstimator::update() {
  ++est_.updates;
  prune();
  OnlineWindow w = window_contents();
  if (w.matches < opt_.min_matches)
    return hold(OnlineState::Held, "too few matches (" + std::to_string(w.matches) + ")", w);
  if (w.rate_rms_rad_s < opt_.min_rate_rad_s)
    return hold(OnlineState::Held, "too little rotation (" + std::to_string(w.rate_rms_rad_s) + " rad/s RMS)", w);
  try {
    const Recording rec = window_recording();
    const DiagnosisModel m(rec);
    std::vector<int> idx(m.size());
    for (int i = 0; i < m.size(); ++i) idx[i] = i;
    ModelParams p = nominal_params(rec.nominal);
    p[Param::BiasX] = est_.value.gyro_bias.x(), p[Param::BiasY] = est_.value.gyro_bias.y(),
    p[Param::BiasZ] = est_.value.gyro_bias.z();
    if (est_.state != OnlineState::Converged && opt_.search_s > 0) {
      // Until converged the offset may be far off (a new rig, a step): a grid search first.
      const std::vector<int> sub = subsample(idx, 300);
      const double guess = std::clamp(robust_stats(m.residuals(p, sub)).scale_px, 0.2, 5.0);
      p[Param::TimeOffset] = refine_time_offset(m, sub, p, guess, opt_.search_s);
    }
    const double sigma_px = std::clamp(robust_stats(m.residuals(p, idx)).scale_px, 0.05, 10.0);
    ParamMask free;
    for (Param q : kFree) free.set(static_cast<int>(q));
    const ModelParams f = fit_params(m, idx, p, free, sigma_px);
    const RobustStats rs = robust_stats(m.residuals(f, idx));
    w.fitted = rs.observations, w.inliers = rs.observations - rs.outliers, w.residual_px = rs.scale_px;
    const OnlineCalibration v = from_params(f);
    if (rs.scale_px > opt_.max_residual_px)
      return hold(OnlineState::Rejected, "residuals too large (" + std::to_string(rs.scale_px) + " px)", w);
    if (2 * w.inliers < w.fitted) return hold(OnlineState::Rejected, "fewer than half the matches fit", w);
    if (!(v.line_delay_s > 0) || v.gyro_bias.cwiseAbs().maxCoeff() > opt_.max_bias_rad_s)
      return hold(OnlineState::Rejected, "implausible fit (line delay or gyro bias)", w);
    const auto var = parameter_variances(m, f, kFree, idx);
    if (!var) return hold(OnlineState::Rejected, "parameters not identifiable from this window", w);
    est_.window = w;
    accept(v, from_variances(*var), w.t_end);
    return est_;
  } catch (const std::exception& e) {
    return hold(OnlineState::Rejected, e.what(), w);
  }
}

}  // namespace rsd::dsp
