#include "dsp/diagnosis.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace rsd::dsp {

namespace {

// A failed prediction costs as much as a residual this many sigmas long, per coordinate:
// far into the robust loss's linear part, so it neither dominates nor vanishes.
constexpr double kFailSigmas = 20.0;
// Huber threshold in sigmas: quadratic (Gaussian) within, linear (outlier-tolerant) beyond.
constexpr double kHuberSigmas = 2.0;

double huber(double s2) {
  const double d = kHuberSigmas;
  return s2 <= d * d ? s2 : 2 * d * std::sqrt(s2) - d * d;
}

// -2 log-likelihood (up to a constant) of residuals under the robust loss, sigma units:
// the same quantity Ceres minimises (times two), so BIC compares fits on their own terms.
double robust_chi2(const std::vector<Eigen::Vector2d>& r, double sigma) {
  double c = 0;
  for (const auto& e : r)
    c += huber(e.allFinite() ? e.squaredNorm() / (sigma * sigma) : 2 * kFailSigmas * kFailSigmas);
  return c;
}

}  // namespace

RobustStats robust_stats(const std::vector<Eigen::Vector2d>& residuals) {
  RobustStats s;
  s.observations = static_cast<int>(residuals.size());
  std::vector<double> len;
  for (const auto& r : residuals)
    if (r.allFinite()) len.push_back(r.norm());
  if (len.empty()) {
    s.outliers = s.observations;
    return s;
  }
  std::vector<double> sorted = len;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  // Median of a Rayleigh(sigma) length is sigma sqrt(2 ln 2).
  s.scale_px = sorted[sorted.size() / 2] / std::sqrt(2 * std::log(2.0));
  const double limit = kOutlierSigmas * std::max(s.scale_px, 1e-12);
  double sum = 0;
  int n = 0;
  for (double l : len)
    if (l <= limit) sum += l * l, ++n;
  s.outliers = s.observations - n;
  s.rms_px = n > 0 ? std::sqrt(sum / (2.0 * n)) : 0.0;
  return s;
}

// ---------------------------------------------------------------- locate

namespace {

// Share of the energy of r that the columns of A explain (least squares R^2 about zero).
double explained(const Eigen::MatrixXd& A, const Eigen::VectorXd& r) {
  const double e = r.squaredNorm();
  if (e <= 0 || A.rows() <= A.cols()) return 0;
  const Eigen::VectorXd beta = A.colPivHouseholderQr().solve(r);
  return std::clamp(1.0 - (r - A * beta).squaredNorm() / e, 0.0, 1.0);
}

struct Signature {
  Eigen::VectorXd r;                            // stacked (du, dv) residuals
  Eigen::MatrixXd vel, row, both, radius, scale;  // pattern columns, same stacking
  std::vector<std::pair<int, double>> frame_energy;  // (frame rank, |r|^2)
};

Signature signature(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx) {
  const Recording& rec = m.recording();
  const CameraModel& cam = rec.nominal.cam;
  const auto base = m.residuals(p, idx);
  const RobustStats st = robust_stats(base);
  ModelParams shifted = p;
  const double h = 1e-3;  // image velocity: how the prediction moves when time moves
  shifted[Param::TimeOffset] += h;
  std::vector<int> keep;
  for (size_t k = 0; k < idx.size(); ++k)
    if (base[k].allFinite() && base[k].norm() <= kOutlierSigmas * st.scale_px) keep.push_back(static_cast<int>(k));
  const int n = static_cast<int>(keep.size());
  Signature s{Eigen::VectorXd(2 * n), Eigen::MatrixXd(2 * n, 1), Eigen::MatrixXd(2 * n, 1),
              Eigen::MatrixXd(2 * n, 2), Eigen::MatrixXd(2 * n, 2), Eigen::MatrixXd::Zero(2 * n, 2), {}};
  const bool down = (rec.nominal.time.readout == Readout::TopToBottom) != p.flip_readout;
  for (int j = 0; j < n; ++j) {
    const int k = keep[j], i = idx[k];
    const auto rs = m.residual(shifted, i);
    const Eigen::Vector2d v = rs ? Eigen::Vector2d((base[k] - *rs) / h) : Eigen::Vector2d::Zero();
    const Eigen::Vector2d px = m.observed(i);
    // Rows since the first row read, as a share of the frame: the rolling-shutter delay.
    const double row = (down ? px.y() : cam.height - 1 - px.y()) / cam.height;
    const double xn = (px.x() - cam.cx) / cam.fx, yn = (px.y() - cam.cy) / cam.fy, r2 = xn * xn + yn * yn;
    const Eigen::Vector2d radial(cam.fx * xn, cam.fy * yn);
    s.r.segment<2>(2 * j) = base[k];
    s.vel.block<2, 1>(2 * j, 0) = v;
    s.row.block<2, 1>(2 * j, 0) = v * row;
    s.both.block<2, 1>(2 * j, 0) = v;
    s.both.block<2, 1>(2 * j, 1) = v * row;
    s.radius.block<2, 1>(2 * j, 0) = radial * r2;
    s.radius.block<2, 1>(2 * j, 1) = radial * r2 * r2;
    s.scale(2 * j, 0) = px.x() - cam.cx;
    s.scale(2 * j + 1, 1) = px.y() - cam.cy;
    s.frame_energy.push_back({m.frame_rank(i), base[k].squaredNorm()});
  }
  return s;
}

// Share of the residual energy in frames whose mean energy exceeds 4x the median frame's,
// and the span of those frames.
Located time_signal(const std::vector<std::pair<int, double>>& fe) {
  std::vector<double> sum, cnt;
  for (const auto& [rank, e] : fe) {
    if (rank >= static_cast<int>(sum.size())) sum.resize(rank + 1, 0), cnt.resize(rank + 1, 0);
    sum[rank] += e, cnt[rank] += 1;
  }
  std::vector<double> mean;
  for (size_t k = 0; k < sum.size(); ++k)
    if (cnt[k] > 0) mean.push_back(sum[k] / cnt[k]);
  if (mean.empty()) return {"time", 0, ""};
  std::vector<double> sorted = mean;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double med = sorted[sorted.size() / 2];
  double total = 0, hot = 0;
  int first = -1, last = -1;
  for (size_t k = 0; k < sum.size(); ++k) {
    total += sum[k];
    if (cnt[k] > 0 && sum[k] / cnt[k] > 4 * med) hot += sum[k], last = static_cast<int>(k), first = first < 0 ? last : first;
  }
  std::ostringstream d;
  d << "residual concentrated in frames " << first << " to " << last << " (time order)";
  return {"time", total > 0 ? hot / total : 0, first < 0 ? "" : d.str()};
}

}  // namespace

std::vector<Located> locate(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx) {
  const Signature s = signature(m, p, idx);
  if (s.r.size() == 0) return {};
  // A time shift and a row delay both move points along their image motion; each signal's
  // strength is what it explains beyond the other, so the two do not claim the same energy.
  const double both = explained(s.both, s.r);
  std::vector<Located> out = {
      {"image_velocity", std::max(0.0, both - explained(s.row, s.r)),
       "residual follows the image motion, the same for all rows: a time shift"},
      {"row", std::max(0.0, both - explained(s.vel, s.r)),
       "residual along the image motion grows linearly with image row: row timing"},
      {"radius", explained(s.radius, s.r), "residual radial, growing with r^2 and r^4: lens distortion"},
      {"image_scale", explained(s.scale, s.r), "residual proportional to distance from the principal point: scale"},
      time_signal(s.frame_energy)};
  // Signals explaining under 5% of the residual are noise-level coincidences.
  out.erase(std::remove_if(out.begin(), out.end(), [](const Located& l) { return l.strength < 0.05; }), out.end());
  std::sort(out.begin(), out.end(), [](const Located& a, const Located& b) { return a.strength > b.strength; });
  return out;
}

// ---------------------------------------------------------------- fitting

namespace {

// One observation's residual in sigma units as a function of the free parameters (in
// param_scale units, relative to `base`). Numeric differentiation: the prediction is a
// root-finding (the rolling-shutter fixed point), not an expression Jets can run through.
struct ObservationCost {
  const DiagnosisModel* m;
  int i;
  ModelParams base;
  std::vector<std::pair<Param, double>> free;  // parameter and its scale
  double inv_sigma;
  bool operator()(double const* const* x, double* r) const {
    ModelParams p = base;
    for (size_t j = 0; j < free.size(); ++j) p[free[j].first] += x[0][j] * free[j].second;
    const auto res = m->residual(p, i);
    r[0] = res ? res->x() * inv_sigma : kFailSigmas;
    r[1] = res ? res->y() * inv_sigma : kFailSigmas;
    return true;
  }
};

// Physical limits of the free parameters, in the fit's units: a line delay between zero
// and a readout filling the frame period; an offset inside the motion data; positive focals.
void set_bounds(ceres::Problem& pb, double* x, const DiagnosisModel& m, const ModelParams& base,
                const std::vector<std::pair<Param, double>>& free) {
  const NominalModel& n = m.recording().nominal;
  const auto [lo_off, hi_off] = m.offset_range();
  for (size_t j = 0; j < free.size(); ++j) {
    const auto [p, sc] = free[j];
    const int k = static_cast<int>(j);
    if (p == Param::LineDelay) {
      pb.SetParameterLowerBound(x, k, -base[p] / sc);
      pb.SetParameterUpperBound(x, k, (1.0 / (n.frame_rate_hz * n.cam.height) - base[p]) / sc);
    } else if (p == Param::TimeOffset) {
      pb.SetParameterLowerBound(x, k, (lo_off - base[p]) / sc);
      pb.SetParameterUpperBound(x, k, (hi_off - base[p]) / sc);
    } else if (p == Param::Fx || p == Param::Fy) {
      pb.SetParameterLowerBound(x, k, -0.5 * base[p] / sc);
    }
  }
}

}  // namespace

ModelParams fit_params(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& start,
                       const ParamMask& free_mask, double sigma_px, int max_iterations) {
  std::vector<std::pair<Param, double>> free;
  for (int k = 0; k < kParamCount; ++k)
    if (free_mask[k]) free.push_back({Param(k), param_scale(Param(k), m.recording().nominal)});
  if (free.empty() || idx.empty()) return start;
  std::vector<double> x(free.size(), 0.0);
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem pb(po);
  ceres::HuberLoss loss(kHuberSigmas);
  ceres::NumericDiffOptions nd;
  nd.relative_step_size = 1e-3;  // of a param_scale unit when x is near 0
  for (int i : idx) {
    auto* cost = new ceres::DynamicNumericDiffCostFunction<ObservationCost, ceres::FORWARD>(
        new ObservationCost{&m, i, start, free, 1.0 / sigma_px}, ceres::TAKE_OWNERSHIP, nd);
    cost->AddParameterBlock(static_cast<int>(free.size()));
    cost->SetNumResiduals(2);
    pb.AddResidualBlock(cost, &loss, x.data());
  }
  set_bounds(pb, x.data(), m, start, free);
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.logging_type = ceres::SILENT;
  so.function_tolerance = 1e-10;
  so.parameter_tolerance = 1e-10;
  so.num_threads = 1;  // dsp code runs on its caller's thread
  ceres::Solver::Summary summary;
  ceres::Solve(so, &pb, &summary);
  ModelParams out = start;
  for (size_t j = 0; j < free.size(); ++j) out[free[j].first] += x[j] * free[j].second;
  return out;
}

namespace {

// Truncated quadratic cost of a time offset: bounded per observation so that a wrong offset
// (residuals of hundreds of pixels) costs the same wherever it is, and the valley is clear.
double offset_cost(const DiagnosisModel& m, const std::vector<int>& idx, ModelParams p, double offset,
                   double width_px) {
  p[Param::TimeOffset] = offset;
  double c = 0;
  for (const auto& r : m.residuals(p, idx)) c += r.allFinite() ? std::min(r.squaredNorm() / (width_px * width_px), 1.0) : 1.0;
  return c;
}

double best_on_grid(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, double lo, double hi,
                    double step, double width_px) {
  double best = p[Param::TimeOffset], best_cost = std::numeric_limits<double>::infinity();
  for (double t = lo; t <= hi + 1e-12; t += step) {
    const double c = offset_cost(m, idx, p, t, width_px);
    if (c < best_cost) best_cost = c, best = t;
  }
  return best;
}

}  // namespace

double scan_time_offset(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, double sigma_px) {
  // A hundred observations spread over the recording decide the valley; the fit refines.
  std::vector<int> sub;
  const size_t stride = std::max<size_t>(1, idx.size() / 100);
  for (size_t k = 0; k < idx.size(); k += stride) sub.push_back(idx[k]);
  const auto [lo_range, hi_range] = m.offset_range();
  const double now = p[Param::TimeOffset];
  const double lo = std::max(lo_range, now - 1.0), hi = std::min(hi_range, now + 1.0);
  if (!(lo < hi)) return now;
  // Coarse: 5 ms steps with a wide valley (20 sigma); fine: 0.25 ms steps, 5 sigma.
  const double coarse = best_on_grid(m, sub, p, lo, hi, 5e-3, 20 * sigma_px);
  return best_on_grid(m, sub, p, std::max(lo, coarse - 5e-3), std::min(hi, coarse + 5e-3), 2.5e-4, 5 * sigma_px);
}

// ---------------------------------------------------------------- selection

namespace {

enum Effect { RollingShutter, TimeOffset, ReadoutDirection, LensDistortion, FocalLength, kEffectCount };
const char* kEffectNames[] = {"rolling_shutter", "time_offset", "readout_direction", "lens_distortion", "focal_length"};

ParamMask effect_params(int e) {
  ParamMask m;
  auto set = [&](Param p) { m.set(static_cast<int>(p)); };
  switch (e) {
    case RollingShutter: set(Param::LineDelay); break;
    case TimeOffset: set(Param::TimeOffset); break;
    case ReadoutDirection: break;  // discrete: the flip; its line delay comes with rolling_shutter
    case LensDistortion: set(Param::K1), set(Param::K2); break;
    case FocalLength: set(Param::Fx), set(Param::Fy); break;
  }
  return m;
}

struct State {
  std::vector<int> effects;  // selected, in order
  ModelParams params;
  double bic = 0;
  bool has(int e) const { return std::find(effects.begin(), effects.end(), e) != effects.end(); }
};

struct Selector {
  const DiagnosisModel& m;
  const std::vector<int>& idx;
  ModelParams nominal;
  double sigma;
  const DiagnosisOptions& opt;

  double bic(const ModelParams& p, const std::vector<int>& effects) const {
    ParamMask mask;
    for (int e : effects) mask |= effect_params(e);
    const double k = static_cast<double>(mask.count()) + (p.flip_readout ? 1 : 0);
    return robust_chi2(m.residuals(p, idx), sigma) + k * std::log(2.0 * idx.size());
  }

  // Fits the effects `effects` from `start`: a global offset search first when the offset
  // is free, since the robust cost has many local minima in it.
  State fit(std::vector<int> effects, ModelParams start) const {
    ParamMask mask;
    for (int e : effects) mask |= effect_params(e);
    if (std::find(effects.begin(), effects.end(), TimeOffset) != effects.end())
      start[Param::TimeOffset] = scan_time_offset(m, idx, start, sigma);
    const ModelParams p = fit_params(m, idx, start, mask, sigma, opt.max_iterations);
    return {effects, p, bic(p, effects)};
  }

  // Adding effect e to s; readout_direction brings rolling_shutter along when the nominal
  // model is a global shutter (the order of rows read means nothing without a readout time).
  State add(const State& s, int e) const {
    std::vector<int> effects = s.effects;
    ModelParams start = s.params;
    effects.push_back(e);
    if (e == ReadoutDirection) {
      start.flip_readout = true;
      if (!s.has(RollingShutter) && nominal[Param::LineDelay] == 0) effects.push_back(RollingShutter);
    }
    return fit(effects, start);
  }

  State remove(const State& s, int e) const {
    std::vector<int> effects;
    for (int f : s.effects)
      if (f != e) effects.push_back(f);
    ModelParams start = s.params;
    const ParamMask drop = effect_params(e);
    for (int k = 0; k < kParamCount; ++k)
      if (drop[k]) start.v[k] = nominal.v[k];
    if (e == ReadoutDirection) start.flip_readout = false;
    return fit(effects, start);
  }
};

}  // namespace

namespace {

struct Step {
  int effect;
  double rms, bic_drop;
};

std::vector<Step> forward(const Selector& sel, State& s) {
  std::vector<Step> steps;
  while (true) {
    State best;
    int best_e = -1;
    for (int e = 0; e < kEffectCount; ++e) {
      if (s.has(e)) continue;
      State c = sel.add(s, e);
      if (best_e < 0 || c.bic < best.bic) best = std::move(c), best_e = e;
    }
    if (best_e < 0 || s.bic - best.bic < sel.opt.min_bic_drop) return steps;
    const double drop = s.bic - best.bic;
    for (size_t k = s.effects.size(); k < best.effects.size(); ++k)
      steps.push_back({best.effects[k], robust_stats(sel.m.residuals(best.params, sel.idx)).rms_px, drop});
    s = std::move(best);
  }
}

// Drops any selected effect whose removal (with a refit of the rest) costs less BIC than
// the selection threshold: an earlier pick that later ones made redundant.
void backward(const Selector& sel, State& s, std::vector<Step>& steps) {
  bool changed = true;
  while (changed && s.effects.size() > 1) {
    changed = false;
    for (int e : s.effects) {
      State c = sel.remove(s, e);
      if (c.bic - s.bic < sel.opt.min_bic_drop) {
        s = std::move(c);
        steps.erase(std::remove_if(steps.begin(), steps.end(), [&](const Step& st) { return st.effect == e; }), steps.end());
        changed = true;
        break;
      }
    }
  }
}

NamedEffect describe(int e, const ModelParams& p, const NominalModel& n, const Step& st) {
  NamedEffect out{kEffectNames[e], {}, "", st.rms, st.bic_drop};
  std::ostringstream x;
  switch (e) {
    case RollingShutter: {
      const double readout = p[Param::LineDelay] * n.cam.height;
      out.params = {{"line_delay_s", p[Param::LineDelay], ""}, {"frame_readout_s", readout, ""}};
      x << "rows are read over " << readout * 1e3 << " ms, not " << n.time.line_delay_s * n.cam.height * 1e3 << " ms";
      break;
    }
    case TimeOffset:
      out.params = {{"time_offset_s", p[Param::TimeOffset], ""}};
      x << "the motion clock is " << p[Param::TimeOffset] * 1e3 << " ms ahead of the camera clock";
      break;
    case ReadoutDirection: {
      const bool down = (n.time.readout == Readout::TopToBottom) != p.flip_readout;
      out.params = {{"direction", 0, down ? "top_to_bottom" : "bottom_to_top"}};
      x << "rows are read " << (down ? "top to bottom" : "bottom to top") << ", not the nominal order";
      break;
    }
    case LensDistortion:
      out.params = {{"k1", p[Param::K1], ""}, {"k2", p[Param::K2], ""}};
      x << "radial distortion k1 = " << p[Param::K1] << ", k2 = " << p[Param::K2];
      break;
    case FocalLength:
      out.params = {{"fx", p[Param::Fx], ""}, {"fy", p[Param::Fy], ""}};
      x << "focal length " << p[Param::Fx] << " x " << p[Param::Fy] << " px, not " << n.cam.fx << " x " << n.cam.fy;
      break;
  }
  out.explains = x.str();
  return out;
}

// Fitting and held-out observations: whole frames are held out, every n-th in time order.
void split(const DiagnosisModel& m, int every, std::vector<int>& fit, std::vector<int>& held) {
  for (int i = 0; i < m.size(); ++i)
    (every > 1 && m.frame_rank(i) % every == every - 1 ? held : fit).push_back(i);
}

// True when the nominal model's robust chi-square is what noise alone would give (within
// three standard deviations of a chi-square with one degree per residual).
bool within_noise(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, double sigma) {
  const double n = 2.0 * idx.size();
  return robust_chi2(m.residuals(p, idx), sigma) <= n + 3 * std::sqrt(2 * n);
}

}  // namespace

Diagnosis diagnose(const Recording& rec, const DiagnosisOptions& opt) {
  const DiagnosisModel m(rec);
  Diagnosis d;
  std::vector<int> all(m.size()), fit, held;
  for (int i = 0; i < m.size(); ++i) all[i] = i;
  split(m, opt.heldout_every, fit, held);
  const ModelParams nominal = nominal_params(rec.nominal);
  d.baseline = robust_stats(m.residuals(nominal, all));
  d.located = locate(m, nominal, fit);
  // Noise: as stated, or else what is left after every effect is fitted at once.
  d.sigma_px = rec.noise_px.value_or(0.0);
  Selector sel{m, fit, nominal, d.sigma_px > 0 ? d.sigma_px : std::max(d.baseline.scale_px, 1e-3), opt};
  if (!(d.sigma_px > 0)) {
    const State rich = sel.fit({RollingShutter, TimeOffset, LensDistortion, FocalLength}, nominal);
    d.sigma_px = sel.sigma = std::max(robust_stats(m.residuals(rich.params, fit)).scale_px, 1e-3);
  }
  State s{{}, nominal, sel.bic(nominal, {})};
  if (!within_noise(m, fit, nominal, sel.sigma)) {
    std::vector<Step> steps = forward(sel, s);
    backward(sel, s, steps);
    for (const Step& st : steps) d.effects.push_back(describe(st.effect, s.params, rec.nominal, st));
  }
  d.fitted = s.params;
  d.final_rms_px = robust_stats(m.residuals(s.params, all)).rms_px;
  d.heldout_observations = static_cast<int>(held.size());
  d.heldout_baseline_rms_px = robust_stats(m.residuals(nominal, held)).rms_px;
  d.heldout_final_rms_px = robust_stats(m.residuals(s.params, held)).rms_px;
  return d;
}

}  // namespace rsd::dsp
