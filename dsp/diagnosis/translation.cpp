#include "dsp/diagnosis/translation.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <tuple>

#include "dsp/core/statistics.hpp"
#include "dsp/diagnosis/band_cholesky.hpp"
#include "dsp/diagnosis/model.hpp"
#include "dsp/diagnosis/parallax.hpp"
#include "dsp/diagnosis/robust_stats.hpp"

namespace rsd::dsp {

namespace {

// A pair's unknowns: the velocity over depth at its time and that velocity's rate of change
// (world axes), w = (u(t), u'(t)). A match sees the camera move between its two rows' times,
// not between the frames' starts: its velocity is u(t + delta) ~ u(t) + delta u'(t), delta its
// rows' mean time after the frames' (docs/diagnosis.md, "Parallax"). Over a hand's shake the
// velocity changes by up to a tenth across a 25 ms readout, a flow error that grows down the
// image and that a principal point and a mount's pitch took up.
constexpr int kW = 6;
using PairFlow = Eigen::Matrix<double, 2, kW>;

// One frame pair's share of the velocity fit: its time and the normal matrix of its inliers in
// w (world axes), and how a velocity turns into its translation over depth (camera axes):
// beta = dt R^T u. The right-hand sides are kept beside the pairs, rows 6q..6q+5 pair q's (one
// column per set of residuals).
struct PairSums {
  double t = 0;
  Eigen::Matrix3d turn = Eigen::Matrix3d::Zero();
  Eigen::Matrix<double, kW, kW> N = Eigen::Matrix<double, kW, kW>::Zero();
};

// Uniform cubic B-spline: the weights of the four control points at fraction u of an interval.
std::array<double, 4> cubic_weights(double u) {
  const double u2 = u * u, u3 = u2 * u, v = 1 - u;
  return {v * v * v / 6, (3 * u3 - 6 * u2 + 4) / 6, (-3 * u3 + 3 * u2 + 3 * u + 1) / 6, u3 / 6};
}

// Their derivatives by time, over a knot spacing of one.
std::array<double, 4> cubic_slopes(double u) {
  const double v = 1 - u;
  return {-v * v / 2, (3 * u * u - 4 * u) / 2, (-3 * u * u + 2 * u + 1) / 2, u * u / 2};
}

// The velocity spline over [t0, t0 + intervals x knot_s]: a time's first control point, the
// weights of the four and their derivatives by time (what gives u and u' there).
struct Spline {
  double t0, knot;
  int intervals;
  int controls() const { return intervals + 3; }
  int first(double t, std::array<double, 4>& w, std::array<double, 4>& dw) const {
    const double s = (t - t0) / knot;
    const int j = std::clamp(static_cast<int>(std::floor(s)), 0, intervals - 1);
    const double u = std::clamp(s - j, 0.0, 1.0);
    w = cubic_weights(u), dw = cubic_slopes(u);
    for (double& d : dw) d /= knot;
    return j;
  }
};

// The band of the velocity spline's normal matrix: a pair touches four control points of three.
constexpr int kBand = 3 * 4 - 1;

// The normal matrix of the spline's control points: the pairs' N through the spline's weights
// (u(t) and u'(t) both linear in the control points) and a light penalty on the second difference of the control points (it decides only where
// the data leave a direction free: a stretch without pairs, a component no pair shows). A
// pair's time touches four consecutive control points and the penalty three, so it is banded
// (kBand scalars either side of the diagonal), gathered and factorised as a band.
BandCholesky velocity_normal(const Spline& sp, const std::vector<PairSums>& pairs) {
  const int n = 3 * sp.controls();
  Eigen::MatrixXd band = Eigen::MatrixXd::Zero(kBand + 1, n);  // band(i - j + kBand, j) = A(i, j), i <= j
  auto add = [&](int i, int j, double v) {
    if (i <= j) band(i - j + kBand, j) += v;
  };
  double trace = 0;
  for (const PairSums& p : pairs) {
    std::array<double, 4> w, dw;
    const int j = sp.first(p.t, w, dw);
    // Control points a and c: W_a^T N W_c, W_a = (w_a I; dw_a I); its upper triangle, the
    // blocks above the diagonal whole, those on it half.
    const auto N00 = p.N.topLeftCorner<3, 3>(), N01 = p.N.topRightCorner<3, 3>(), N11 = p.N.bottomRightCorner<3, 3>();
    for (int a = 0; a < 4; ++a)
      for (int c = a; c < 4; ++c) {
        const Eigen::Matrix3d M = w[a] * w[c] * N00 + w[a] * dw[c] * N01 + dw[a] * w[c] * N01.transpose() + dw[a] * dw[c] * N11;
        for (int y = 0; y < 3; ++y)
          for (int x = 0; x < (a == c ? y + 1 : 3); ++x) band(kBand + 3 * (a - c) + x - y, 3 * (j + c) + y) += M(x, y);
      }
    trace += N00.trace();
  }
  const double lambda = 1e-4 * trace / n, ridge = 1e-9 * trace / n + 1e-12;
  for (int k = 0; k + 2 < sp.controls(); ++k) {
    const std::array<double, 3> d = {1, -2, 1};
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c)
        for (int x = 0; x < 3; ++x) add(3 * (k + a) + x, 3 * (k + c) + x, lambda * d[a] * d[c]);
  }
  band.row(kBand).array() += ridge;
  return BandCholesky(std::move(band));
}

// Each pair's w, its velocity over depth and that velocity's rate (world axes; rows 6q..6q+5
// pair q's, a column per column of the right-hand sides B, laid out alike) from the spline's
// control points minimising the pairs' squared residuals (their N and B), velocity_normal of
// the same pairs; zero where the normal matrix is not positive definite.
Eigen::MatrixXd pair_velocities(const Spline& sp, const std::vector<PairSums>& pairs, const Eigen::MatrixXd& B) {
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(B.rows(), B.cols());
  const BandCholesky normal = velocity_normal(sp, pairs);
  if (!normal.ok()) return U;
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(normal.size(), B.cols());
  std::array<double, 4> w, dw;
  for (size_t q = 0; q < pairs.size(); ++q) {
    const int j = sp.first(pairs[q].t, w, dw);
    for (int a = 0; a < 4; ++a)
      c.middleRows<3>(3 * (j + a)) += w[a] * B.middleRows<3>(kW * q) + dw[a] * B.middleRows<3>(kW * q + 3);
  }
  normal.solve(c);
  for (size_t q = 0; q < pairs.size(); ++q) {
    const int j = sp.first(pairs[q].t, w, dw);
    for (int a = 0; a < 4; ++a) {
      U.middleRows<3>(kW * q) += w[a] * c.middleRows<3>(3 * (j + a));
      U.middleRows<3>(kW * q + 3) += dw[a] * c.middleRows<3>(3 * (j + a));
    }
  }
  return U;
}

// The pairs' normal equations over the inliers `in` (observations in pair order, flow(k) the
// 2 x 6 flow of observation k per unit w, rk(k) its residual), summed in registers over each
// pair's run of observations and stored once.
template <class Flow, class Residual>
void pair_sums(std::vector<PairSums>& pairs, Eigen::MatrixXd& B, const std::vector<int>& pair_of, const std::vector<bool>& in,
               const Flow& flow, const Residual& rk) {
  B.setZero(kW * static_cast<Eigen::Index>(pairs.size()), 1);
  for (size_t k = 0; k < pair_of.size();) {
    const int q = pair_of[k];
    Eigen::Matrix<double, kW, kW> N = Eigen::Matrix<double, kW, kW>::Zero();
    Eigen::Matrix<double, kW, 1> b = Eigen::Matrix<double, kW, 1>::Zero();
    for (; k < pair_of.size() && pair_of[k] == q; ++k) {
      if (!in[k]) continue;
      const PairFlow Jk = flow(k);
      // The whole 6 x 6 by fixed-size products: a rank update of the upper half alone takes
      // Eigen's blocked matrix-product path, whose packing costs more than the 72 products (the
      // walking phone's minute under parallax: 14% of its profile).
      N.noalias() += Jk.transpose() * Jk;
      b += Jk.transpose() * rk(k);
    }
    pairs[q].N = N, B.middleRows<kW>(kW * q) = b;
  }
}

// The scene's slope g (inverse depth 1 + g . xn over the depth at the optical axis) that best
// explains the inliers' residuals given the translations U: r - f = (g . xn) f, f = J u per
// observation, linear in g. A light ridge keeps g at zero where the translation shows none.
template <class Residual>
Eigen::Vector2d scene_slope(const std::vector<PairFlow>& J, const std::vector<Eigen::Vector2d>& xn,
                            const std::vector<int>& pair_of, const Eigen::MatrixXd& U, const std::vector<bool>& in,
                            const Residual& r) {
  Eigen::Matrix2d N = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (size_t k = 0; k < J.size(); ++k) {
    if (!in[k]) continue;
    const Eigen::Vector2d f = J[k] * U.block<kW, 1>(kW * pair_of[k], 0);
    const Eigen::Matrix2d A = f * xn[k].transpose();  // d(flow)/dg
    N += A.transpose() * A, b += A.transpose() * (r(k) - f);
  }
  N.diagonal().array() += 1e-3 * N.trace() + 1e-12;
  return N.ldlt().solve(b);
}

}  // namespace

// The observations of one set of residuals, grouped by frame pair (frame_a's rank and frame_b's
// time: a frame may be matched to more than one other), with what their translation flow needs.
// It depends only on which observations had a residual: a fit asks for the same grouping at every
// trial point, and the one its last residuals settled on is taken again when it is the same.
struct PairGroups {
  std::vector<int> idx;          // the observations grouped
  std::vector<bool> finite;      // which of them had a residual
  std::vector<size_t> position;  // per observation taken, in pair order: its place in idx
  std::vector<int> pair_of;      // its pair
  std::vector<Eigen::Matrix<double, 2, 3>> unit;  // its flow per unit translation, camera axes
  std::vector<Eigen::Vector2d> xn;  // its normalised image coordinates
  std::vector<size_t> pair_first;   // each pair's first observation (position in idx)
  bool same(const std::vector<int>& of, const std::vector<Eigen::Vector2d>& r) const {
    if (of != idx || r.size() != finite.size()) return false;
    for (size_t k = 0; k < r.size(); ++k)
      if (r[k].allFinite() != finite[k]) return false;
    return true;
  }
};

struct TranslationFit::State {
  std::shared_ptr<const PairGroups> groups;
  std::vector<bool> in;  // after the passes: whether each grouped observation was an inlier of the last
  Eigen::Vector2d slope = Eigen::Vector2d::Zero();  // after the passes: the scene's slope
};

namespace {

// The observations of `r` that have a residual, by pair: `prior`'s when it grouped the same.
std::shared_ptr<const PairGroups> group_by_pair(const DiagnosisModel& m, const std::vector<int>& idx,
                                                const std::vector<Eigen::Vector2d>& r,
                                                const std::shared_ptr<const PairGroups>& prior) {
  if (prior && prior->same(idx, r)) return prior;
  struct Member {
    int rank;
    double t_b;
    size_t second;  // position in idx
    bool operator<(const Member& o) const { return std::tie(rank, t_b, second) < std::tie(o.rank, o.t_b, o.second); }
    bool same_pair(const Member& o) const { return rank == o.rank && t_b == o.t_b; }
  };
  std::vector<Member> by_pair;
  by_pair.reserve(idx.size());
  for (size_t k = 0; k < idx.size(); ++k)
    if (r[k].allFinite()) by_pair.push_back({m.frame_rank(idx[k]), m.frame_time_b(idx[k]), k});
  std::sort(by_pair.begin(), by_pair.end());
  auto s = std::make_shared<PairGroups>();
  const CameraModel& cam = m.recording().nominal.cam;
  s->idx = idx;
  s->finite.resize(r.size());
  for (size_t k = 0; k < r.size(); ++k) s->finite[k] = r[k].allFinite();
  for (size_t k = 0; k < by_pair.size(); ++k) {
    const size_t at = by_pair[k].second;
    const Eigen::Vector2d px = m.observed(idx[at]);
    if (k == 0 || !by_pair[k].same_pair(by_pair[k - 1])) s->pair_first.push_back(at);
    s->position.push_back(at);
    s->pair_of.push_back(static_cast<int>(s->pair_first.size()) - 1);
    s->unit.push_back(translation_flow(cam, px));
    s->xn.emplace_back((px.x() - cam.cx) / cam.fx, (px.y() - cam.cy) / cam.fy);
  }
  return s;
}

// Each pair's time on the spline and how a velocity (world axes) turns into its translation
// over depth (camera axes), at the parameters of `track`, `tm`, `mount_t`.
std::vector<PairSums> pairs_at(const DiagnosisModel& m, const std::vector<int>& idx, const PairGroups& s,
                               const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t) {
  std::vector<PairSums> pairs(s.pair_first.size());
  for (size_t q = 0; q < pairs.size(); ++q) {
    const int i = idx[s.pair_first[q]];
    pairs[q].t = 0.5 * (m.frame_time(i) + m.frame_time_b(i));
    const Eigen::Matrix3d world_from_camera = track.camera_at(tm.motion_time(m.frame_time(i))) * mount_t;
    pairs[q].turn = (m.frame_time_b(i) - m.frame_time(i)) * world_from_camera.transpose();
  }
  return pairs;
}

// Each grouped observation's flow per unit w (world axes, the plane's depth factor left out):
// its pair's turn, of the velocity at its rows' mean time, delta after the pair's (row_timing
// of `tm`), u(t) + delta u'(t). Over the frames' time apart still: the time between the
// match's rows differs from it by the rows it moved times the line delay, a percent or less,
// and taken in, it let the line delay shape the translation's flow: a forward flight past a
// scene the plane cannot describe (the suite's drone) had its line delay 10% off, from 1.4%.
std::vector<PairFlow> match_flows(const DiagnosisModel& m, const std::vector<int>& idx, const PairGroups& s,
                                  const std::vector<PairSums>& pairs, const TimeModel& tm) {
  const RowTiming rt = row_timing(tm, m.recording().nominal.cam.height);
  std::vector<PairFlow> J(s.position.size());
  for (size_t k = 0; k < J.size(); ++k) {
    const int i = idx[s.position[k]];
    const double row_a = rt.row_time(m.observed_a(i).y()), row_b = rt.row_time(m.observed(i).y());
    const Eigen::Matrix<double, 2, 3> F = s.unit[k] * pairs[s.pair_of[k]].turn;
    J[k] << F, (0.5 * (row_a + row_b)) * F;
  }
  return J;
}

Spline spline_over(const std::vector<PairSums>& pairs, double knot_s) {
  double t_lo = pairs.front().t, t_hi = t_lo;
  for (const PairSums& p : pairs) t_lo = std::min(t_lo, p.t), t_hi = std::max(t_hi, p.t);
  return {t_lo, knot_s, std::max(1, static_cast<int>(std::ceil((t_hi - t_lo) / knot_s)))};
}

}  // namespace

void remove_translation(const DiagnosisModel& m, const std::vector<int>& idx, std::vector<Eigen::Vector2d>& r,
                        const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t, double knot_s,
                        TranslationFit* keep) {
  std::shared_ptr<const TranslationFit::State> prior;
  if (keep) prior = std::move(keep->state), keep->state.reset();
  auto st = std::make_shared<TranslationFit::State>();
  st->groups = group_by_pair(m, idx, r, prior ? prior->groups : nullptr);
  TranslationFit::State& fit = *st;
  const PairGroups& s = *fit.groups;
  if (s.position.empty()) return;
  std::vector<PairSums> pairs = pairs_at(m, idx, s, track, tm, mount_t);
  const Spline sp = spline_over(pairs, knot_s);
  const size_t n = s.position.size();
  const std::vector<PairFlow> J = match_flows(m, idx, s, pairs, tm);  // per unit w, world axes
  std::vector<Eigen::Vector2d> rk(n);                                // the residuals in pair order
  for (size_t k = 0; k < n; ++k) rk[k] = r[s.position[k]];
  // Four passes from no translation over a flat scene: the inliers are the residuals within 4
  // robust scales of the current fit (one scale for the whole set: the noise does not depend on
  // the pair, and a pair with a handful of observations is judged as well as one with
  // hundreds). From the second on, the scene's slope too (scene_slope): one plane's inverse
  // depth is affine in the normalised image coordinates, and a ground ahead of a forward-flying
  // drone or a car leaves, at one depth, pixels of parallax growing towards the image's bottom.
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(kW * static_cast<Eigen::Index>(pairs.size()), 1), B;
  std::vector<double> len(n);
  fit.in.assign(n, false);
  auto depth_factor = [&](size_t k) { return 1.0 + fit.slope.dot(s.xn[k]); };
  auto flow = [&](size_t k) { return Eigen::Vector2d(depth_factor(k) * (J[k] * U.block<kW, 1>(kW * s.pair_of[k], 0))); };
  auto left = [&](size_t k) { return Eigen::Vector2d(rk[k] - flow(k)); };
  for (int pass = 0; pass < 4; ++pass) {
    for (size_t k = 0; k < n; ++k) len[k] = left(k).norm();
    const double limit = 4 * std::max(median(len) / std::sqrt(2 * std::log(2.0)), 1e-6);
    for (size_t k = 0; k < n; ++k) fit.in[k] = len[k] <= limit;
    if (pass >= 1) fit.slope = scene_slope(J, s.xn, s.pair_of, U, fit.in, [&](size_t k) { return rk[k]; });
    pair_sums(pairs, B, s.pair_of, fit.in, [&](size_t k) { return PairFlow(depth_factor(k) * J[k]); },
              [&](size_t k) { return rk[k]; });
    U = pair_velocities(sp, pairs, B);
  }
  for (size_t k = 0; k < n; ++k) r[s.position[k]] = left(k);
  if (keep) keep->state = st;
}

void remove_fitted_translation(const DiagnosisModel& m, const std::vector<int>& idx, std::vector<Eigen::Vector2d>& r,
                               const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t, double knot_s,
                               const TranslationFit& fit) {
  if (!fit.state) return remove_translation(m, idx, r, track, tm, mount_t, knot_s);
  const PairGroups& s = *fit.state->groups;
  if (r.size() != s.idx.size() || idx.size() != s.idx.size())
    throw std::invalid_argument("remove_fitted_translation: residuals of other observations than the fit's");
  std::vector<PairSums> pairs = pairs_at(m, idx, s, track, tm, mount_t);
  const Spline sp = spline_over(pairs, knot_s);
  // An observation the fit had whose prediction fails here is left out of it (and stays NaN).
  std::vector<bool> in = fit.state->in;
  for (size_t k = 0; k < in.size(); ++k) in[k] = in[k] && r[s.position[k]].allFinite();
  const Eigen::Vector2d slope = fit.state->slope;
  const std::vector<PairFlow> J = match_flows(m, idx, s, pairs, tm);
  auto flow = [&](size_t k) { return PairFlow((1.0 + slope.dot(s.xn[k])) * J[k]); };
  Eigen::MatrixXd B;
  pair_sums(pairs, B, s.pair_of, in, flow, [&](size_t k) { return r[s.position[k]]; });
  const Eigen::MatrixXd U = pair_velocities(sp, pairs, B);
  for (size_t k = 0; k < s.position.size(); ++k) r[s.position[k]] -= flow(k) * U.block<kW, 1>(kW * s.pair_of[k], 0);
}

void remove_fitted_translation_from_columns(const DiagnosisModel& m, const std::vector<int>& idx, Eigen::MatrixXd& cols,
                                            const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t,
                                            double knot_s, const TranslationFit& fit) {
  if (!fit.state || cols.cols() == 0) return;
  const PairGroups& s = *fit.state->groups;
  const std::vector<bool>& in = fit.state->in;
  const Eigen::Vector2d slope = fit.state->slope;
  if (static_cast<size_t>(cols.rows()) != 2 * s.idx.size() || idx.size() != s.idx.size())
    throw std::invalid_argument("remove_fitted_translation_from_columns: columns of other observations than the fit's");
  std::vector<PairSums> pairs = pairs_at(m, idx, s, track, tm, mount_t);
  const Spline sp = spline_over(pairs, knot_s);
  auto rows = [&](size_t k) { return cols.middleRows<2>(2 * static_cast<Eigen::Index>(s.position[k])); };
  std::vector<PairFlow> F = match_flows(m, idx, s, pairs, tm);
  for (size_t k = 0; k < F.size(); ++k) F[k] *= 1.0 + slope.dot(s.xn[k]);
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(kW * static_cast<Eigen::Index>(pairs.size()), cols.cols());
  for (size_t k = 0; k < F.size(); ++k) {
    if (!in[k] || !rows(k).allFinite()) continue;
    const int q = s.pair_of[k];
    pairs[q].N += F[k].transpose() * F[k], B.middleRows<kW>(kW * q) += F[k].transpose() * rows(k);
  }
  const Eigen::MatrixXd U = pair_velocities(sp, pairs, B);
  for (size_t k = 0; k < F.size(); ++k) rows(k) -= F[k] * U.middleRows<kW>(kW * s.pair_of[k]);
}

double translation_knot_spacing(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p) {
  std::vector<int> ranks;
  double t_lo = std::numeric_limits<double>::infinity(), t_hi = -t_lo;
  for (int i : idx) ranks.push_back(m.frame_rank(i)), t_lo = std::min(t_lo, m.frame_time(i)), t_hi = std::max(t_hi, m.frame_time(i));
  std::sort(ranks.begin(), ranks.end());
  const double pairs = static_cast<double>(std::unique(ranks.begin(), ranks.end()) - ranks.begin());
  ModelParams q = p;
  q.translation_nuisance = true;
  q.translation_knot_s = kTranslationKnotsS[0];
  double scale = robust_stats(m.residuals(q, idx)).scale_px;
  for (size_t k = 1; k < kTranslationKnotsS.size(); ++k) {
    if (pairs < 2 * (t_hi - t_lo) / kTranslationKnotsS[k]) break;
    ModelParams finer = q;
    finer.translation_knot_s = kTranslationKnotsS[k];
    const double s = robust_stats(m.residuals(finer, idx)).scale_px;
    if (!(s < (1 - kFinerKnotsGain) * scale)) break;
    q = finer, scale = s;
  }
  return q.translation_knot_s;
}

}  // namespace rsd::dsp
