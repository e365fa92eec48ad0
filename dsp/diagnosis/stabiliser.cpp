#include "dsp/diagnosis/stabiliser.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "dsp/diagnosis/effects.hpp"
#include "dsp/diagnosis/gyro.hpp"
#include "dsp/geometry/camera_motion.hpp"

namespace rsd::dsp {

namespace {

// Per sample, the turn v that takes its orientation R_k to the mean of the orientations around
// it weighted by the kernel, R_k Exp(v_k) (one Gauss-Newton step of the Karcher mean, in the
// tangent space at R_k; the stabiliser smooths where the camera points, not its body rates,
// which differ from it by the angle turned times the rate). The kernel is integrated on a
// regular grid of its own, not over the samples: a gyro sampled at 20 to 200 Hz would weigh a
// short kernel by where the samples fall. Between samples the orientation is the gyro track's
// (the rate's Hermite curve integrated, not a slerp, which at a gyro's 20 Hz end is off by
// milliradians).
std::vector<Eigen::Vector3d> turns_to_mean(const std::vector<GyroSample>& gyro, double sigma_s, double from, double to) {
  const GyroTrack track(gyro, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), gyro_gap_limit(gyro));
  constexpr int kNodes = 33;  // over +-4 sigma (a cut at 3 raised a 1 Hz sine's gain by 0.3%)
  std::array<double, kNodes> d{}, w{};
  double total = 0;
  for (int i = 0; i < kNodes; ++i) {
    d[i] = sigma_s * (-4.0 + 8.0 * i / (kNodes - 1));
    w[i] = std::exp(-0.5 * (d[i] / sigma_s) * (d[i] / sigma_s)), total += w[i];
  }
  std::vector<Eigen::Vector3d> v(gyro.size(), Eigen::Vector3d::Zero());
  size_t at_k = 0, at = 0;
  for (size_t k = 0; k < gyro.size(); ++k) {
    if (gyro[k].t < from || gyro[k].t > to) continue;
    const Eigen::Matrix3d Rk_t = track.camera_at(gyro[k].t, at_k).transpose();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int i = 0; i < kNodes; ++i) sum += w[i] * log_so3(Rk_t * track.camera_at(gyro[k].t + d[i], at));
    v[k] = sum / total;
  }
  return v;
}

}  // namespace

std::vector<GyroSample> smoothed_rates(const std::vector<GyroSample>& gyro, double sigma_s, double from, double to) {
  if (!(sigma_s > 0)) throw std::invalid_argument("smoothed_rates: sigma_s must be positive");
  const size_t n = gyro.size();
  for (size_t k = 1; k < n; ++k)
    if (!(gyro[k].t > gyro[k - 1].t))
      throw std::invalid_argument("smoothed_rates: the gyro's sample times must increase (as clean_gyro gives them)");
  if (n < 2) return gyro;
  const std::vector<Eigen::Vector3d> v = turns_to_mean(gyro, sigma_s, from, to);
  // S = R Exp(v) turns at Exp(-v) w + J_r(v) dv/dt (J_r to first order); dv/dt by central
  // differences (one-sided at the ends).
  std::vector<GyroSample> out(gyro);
  for (size_t k = 0; k < n; ++k) {
    if (gyro[k].t < from || gyro[k].t > to) continue;
    const size_t a = k > 0 ? k - 1 : 0, b = std::min(k + 1, n - 1);
    const Eigen::Vector3d dv = (v[b] - v[a]) / (gyro[b].t - gyro[a].t);
    out[k].w = exp_so3(-v[k]) * gyro[k].w + dv - 0.5 * v[k].cross(dv);
  }
  return out;
}


namespace {

// The span of the motion clock the observations of idx and `also` see at p (their frames' times
// moved by the clock offset), with half a second to spare for the readout and the smoothing's
// reach: a minute's gyro smoothed whole for the twenty seconds a test looks at took a second.
struct Span {
  double from, to;
};
Span motion_span(const DiagnosisModel& m, const std::vector<int>& idx, const std::vector<int>& also, const ModelParams& p) {
  Span s{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (const std::vector<int>* set : {&idx, &also})
    for (int i : *set) s.from = std::min(s.from, m.frame_time(i)), s.to = std::max(s.to, m.frame_time_b(i));
  const double offset = p[Param::TimeOffset];
  return {s.from + offset - 0.5, s.to + offset + 0.5};
}

double chi2_with(const DiagnosisModel& m, double sigma_s, Span span, const std::vector<int>& idx, const ModelParams& p,
                 double sigma_px) {
  const DiagnosisModel s(m, smoothed_rates(m.gyro_samples(), sigma_s, span.from - 4 * sigma_s, span.to + 4 * sigma_s));
  return robust_chi2(s.residuals(p, idx), sigma_px);
}

}  // namespace

StabiliserFit fit_stabiliser(const DiagnosisModel& m, const std::vector<int>& search, const std::vector<int>& idx,
                             const ModelParams& p, const ParamMask& free, double sigma_px, int iterations) {
  if (!m.has_gyro()) throw std::invalid_argument("fit_stabiliser: the recording has no gyro");
  const Span span = motion_span(m, search, idx, p);
  StabiliserFit best;
  best.chi2 = std::numeric_limits<double>::infinity();
  const auto consider = [&](double sigma_s) {
    const double c = chi2_with(m, sigma_s, span, search, p, sigma_px);
    if (c < best.chi2) best.chi2 = c, best.sigma_s = sigma_s;
  };
  for (double s = 0.01; s < 0.7; s *= 2) consider(s);
  // Golden-section on log sigma within a factor two of the grid's best.
  const double g = (std::sqrt(5.0) - 1) / 2;
  double a = std::log(best.sigma_s / 2), b = std::log(best.sigma_s * 2);
  double x1 = b - g * (b - a), x2 = a + g * (b - a);
  double f1 = chi2_with(m, std::exp(x1), span, search, p, sigma_px), f2 = chi2_with(m, std::exp(x2), span, search, p, sigma_px);
  for (int it = 0; it < 6; ++it) {
    if (f1 < f2) b = x2, x2 = x1, f2 = f1, x1 = b - g * (b - a), f1 = chi2_with(m, std::exp(x1), span, search, p, sigma_px);
    else a = x1, x1 = x2, f1 = f2, x2 = a + g * (b - a), f2 = chi2_with(m, std::exp(x2), span, search, p, sigma_px);
  }
  if (std::min(f1, f2) < best.chi2) best.sigma_s = std::exp(f1 < f2 ? x1 : x2);
  const DiagnosisModel s(m, smoothed_rates(m.gyro_samples(), best.sigma_s, span.from - 4 * best.sigma_s,
                                           span.to + 4 * best.sigma_s));
  const ModelParams refitted = free.any() ? fit_params(s, idx, p, free, sigma_px, iterations) : p;
  best.chi2 = robust_chi2(s.residuals(refitted, idx), sigma_px);
  return best;
}

bool smoothing_beats_a_gain(const DiagnosisModel& m, const std::vector<int>& all, ModelParams p, double sigma_px,
                            double min_drop) {
  if (!m.has_gyro()) return false;
  p.translation_nuisance = false;
  // Twenty seconds are evidence enough, and a minute's took three times as long.
  double first = std::numeric_limits<double>::infinity();
  for (int i : all) first = std::min(first, m.frame_time(i));
  std::vector<int> idx;
  for (int i : all)
    if (m.frame_time(i) < first + kProbeSeconds) idx.push_back(i);
  // Ten observations per parameter of the larger fit (a scale per axis and the focal length) at
  // the least: fewer say nothing either way.
  if (idx.size() < 40) return false;
  const NominalModel& n = m.recording().nominal;
  const ParamMask focal = mask_of({Effect::FocalLength}, n.cam.dist.model);
  const ModelParams gain = fit_params(m, idx, p, mask_of({Effect::GyroScale, Effect::FocalLength}, n.cam.dist.model), sigma_px, 8);
  // The smoothing searched from p's focal length and from the nominal one: the gross search
  // may have shortened it for the stabiliser's gain (15% on the suite's stabilised clip, where
  // the smoothing's search from there settled at 26 ms, from the nominal at 44).
  ModelParams at_nominal = p;
  at_nominal[Param::Fx] = n.cam.fx, at_nominal[Param::Fy] = n.cam.fy;
  double smoothed = std::numeric_limits<double>::infinity();
  for (const ModelParams& from : {p, at_nominal}) smoothed = std::min(smoothed, fit_stabiliser(m, idx, idx, from, focal, sigma_px, 8).chi2);
  const double with = robust_chi2(m.residuals(gain, idx), sigma_px);
  return (with - smoothed) / design_effect(m, gain, idx, sigma_px) > min_drop;
}

std::optional<double> stabiliser_after_selection(const DiagnosisModel& m, const std::vector<int>& search,
                                                 const std::vector<int>& idx, ModelParams p, double sigma_px,
                                                 double min_drop) {
  if (!m.has_gyro() || idx.empty()) return std::nullopt;
  p.translation_nuisance = false;
  const StabiliserFit s = fit_stabiliser(m, search, idx, p, ParamMask{}, sigma_px, 0);
  const double with = robust_chi2(m.residuals(p, idx), sigma_px);
  const bool clear = (with - s.chi2) / design_effect(m, p, idx, sigma_px) > min_drop;
  if (clear && with - s.chi2 >= kStabiliserShare * with) return s.sigma_s;
  return std::nullopt;
}

}  // namespace rsd::dsp
