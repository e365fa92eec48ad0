#include "dsp/diagnosis/blocked_halves.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>

#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/robust_stats.hpp"
#include "dsp/diagnosis/uncertainty.hpp"
#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/lens_model.hpp"

namespace rsd::dsp {

namespace {

template <class Key>
Halves split_at_median(const std::vector<int>& idx, Key key) {
  std::vector<double> k;
  for (int i : idx) k.push_back(key(i));
  if (k.empty()) return {};
  std::vector<double> sorted = k;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double mid = sorted[sorted.size() / 2];
  Halves h;
  for (size_t j = 0; j < idx.size(); ++j) (k[j] < mid ? h.a : h.b).push_back(idx[j]);
  return h;
}

// S = sum |d_i|^2 / sigma^2 over the observations both models predict within the robust loss's
// quadratic core (an outlier's change says nothing about the noise of the drop).
double signal_energy(const std::vector<Eigen::Vector2d>& r0, const std::vector<Eigen::Vector2d>& r1, double sigma) {
  double s = 0;
  const double core = 2.0 * sigma;
  for (size_t k = 0; k < r0.size(); ++k)
    if (r0[k].allFinite() && r1[k].allFinite() && r0[k].norm() < core && r1[k].norm() < core)
      s += (r0[k] - r1[k]).squaredNorm() / (sigma * sigma);
  return s;
}

// The robust chi-square drop from r0 to r1 plus the margin independent noise allows (fit_halves).
double noise_margined_drop(const std::vector<Eigen::Vector2d>& r0, const std::vector<Eigen::Vector2d>& r1, double sigma) {
  return robust_chi2(r0, sigma) - robust_chi2(r1, sigma) + 3.0 * std::sqrt(signal_energy(r0, r1, sigma));
}

// The frames of one block of kHalvesBlockS, the unit the halves' covariances cluster by.
int block_frames(const DiagnosisModel& m) {
  return std::max(1, static_cast<int>(std::lround(kHalvesBlockS * m.recording().nominal.frame_rate_hz)));
}

// The drop from r0 to r1 on the observations `judge` with the larger of two margins: the
// noise's, and three standard errors from the spread of the blocks' drops (block_margined_drop).
// A real recording's residuals carry structure no effect of the table holds (a flight's
// parallax beyond the smooth translation, things that move), shared by neighbouring frames, and
// a change of the parameters moves a block's chi-square by far more than noise would, either
// way: on the Karma clip with its nominal focal length 35% short, a clock offset fitted on the
// pan's half raised the flight's half from 14 946 to 15 102, where the noise allowed 55 (its
// bulk alone: 28 beyond), and the offset was dropped; the flight half's 25 blocks spread that
// drop with a standard error of 98. A stand-in mispredicts the unseen half block after block,
// beyond both margins.
double margined_drop(const DiagnosisModel& m, const std::vector<int>& judge, const std::vector<Eigen::Vector2d>& r0,
                     const std::vector<Eigen::Vector2d>& r1, double sigma) {
  std::vector<int> block(judge.size());
  const int frames = block_frames(m);
  for (size_t k = 0; k < judge.size(); ++k) block[k] = m.frame_rank(judge[k]) / frames;
  return std::max(noise_margined_drop(r0, r1, sigma), block_margined_drop(block, r0, r1, sigma));
}

// The same drop, with its margin, on the bulk of `judge`: the observations `poorer` predicts
// within kOutlierSigmas robust scales (`r0`, its residuals on `judge`; under the translation
// nuisance, the translation fitted to the bulk). A half's outliers (a forward flight's near objects, things that move) are no model's:
// a real clock offset that a drone's closing pan shows raised the flight's half by 254, all of
// it in that half's tail (its bulk alone: 25, within the margin of 69), and was dropped. A
// stand-in fitted on one half mispredicts the other's bulk.
double bulk_drop(const DiagnosisModel& m, const std::vector<int>& judge, const std::vector<Eigen::Vector2d>& r0,
                 const ModelParams& poorer, const ModelParams& richer, double sigma) {
  const std::vector<bool> in = inliers(r0);
  std::vector<int> bulk;
  for (size_t k = 0; k < judge.size(); ++k)
    if (in[k]) bulk.push_back(judge[k]);
  if (bulk.empty()) return -std::numeric_limits<double>::infinity();
  return margined_drop(m, bulk, m.residuals(poorer, bulk), m.residuals(richer, bulk), sigma);
}

// The values on which two halves must agree for the parameters `added` (over the hypothesis's
// `free` parameters, in their order): each added parameter alone, but a lens's radial terms as
// the curve they draw together (its distorted radius at eight angles out to the image's widest
// ray). Terms of one lens trade with each other (under a hand-held shake's parallax a walk's
// halves put k1 at -0.072 and -0.044, k2 at +0.020 and -0.027, truth -0.06 and 0: k2 4.2 sigmas
// apart, and the lens was dropped), while the curve within the image, what the lens does, is
// held far better (those halves' curves: 3.7 sigmas at most, where the lens hardly bends).
std::vector<Eigen::VectorXd> compared_values(const DiagnosisModel& m, const ModelParams& at, const std::vector<Param>& free,
                                             const ParamMask& added) {
  constexpr Param kRadial[] = {Param::K1, Param::K2, Param::K3, Param::K4};  // distort_radial_jacobian's columns
  auto radial_column = [&](Param q) {
    return static_cast<int>(std::find(std::begin(kRadial), std::end(kRadial), q) - std::begin(kRadial));
  };
  auto is_radial = [&](Param q) { return radial_column(q) < 4; };
  std::vector<Eigen::VectorXd> out;
  bool lens = false;
  for (size_t j = 0; j < free.size(); ++j) {
    if (!added[static_cast<size_t>(free[j])]) continue;
    if (is_radial(free[j])) {
      lens = true;
      continue;
    }
    out.push_back(Eigen::VectorXd::Unit(static_cast<Eigen::Index>(free.size()), static_cast<Eigen::Index>(j)));
  }
  if (!lens) return out;
  const NominalModel& n = m.recording().nominal;
  const Distortion d = lens_of(n, at);
  const double widest = widest_ray_angle(n.cam);
  constexpr int kAngles = 8;
  for (int a = 1; a <= kAngles; ++a) {
    const double r = std::tan(widest * a / kAngles);
    const Eigen::Matrix<double, 2, 4> dk = distort_radial_jacobian(d, Eigen::Vector2d(r, 0));
    Eigen::VectorXd g = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(free.size()));
    for (size_t j = 0; j < free.size(); ++j)
      if (added[static_cast<size_t>(free[j])] && is_radial(free[j]))
        g[static_cast<Eigen::Index>(j)] = dk(0, radial_column(free[j]));
    out.push_back(g);
  }
  return out;
}

// How far apart fits on the two halves put the parameters `added`, in combined sigmas (each
// half's variance with every free parameter of the hypothesis free, so correlations widen it,
// and clustered by blocks of a quarter of a second: a model that is not quite the camera's (a
// lens that is nearly right) misfits in a way that follows the motion, and moves a value fitted
// on one stretch of motion from one fitted on another; the blocks' spread sees that, the
// frames' alone did not, and a real 12 ms clock offset through a rendered fisheye lens was
// called two halves apart). Each sigma is at least a tenth of the value's distance from the
// poorer hypothesis's (`before`): under the translation nuisance the sigmas understate the
// scatter, and a 0.4 s clock offset that a walk's halves put 2.9 ms apart (8 sigmas) is real
// beyond doubt: dropping it left 68 px where the noise floor was 3.6. A stand-in's halves differ by
// about its whole size (a clock jump's: 0 and 3 ms), far past this floor. The values compared
// are compared_values's.
double apart(const DiagnosisModel& m, const CovariedHalves& richer, const ModelParams& before, const ParamMask& free_mask,
             const ParamMask& added) {
  const std::vector<Param> free = params_in(free_mask);
  const auto &ca = richer.cov[0], &cb = richer.cov[1];
  if (!ca || !cb) return 0;  // a half that cannot measure them (no motion there) has no say
  const ModelParams &on_a = richer.fits.on[0], &on_b = richer.fits.on[1];
  Eigen::VectorXd a(free.size()), b(free.size()), mean_from_before(free.size());
  for (size_t j = 0; j < free.size(); ++j) {
    const Param q = free[j];
    const auto k = static_cast<Eigen::Index>(j);
    a[k] = on_a[q], b[k] = on_b[q], mean_from_before[k] = 0.5 * (on_a[q] + on_b[q]) - before[q];
  }
  double worst = 0;
  for (const Eigen::VectorXd& g : compared_values(m, on_a, free, added)) {
    const double s = std::max(std::sqrt(ca->variance_of(g) + cb->variance_of(g)), kHalvesSizeFraction * std::abs(g.dot(mean_from_before)));
    if (s > 0) worst = std::max(worst, std::abs(g.dot(a - b)) / s);
  }
  return worst;
}

// The half (0: a, 1: b) that measures the values `added` adds far less well than the other:
// every compared value's sigma there at least kWeakHalfSigmas times the other half's; -1 if
// neither, or where a half cannot measure them at all (apart gives it no say either). A weak
// half's own fit is loose and mispredicts the strong half by what that looseness allows, not for
// what the effect is (on the Karma clip with its nominal focal length 35% short, the flight's
// half put the focal length at 800 +- 136 px, its bound, the pan's at 465 +- 12, and the
// flight's value cost the pan's half 2 813): it is not asked to predict the strong half
// (cross_check); its say is whether the two values agree within their sigmas (apart).
int weak_half(const DiagnosisModel& m, const CovariedHalves& richer, const ParamMask& free_mask, const ParamMask& added) {
  const auto &ca = richer.cov[0], &cb = richer.cov[1];
  if (!ca || !cb) return -1;
  const std::vector<Param> free = params_in(free_mask);
  bool a_weak = true, b_weak = true, any = false;
  for (const Eigen::VectorXd& g : compared_values(m, richer.fits.on[0], free, added)) {
    const double sa = std::sqrt(ca->variance_of(g)), sb = std::sqrt(cb->variance_of(g));
    any = true;
    a_weak = a_weak && sb > 0 && sa >= kWeakHalfSigmas * sb, b_weak = b_weak && sa > 0 && sb >= kWeakHalfSigmas * sa;
  }
  if (!any) return -1;
  return a_weak ? 0 : b_weak ? 1 : -1;
}

}  // namespace

double block_margined_drop(const std::vector<int>& block, const std::vector<Eigen::Vector2d>& r0,
                           const std::vector<Eigen::Vector2d>& r1, double sigma) {
  std::map<int, double> drops;
  for (size_t k = 0; k < r0.size(); ++k) drops[block[k]] += robust_loss(r0[k], sigma) - robust_loss(r1[k], sigma);
  const double n = static_cast<double>(drops.size());
  if (n < kMinClusters) return -std::numeric_limits<double>::infinity();
  double sum = 0, spread = 0;
  for (const auto& [b, d] : drops) sum += d;
  for (const auto& [b, d] : drops) spread += (d - sum / n) * (d - sum / n);
  return sum + 3.0 * std::sqrt(n / (n - 1) * spread);
}

Halves time_halves(const DiagnosisModel& m, const std::vector<int>& idx) {
  return split_at_median(idx, [&](int i) { return m.frame_time(i); });
}

Halves rate_halves(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p) {
  const auto& g = m.recording().gyro;
  return split_at_median(idx, [&](int i) {
    const double t = m.frame_time(i) + p[Param::TimeOffset];
    auto it = std::lower_bound(g.begin(), g.end(), t, [](const GyroSample& s, double x) { return s.t < x; });
    if (it == g.end()) it = std::prev(g.end());
    return it->w.norm();
  });
}

// An effect that describes the physics predicts what it has not seen; a stand-in, fitted to
// structure that differs between the halves, does not. But a real effect that one half shows
// only weakly (little motion there) may lower that half's chi-square by less than its noise, or
// raise it a little: it holds unless it degrades the half beyond that noise (issue 34, point 3).
// The noise of the drop: with d_i the change the effect makes to observation i's prediction and
// S = sum |d_i|^2 / sigma^2 its signal energy on the half, the drop is S + 2 sum r_i.d_i /
// sigma^2 with standard deviation 2 sqrt(S) for independent noise; the margin is 3 sqrt(S). A
// stand-in's wrong half costs about S itself, far past the margin once S is more than 9.
HalvesFits fit_halves(const DiagnosisModel& m, const Halves& h, const Hypothesis& hyp, double sigma, int iterations) {
  return {{fit_params(m, h.a, hyp.params, hyp.free, sigma, iterations),
           fit_params(m, h.b, hyp.params, hyp.free, sigma, iterations)}};
}

CovariedHalves with_covariances(const DiagnosisModel& m, const Halves& h, const ParamMask& free_mask, const HalvesFits& fits) {
  const std::vector<Param> free = params_in(free_mask);
  const int block = block_frames(m);
  return {fits, {parameter_covariance(m, fits.on[0], free, h.a, block), parameter_covariance(m, fits.on[1], free, h.b, block)}};
}

HalvesVerdict cross_check(const DiagnosisModel& m, const Halves& h, const HalvesFits& poorer, const ParamMask& poorer_free,
                          const CovariedHalves& richer, const ParamMask& richer_free, double sigma) {
  HalvesVerdict v{std::numeric_limits<double>::infinity(), 0};
  const int weak = weak_half(m, richer, richer_free, richer_free & ~poorer_free);
  for (int dir = 0; dir < 2; ++dir) {
    if (dir == weak) continue;  // a weak half's loose fit has no say on the strong half (fit_halves)
    const std::vector<int>& judge = dir ? h.a : h.b;
    const ModelParams& rich = richer.fits.on[dir];
    const auto r0 = m.residuals(poorer.on[dir], judge);
    double drop = margined_drop(m, judge, r0, m.residuals(rich, judge), sigma);
    if (drop < 0) drop = std::max(drop, bulk_drop(m, judge, r0, poorer.on[dir], rich, sigma));
    v.drop = std::min(v.drop, drop);
  }
  v.apart_sigmas = apart(m, richer, poorer.on[0], richer_free, richer_free & ~poorer_free);
  return v;
}

HalvesVerdict cross_check(const DiagnosisModel& m, const Halves& h, const HalvesFits& poorer, const ParamMask& poorer_free,
                          const HalvesFits& richer, const ParamMask& richer_free, double sigma) {
  return cross_check(m, h, poorer, poorer_free, with_covariances(m, h, richer_free, richer), richer_free, sigma);
}

HalvesVerdict cross_check(const DiagnosisModel& m, const Halves& h, const Hypothesis& poorer, const Hypothesis& richer,
                          double sigma, int iterations) {
  return cross_check(m, h, fit_halves(m, h, poorer, sigma, iterations), poorer.free,
                     fit_halves(m, h, richer, sigma, iterations), richer.free, sigma);
}

}  // namespace rsd::dsp
