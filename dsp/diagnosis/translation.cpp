#include "dsp/diagnosis/translation.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#include "dsp/core/statistics.hpp"
#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/row_timing.hpp"
#include "dsp/diagnosis/model.hpp"
#include "dsp/diagnosis/own_depth.hpp"
#include "dsp/diagnosis/parallax.hpp"
#include "dsp/diagnosis/robust_stats.hpp"
#include "dsp/diagnosis/velocity_spline.hpp"

namespace rsd::dsp {

namespace {

// A pair's unknowns: the velocity over depth at its time and that velocity's rate of change
// (world axes), w = (u(t), u'(t)). A match sees the camera move between its two rows' times,
// not between the frames' starts: its velocity is u(t + delta) ~ u(t) + delta u'(t), delta its
// rows' mean time after the frames' (docs/diagnosis.md, "Parallax"). Over a hand's shake the
// velocity changes by up to a tenth across a 25 ms readout, a flow error that grows down the
// image and that a principal point and a mount's pitch took up.
//
// A match's flow per unit w is d unit T (u + delta u'): d the plane's depth factor at it,
// unit its flow per unit translation (camera axes, fixed by its pixel), T its pair's turn into
// camera axes over the frames' time apart. What moves with the parameters is two scalars per
// match (d with the scene's slope, delta with the line delay) and a 3 x 3 per pair, so a pair's
// normal equations are T^T (sum of d^2 unit^T unit, weighted by 1, delta, delta^2) T, and a
// match's 2 x 6 flow is never formed (it was a sixth of the walking phone's minute under
// parallax, with the sums over it).
constexpr int kW = VelocitySpline::kUnknowns;

// One frame pair's share of the velocity fit: its time and the normal matrix of its inliers in
// w (world axes), and how a velocity turns into its translation over depth (camera axes):
// beta = dt R^T u. The right-hand sides are kept beside the pairs, rows 6q..6q+5 pair q's (one
// column per set of residuals).
struct PairSums {
  double t = 0;
  Eigen::Matrix3d orientation = Eigen::Matrix3d::Identity();  // world from camera at its first frame
  Eigen::Matrix3d turn = Eigen::Matrix3d::Zero();
  Eigen::Matrix<double, kW, kW> N = Eigen::Matrix<double, kW, kW>::Zero();
  // The pair's time shift (pair_shift_sd, translation.hpp): the rotation a shift of one second
  // turns the pair by (camera axes, the rate's change over the pair), and what eliminating it
  // leaves for w: the shift is gain (b_s - coupling w), b_s its right-hand side (pair_sums).
  Eigen::Vector3d shift_axis = Eigen::Vector3d::Zero();
  double shift_gain = 0;
  Eigen::Matrix<double, 1, kW> shift_coupling = Eigen::Matrix<double, 1, kW>::Zero();
};

}  // namespace

double pair_shift_sd(const DiagnosisModel& m) {
  const StampSpread& s = m.gyro_stamps();
  const double sd = std::sqrt(std::max(0.0, s.jitter_s * s.jitter_s - s.moved_rms_s * s.moved_rms_s));
  return sd < kMinPairShiftS ? 0.0 : sd;
}

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
  bool shifts = false;               // whether the pairs shift in time (pair_shift_sd)
  std::vector<double> mean_row;     // the mean of its two rows (the rows' mean time is affine in it)
  std::vector<Eigen::Vector2d> xn;  // its normalised image coordinates
  std::vector<size_t> pair_first;   // each pair's first observation (position in idx)
  bool same(const std::vector<int>& of, const std::vector<Eigen::Vector2d>& r) const {
    if (of != idx || r.size() != finite.size()) return false;
    for (size_t k = 0; k < r.size(); ++k)
      if (r[k].allFinite() != finite[k]) return false;
    return true;
  }
};

// The scene's plane, fixed in the world, as each grouped observation sees it: its inverse depth
// over the plane's at the middle pair's optical axis is a + g . b, g the plane's slope in the
// middle pair's camera and (b, a) the observation's ray (xn, 1) turned into that camera's axes.
// A wall or a ground stays where it is while the camera turns, and its tilt in each pair's camera
// follows the turn: a plane that turned with every pair's camera left a wall's tilt, whose flow
// holds a rotation's monomials (x^2, x y), for a gyro bias to take (docs/diagnosis.md, "Parallax").
struct ScenePlane {
  std::vector<double> a;
  std::vector<Eigen::Vector2d> b;
  double factor(size_t k, const Eigen::Vector2d& g) const { return a[k] + g.dot(b[k]); }
};

struct TranslationFit::State {
  std::shared_ptr<const PairGroups> groups;
  // The rays' turns into the middle pair's camera, taken once, at the orientations the passes
  // first ran at: a gyro's bias, scale or drift turns the integrated orientations and with them a
  // plane turned at every trial point, a path by which they would mimic the scene's tilt.
  std::shared_ptr<const ScenePlane> plane;
  std::vector<bool> in;  // after the passes: whether each grouped observation was an inlier of the last
  Eigen::Vector2d slope = Eigen::Vector2d::Zero();  // after the passes: the scene's slope
  double shift_rho = 0;  // the pairs' shift prior, noise^2 / shift sd^2 at the last pass; 0: no shifts
  // After the passes: each grouped observation's own depth (own_depths), empty without one; and
  // what translation_depth_spread measures from: the last pass's velocities (camera axes), the
  // matches' rows' delays and the pass's robust scale.
  std::vector<Eigen::Vector2d> own_depth;
  Eigen::MatrixXd velocities;
  std::vector<double> delta;
  double scale = 0;
  // And what translation_travel integrates: the last pass's velocities in world axes (rows
  // 6q..6q+5 pair q's u and u'), the pairs' times and the middle pair's orientation.
  bool world_plane = false;
  Eigen::MatrixXd world_velocities;
  std::vector<double> pair_t;
  Eigen::Matrix3d middle = Eigen::Matrix3d::Identity();
};

namespace {

// The observations of `r` that have a residual, by pair: `prior`'s when it grouped the same.
std::shared_ptr<const PairGroups> group_by_pair(const DiagnosisModel& m, const std::vector<int>& idx,
                                                const std::vector<Eigen::Vector2d>& r,
                                                const std::shared_ptr<const PairGroups>& prior, bool with_shifts) {
  const bool shifts = with_shifts && pair_shift_sd(m) > 0;
  if (prior && prior->shifts == shifts && prior->same(idx, r)) return prior;
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
  s->shifts = shifts;
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
    s->mean_row.push_back(0.5 * (m.observed_a(idx[at]).y() + px.y()));
    s->xn.emplace_back((px.x() - cam.cx) / cam.fx, (px.y() - cam.cy) / cam.fy);
  }
  return s;
}

// Each pair's time on the spline and how a velocity (world axes) turns into its translation
// over depth (camera axes), at the parameters of `track`, `tm`, `mount_t`.
std::vector<PairSums> pairs_at(const DiagnosisModel& m, const std::vector<int>& idx, const PairGroups& s,
                               const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t) {
  std::vector<PairSums> pairs(s.pair_first.size());
  // Pairs in frame order: each lookup walks on from the last one's knot. The rate at frame_b is
  // mostly the next pair's at its frame_a (consecutive frames).
  size_t hint_a = 0, hint_b = 0;
  Eigen::Vector3d w_a = Eigen::Vector3d::Zero();
  for (size_t q = 0; q < pairs.size(); ++q) {
    const int i = idx[s.pair_first[q]];
    const double t_a = m.frame_time(i), t_b = m.frame_time_b(i);
    pairs[q].t = 0.5 * (t_a + t_b);
    pairs[q].orientation = track.camera_at(tm.motion_time(t_a), hint_a) * mount_t;
    pairs[q].turn = (t_b - t_a) * pairs[q].orientation.transpose();
    if (!s.shifts) continue;
    if (q == 0 || t_a != m.frame_time_b(idx[s.pair_first[q - 1]])) w_a = track.rate_at(tm.motion_time(t_a), hint_a);
    const Eigen::Vector3d w_b = track.rate_at(tm.motion_time(t_b), hint_b);
    pairs[q].shift_axis = mount_t.transpose() * (w_b - w_a);
    w_a = w_b;
  }
  return pairs;
}

// Each grouped observation's rows' mean time after its pair's (row_timing of `tm`): the delta
// of its velocity u(t) + delta u'(t). Over the frames' time apart still: the time between the
// match's rows differs from it by the rows it moved times the line delay, a percent or less,
// and taken in, it let the line delay shape the translation's flow: a forward flight past a
// scene the plane cannot describe (the suite's drone) had its line delay 10% off, from 1.4%.
std::vector<double> row_delays(const DiagnosisModel& m, const PairGroups& s, const TimeModel& tm) {
  const RowTiming rt = row_timing(tm, m.recording().nominal.cam.height);
  const double v0 = rt.v0(), per_row = 1.0 / rt.r();  // row_time(v) = (v + v0) / r
  std::vector<double> delta(s.position.size());
  for (size_t k = 0; k < delta.size(); ++k) delta[k] = (s.mean_row[k] + v0) * per_row;
  return delta;
}

// Below this cosine between a pair's optical axis and the middle pair's (60 degrees apart) the
// pair's rays are taken in its own camera: a plane seen across such a turn is seldom one plane
// (a pan past a wall looks at another), and its rays would meet the middle pair's plane far
// off or behind the camera.
constexpr double kMinPlaneAxisCos = 0.5;

// Each grouped observation's ray in the middle pair's camera axes (ScenePlane): its pixel in
// frame_b through `cam` (the parameters' intrinsics and lens: the nominal focal length may be off
// by a sixth before the fit), turned by the camera's orientation when its row was read (a
// readout of 25 ms under a hand's 2 rad/s turns a row's ray by 0.05 rad against the frame's
// start, a share of the parallax growing down the image). Without `world`, each in its own
// pair's camera at the nominal intrinsics (the plane's slope takes their scale up).
std::shared_ptr<const ScenePlane> plane_at(const DiagnosisModel& m, const PairGroups& s, const std::vector<PairSums>& pairs,
                                           bool world, const GyroTrack& track, const TimeModel& tm,
                                           const Eigen::Matrix3d& mount_t, const CameraModel& cam) {
  auto plane = std::make_shared<ScenePlane>();
  plane->a.assign(s.xn.size(), 1.0);
  plane->b = s.xn;
  if (!world) return plane;
  // The gyro's orientation is integrated across its gaps, and over a gap longer than the model's
  // max_gyro_gap (a logger's dropped samples: the matches across it are not used) it is off by
  // what the interpolation missed, tenths of a radian under a hand's shake: whole frames' planes
  // were off by pixels. Each stretch between such gaps turns its rays into its own middle pair's
  // camera (one slope g for all: between stretches the plane's tilt is taken as the same, as
  // the plane before each pair's camera takes it everywhere).
  std::vector<double> gap_ends;  // motion clock
  const std::vector<GyroSample>& gyro = m.recording().gyro;
  for (size_t j = 1; j < gyro.size(); ++j)
    if (gyro[j].t - gyro[j - 1].t > m.max_gyro_gap()) gap_ends.push_back(gyro[j].t);
  auto stretch = [&](double t) { return std::upper_bound(gap_ends.begin(), gap_ends.end(), t) - gap_ends.begin(); };
  std::vector<std::vector<size_t>> pairs_in(gap_ends.size() + 1);
  for (size_t q = 0; q < pairs.size(); ++q)
    pairs_in[static_cast<size_t>(stretch(tm.motion_time(m.frame_time(s.idx[s.pair_first[q]]))))].push_back(q);
  const RowTiming rt = row_timing(tm, cam.height);
  size_t hint = 0;
  for (size_t k = 0; k < s.xn.size(); ++k) {
    const int i = s.idx[s.position[k]];
    const Eigen::Vector2d px = m.observed(i);
    const double t = tm.motion_time(m.frame_time_b(i) + rt.row_time(px.y()));
    const std::vector<size_t>& in = pairs_in[static_cast<size_t>(stretch(t))];
    const std::optional<Eigen::Vector3d> ray = cam.ray(px);
    if (in.empty() || !ray || ray->z() <= 0) continue;
    const Eigen::Matrix3d middle_t = pairs[in[in.size() / 2]].orientation.transpose();
    if ((middle_t * pairs[static_cast<size_t>(s.pair_of[k])].orientation)(2, 2) < kMinPlaneAxisCos) continue;
    const Eigen::Vector3d turned = middle_t * track.camera_at(t, hint) * mount_t * (*ray / ray->z());
    plane->a[k] = turned.z(), plane->b[k] = turned.head<2>();
  }
  return plane;
}

// The pairs' normal equations in w (PairSums::N) and their right-hand sides B (rows 6q..6q+5
// pair q's, `columns` columns) over the inliers `in` of the grouped observations, in pair order:
// depth(k) is observation k's depth factor, delta[k] its rows' time after its pair's, rk(k) its
// residuals (2 x Cols). A pair's run of observations is summed before its turn T is applied:
// with F = d unit T, F^T F = d^2 T^T (unit^T unit) T and F^T r = d T^T (unit^T r).
//
// With `shift_rho` > 0 each pair also shifts in time (pair_shift_sd): observation k's flow per
// second of it is flows[k] = s_k (shift_flows), and the shift, one scalar under the prior shift_rho, is
// eliminated beside w: N - c^T c / (s.s + rho) and B - c^T b_s / (s.s + rho), c = sum s_k^T F_k
// its coupling to w, b_s = sum s_k^T r_k its right-hand side (rows of `Bs`, one per pair).
//
// With `own` (own_depths) each match's inner products are taken in its own metric P_k = I - b b^T,
// which eliminates its own depth beside w: unit^T P unit, unit^T P r and the shift's likewise.
template <int Cols, class Depth, class Residual>
void pair_sums(std::vector<PairSums>& pairs, Eigen::MatrixXd& B, Eigen::MatrixXd& Bs, Eigen::Index columns,
               const PairGroups& s, const std::vector<double>& delta, const std::vector<bool>& in, const Depth& depth,
               const Residual& rk, const std::vector<Eigen::Vector2d>& flows, double shift_rho,
               const std::vector<Eigen::Vector2d>& own) {
  B.setZero(kW * static_cast<Eigen::Index>(pairs.size()), columns);
  const bool shifts = shift_rho > 0 && !flows.empty();
  Bs.setZero(shifts ? static_cast<Eigen::Index>(pairs.size()) : 0, columns);
  Eigen::Matrix<double, 3, Cols> c0(3, columns), c1(3, columns), g(3, columns);
  Eigen::Matrix<double, 1, Cols> bs(1, columns);
  // unit^T unit is symmetric: its six distinct entries, weighted by d^2 (1, delta, delta^2).
  auto symmetric = [](const Eigen::Matrix<double, 6, 1>& u) {
    return (Eigen::Matrix3d() << u[0], u[1], u[2], u[1], u[3], u[4], u[2], u[4], u[5]).finished();
  };
  for (size_t k = 0; k < s.pair_of.size();) {
    const int q = s.pair_of[k];
    Eigen::Matrix<double, 6, 3> S = Eigen::Matrix<double, 6, 3>::Zero();
    c0.setZero(), c1.setZero(), bs.setZero();
    double ss = 0;
    Eigen::RowVector3d p0 = Eigen::RowVector3d::Zero(), p1 = Eigen::RowVector3d::Zero();
    for (; k < s.pair_of.size() && s.pair_of[k] == q; ++k) {
      if (!in[k]) continue;
      const double d = depth(k), e = delta[k], d2 = d * d;
      const Eigen::Matrix<double, 2, 3>& a = s.unit[k];
      const Eigen::Vector2d b = own.empty() ? Eigen::Vector2d::Zero() : own[k];
      const Eigen::Vector3d ub = a.transpose() * b;
      const Eigen::Matrix<double, 6, 1> G =
          (Eigen::Matrix<double, 6, 1>() << a.col(0).squaredNorm() - ub[0] * ub[0], a.col(0).dot(a.col(1)) - ub[0] * ub[1],
           a.col(0).dot(a.col(2)) - ub[0] * ub[2], a.col(1).squaredNorm() - ub[1] * ub[1],
           a.col(1).dot(a.col(2)) - ub[1] * ub[2], a.col(2).squaredNorm() - ub[2] * ub[2]).finished();
      S.noalias() += G * Eigen::RowVector3d(d2, d2 * e, d2 * e * e);
      const Eigen::Matrix<double, 1, Cols> br = b.transpose() * rk(k);
      g.noalias() = a.transpose() * rk(k) - ub * br;
      c0 += d * g, c1 += (d * e) * g;
      if (!shifts) continue;
      const Eigen::Vector2d& sk = flows[k];
      const double sb = sk.dot(b);
      const Eigen::RowVector3d su = sk.transpose() * a - sb * ub.transpose();
      ss += sk.squaredNorm() - sb * sb, p0 += d * su, p1 += (d * e) * su;
      bs.noalias() += sk.transpose() * rk(k) - sb * br;
    }
    PairSums& p = pairs[q];
    const Eigen::Matrix3d T = p.turn, Tt = T.transpose();
    Eigen::Matrix<double, kW, kW>& N = p.N;
    const Eigen::Matrix3d N00 = Tt * symmetric(S.col(0)) * T, N01 = Tt * symmetric(S.col(1)) * T,
                          N11 = Tt * symmetric(S.col(2)) * T;
    N << N00, N01, N01.transpose(), N11;
    B.middleRows<3>(kW * q).noalias() = Tt * c0, B.middleRows<3>(kW * q + 3).noalias() = Tt * c1;
    if (!shifts) continue;
    p.shift_coupling << p0 * T, p1 * T;
    p.shift_gain = 1.0 / (ss + shift_rho);
    N.noalias() -= p.shift_gain * p.shift_coupling.transpose() * p.shift_coupling;
    B.middleRows<kW>(kW * q).noalias() -= p.shift_gain * p.shift_coupling.transpose() * bs;
    Bs.row(q) = bs;
  }
}

// Each grouped observation's flow per second of its pair's time shift, s_k = turn_k axis (camera
// axes), at the pairs' axes; empty without shifts.
std::vector<Eigen::Vector2d> shift_flows(const DiagnosisModel& m, const PairGroups& s, const std::vector<PairSums>& pairs) {
  if (!s.shifts) return {};
  const CameraModel& cam = m.recording().nominal.cam;
  std::vector<Eigen::Vector2d> flow(s.xn.size());
  for (size_t k = 0; k < flow.size(); ++k)
    flow[k] = rotation_flow_at(cam, s.xn[k]) * pairs[static_cast<size_t>(s.pair_of[k])].shift_axis;
  return flow;
}

// Each pair's time shift (rows of pairs, a column per column of U) given the velocities U
// (world axes) it was eliminated beside: gain (b_s - coupling w). Empty without shifts.
Eigen::MatrixXd pair_shifts(const std::vector<PairSums>& pairs, const Eigen::MatrixXd& Bs, const Eigen::MatrixXd& U) {
  Eigen::MatrixXd shift = Bs;
  for (Eigen::Index q = 0; q < Bs.rows(); ++q) {
    const PairSums& p = pairs[static_cast<size_t>(q)];
    for (Eigen::Index c = 0; c < Bs.cols(); ++c)
      shift(q, c) = p.shift_gain * (Bs(q, c) - p.shift_coupling.dot(U.block<kW, 1>(kW * q, c)));
  }
  return shift;
}

// Observation k's flow from its pair's time shift, one column of them (zero without shifts).
inline Eigen::Vector2d shift_flow(const PairGroups& s, const std::vector<Eigen::Vector2d>& flows,
                                  const Eigen::MatrixXd& shift, size_t k, Eigen::Index column = 0) {
  if (shift.rows() == 0) return Eigen::Vector2d::Zero();
  return flows[k] * shift(s.pair_of[k], column);
}

// The pairs' velocities U (world axes, rows 6q..6q+5 pair q's u and u') turned into camera axes
// over the frames' time apart, in place: T u and T u', a match's flow then d unit (T u + delta T u').
Eigen::MatrixXd in_camera_axes(const std::vector<PairSums>& pairs, Eigen::MatrixXd U) {
  for (size_t q = 0; q < pairs.size(); ++q)
    for (int h = 0; h < kW; h += 3)
      for (Eigen::Index c = 0; c < U.cols(); ++c) {
        const Eigen::Vector3d u = U.block<3, 1>(kW * q + h, c);
        U.block<3, 1>(kW * q + h, c) = pairs[q].turn * u;
      }
  return U;
}

// Observation k's flow at depth factor one for pair velocities V in camera axes (in_camera_axes),
// one column of them.
inline Eigen::Vector2d unit_depth_flow(const PairGroups& s, const std::vector<double>& delta, const Eigen::MatrixXd& V,
                                size_t k, Eigen::Index column = 0) {
  const Eigen::Index at = kW * static_cast<Eigen::Index>(s.pair_of[k]);
  return s.unit[k] * (V.block<3, 1>(at, column) + delta[k] * V.block<3, 1>(at + 3, column));
}

// f(k) for k < n, as a vector.
template <class F>
std::vector<Eigen::Vector2d> over(size_t n, const F& f) {
  std::vector<Eigen::Vector2d> v(n);
  for (size_t k = 0; k < n; ++k) v[k] = f(k);
  return v;
}

// The scene's slope g (inverse depth a + g . b over the depth at the middle pair's optical axis,
// ScenePlane) that best explains the inliers' residuals given the pairs' velocities V (camera
// axes): r - a f = (g . b) f, f the flow at depth factor one, linear in g. A light ridge keeps g
// at zero where the translation shows none.
template <class Residual>
Eigen::Vector2d scene_slope(const PairGroups& s, const ScenePlane& plane, const std::vector<double>& delta,
                            const Eigen::MatrixXd& V, const std::vector<bool>& in, const Residual& r) {
  Eigen::Matrix2d N = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (size_t k = 0; k < s.position.size(); ++k) {
    if (!in[k]) continue;
    const Eigen::Vector2d f = unit_depth_flow(s, delta, V, k);
    const Eigen::Matrix2d A = f * plane.b[k].transpose();  // d(flow)/dg
    N += A.transpose() * A, b += A.transpose() * (r(k) - plane.a[k] * f);
  }
  N.diagonal().array() += 1e-3 * N.trace() + 1e-12;
  return N.ldlt().solve(b);
}

// The velocity spline over the pairs' times, knot_s apart.
VelocitySpline spline_over(const std::vector<PairSums>& pairs, double knot_s) {
  std::vector<double> t(pairs.size());
  for (size_t q = 0; q < pairs.size(); ++q) t[q] = pairs[q].t;
  return VelocitySpline(t, knot_s);
}

// Each pair's w from the spline (VelocitySpline::velocities) through the pairs' N.
Eigen::MatrixXd pair_velocities(VelocitySpline& sp, const std::vector<PairSums>& pairs, const Eigen::MatrixXd& B) {
  sp.clear();
  for (size_t q = 0; q < pairs.size(); ++q) sp.add(q, pairs[q].N);
  return sp.velocities(B);
}

}  // namespace

void remove_translation(const DiagnosisModel& m, const std::vector<int>& idx, std::vector<Eigen::Vector2d>& r,
                        const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t, double knot_s,
                        TranslationFit* keep, bool with_shifts, double depth_px, bool world_plane,
                        const CameraModel* ray_cam) {
  std::shared_ptr<const TranslationFit::State> prior;
  if (keep) prior = std::move(keep->state), keep->state.reset();
  auto st = std::make_shared<TranslationFit::State>();
  st->groups = group_by_pair(m, idx, r, prior ? prior->groups : nullptr, with_shifts);
  TranslationFit::State& fit = *st;
  const PairGroups& s = *fit.groups;
  if (s.position.empty()) return;
  std::vector<PairSums> pairs = pairs_at(m, idx, s, track, tm, mount_t);
  const bool same_plane = prior && prior->groups == fit.groups && prior->plane && prior->world_plane == world_plane;
  const CameraModel& cam = ray_cam ? *ray_cam : m.recording().nominal.cam;
  fit.plane = same_plane ? prior->plane : plane_at(m, s, pairs, world_plane, track, tm, mount_t, cam);
  fit.world_plane = world_plane;
  const ScenePlane& plane = *fit.plane;
  VelocitySpline sp = spline_over(pairs, knot_s);
  const size_t n = s.position.size();
  std::vector<double> delta = row_delays(m, s, tm);
  std::vector<Eigen::Vector2d> rk(n);  // the residuals in pair order
  for (size_t k = 0; k < n; ++k) rk[k] = r[s.position[k]];
  // Four passes from no translation over a flat scene: the inliers are the residuals within 4
  // robust scales of the current fit (one scale for the whole set: the noise does not depend on
  // the pair, and a pair with a handful of observations is judged as well as one with
  // hundreds). From the second on, the scene's slope too (scene_slope): one plane's inverse
  // depth is affine in the normalised image coordinates, and a ground ahead of a forward-flying
  // drone or a car leaves, at one depth, pixels of parallax growing towards the image's bottom.
  //
  // With the pairs' time shifts (pair_shift_sd), their prior is the noise's variance (the
  // pass's robust scale) over the shift's: a pair's shift follows its matches as far as they
  // hold it above the gyro's stamps' own error. The slope is fitted to what the shifts leave.
  Eigen::MatrixXd V = Eigen::MatrixXd::Zero(kW * static_cast<Eigen::Index>(pairs.size()), 1), B, Bs, shift;  // camera axes
  std::vector<double> len(n);
  fit.in.assign(n, false);
  const double shift_sd = s.shifts ? pair_shift_sd(m) : 0.0;
  auto depth_factor = [&](size_t k) { return plane.factor(k, fit.slope); };
  const std::vector<Eigen::Vector2d> flows = shift_flows(m, s, pairs);
  auto unshifted = [&](size_t k) { return Eigen::Vector2d(rk[k] - shift_flow(s, flows, shift, k)); };
  auto flow = [&](size_t k) { return Eigen::Vector2d(depth_factor(k) * unit_depth_flow(s, delta, V, k)); };
  auto plane_left = [&](size_t k) { return Eigen::Vector2d(unshifted(k) - flow(k)); };
  auto left = [&](size_t k) { return own_metric(fit.own_depth, k, plane_left(k)); };
  auto residual = [&](size_t k) { return rk[k]; };
  for (int pass = 0; pass < 4; ++pass) {
    for (size_t k = 0; k < n; ++k) len[k] = left(k).norm();
    const double scale = std::max(median(len) / std::sqrt(2 * std::log(2.0)), 1e-6), limit = 4 * scale;
    for (size_t k = 0; k < n; ++k) fit.in[k] = len[k] <= limit;
    if (pass >= 1) fit.slope = scene_slope(s, plane, delta, V, fit.in, unshifted);
    // Each match's own depth about the plane (own_depth.hpp), from the second pass on (the first
    // has no flow).
    if (pass >= 1 && depth_px > 0) fit.own_depth = own_depths(over(n, flow), over(n, plane_left), depth_px);
    fit.scale = scale;
    if (shift_sd > 0) fit.shift_rho = scale * scale / (shift_sd * shift_sd);
    pair_sums<1>(pairs, B, Bs, 1, s, delta, fit.in, depth_factor, residual, flows, fit.shift_rho, fit.own_depth);
    const Eigen::MatrixXd U = pair_velocities(sp, pairs, B);
    shift = pair_shifts(pairs, Bs, U);
    V = in_camera_axes(pairs, U);
    if (pass == 3) fit.world_velocities = U;  // the last pass's (translation_travel)
  }
  for (size_t k = 0; k < n; ++k) r[s.position[k]] = left(k);
  fit.velocities = std::move(V), fit.delta = std::move(delta);
  fit.pair_t.resize(pairs.size());
  for (size_t q = 0; q < pairs.size(); ++q) fit.pair_t[q] = pairs[q].t;
  fit.middle = pairs[pairs.size() / 2].orientation;
  if (keep) keep->state = st;
}

namespace {

// remove_fitted_translation's linear part, on `columns` columns of residuals: rows(k) is
// observation k's 2 x Cols block (in pair order), written in place. An observation `fit` had
// whose block holds a NaN here is left out of the velocity fit (and stays NaN).
template <int Cols, class Rows>
void subtract_fitted(const DiagnosisModel& m, const std::vector<int>& idx, Eigen::Index columns, const Rows& rows,
                     const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t, double knot_s,
                     const TranslationFit::State& fit) {
  const PairGroups& s = *fit.groups;
  std::vector<PairSums> pairs = pairs_at(m, idx, s, track, tm, mount_t);
  VelocitySpline sp = spline_over(pairs, knot_s);
  const std::vector<double> delta = row_delays(m, s, tm);
  auto depth_factor = [&](size_t k) { return fit.plane->factor(k, fit.slope); };
  std::vector<bool> taken(fit.in.size());
  for (size_t k = 0; k < taken.size(); ++k) taken[k] = fit.in[k] && rows(k).allFinite();
  Eigen::MatrixXd B, Bs;
  const std::vector<Eigen::Vector2d> flows = shift_flows(m, s, pairs);
  pair_sums<Cols>(pairs, B, Bs, columns, s, delta, taken, depth_factor, rows, flows, fit.shift_rho, fit.own_depth);
  const Eigen::MatrixXd U = pair_velocities(sp, pairs, B), shift = pair_shifts(pairs, Bs, U);
  const Eigen::MatrixXd V = in_camera_axes(pairs, U);
  for (size_t k = 0; k < s.position.size(); ++k)
    for (Eigen::Index c = 0; c < columns; ++c)
      rows(k).col(c) = own_metric(fit.own_depth, k,
                                  rows(k).col(c) - depth_factor(k) * unit_depth_flow(s, delta, V, k, c) -
                                      shift_flow(s, flows, shift, k, c));
}

}  // namespace

void remove_fitted_translation(const DiagnosisModel& m, const std::vector<int>& idx, std::vector<Eigen::Vector2d>& r,
                               const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t, double knot_s,
                               const TranslationFit& fit) {
  if (!fit.state) return remove_translation(m, idx, r, track, tm, mount_t, knot_s);
  const PairGroups& s = *fit.state->groups;
  if (r.size() != s.idx.size() || idx.size() != s.idx.size())
    throw std::invalid_argument("remove_fitted_translation: residuals of other observations than the fit's");
  auto rows = [&](size_t k) -> Eigen::Vector2d& { return r[s.position[k]]; };
  subtract_fitted<1>(m, idx, 1, rows, track, tm, mount_t, knot_s, *fit.state);
}

void remove_fitted_translation_from_columns(const DiagnosisModel& m, const std::vector<int>& idx, Eigen::MatrixXd& cols,
                                            const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t,
                                            double knot_s, const TranslationFit& fit) {
  if (!fit.state || cols.cols() == 0) return;
  const PairGroups& s = *fit.state->groups;
  if (static_cast<size_t>(cols.rows()) != 2 * s.idx.size() || idx.size() != s.idx.size())
    throw std::invalid_argument("remove_fitted_translation_from_columns: columns of other observations than the fit's");
  auto rows = [&](size_t k) { return cols.middleRows<2>(2 * static_cast<Eigen::Index>(s.position[k])); };
  subtract_fitted<Eigen::Dynamic>(m, idx, cols.cols(), rows, track, tm, mount_t, knot_s, *fit.state);
}

double translation_knot_spacing(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p) {
  std::vector<std::pair<int, double>> pair_times;  // each observation's pair (frame_a's rank) and its time
  double t_lo = std::numeric_limits<double>::infinity();
  for (int i : idx) pair_times.emplace_back(m.frame_rank(i), m.frame_time(i)), t_lo = std::min(t_lo, m.frame_time(i));
  std::sort(pair_times.begin(), pair_times.end());
  pair_times.erase(std::unique(pair_times.begin(), pair_times.end(),
                               [](const auto& a, const auto& b) { return a.first == b.first; }),
                   pair_times.end());
  const double pairs = static_cast<double>(pair_times.size());
  // The knot intervals that hold a pair: frames chosen in runs leave the spline's intervals
  // between runs empty, where the penalty alone decides and no pair is fitted.
  auto occupied = [&](double knot_s) {
    std::vector<long> at;
    for (const auto& pt : pair_times) at.push_back(static_cast<long>(std::floor((pt.second - t_lo) / knot_s)));
    std::sort(at.begin(), at.end());
    return static_cast<double>(std::unique(at.begin(), at.end()) - at.begin());
  };
  ModelParams q = p;
  q.translation_nuisance = true;
  q.translation_knot_s = kTranslationKnotsS[0];
  double scale = robust_stats(m.residuals(q, idx)).scale_px;
  for (size_t k = 1; k < kTranslationKnotsS.size(); ++k) {
    if (pairs < 2 * occupied(kTranslationKnotsS[k])) break;
    ModelParams finer = q;
    finer.translation_knot_s = kTranslationKnotsS[k];
    const double s = robust_stats(m.residuals(finer, idx)).scale_px;
    if (!(s < (1 - kFinerKnotsGain) * scale)) break;
    q = finer, scale = s;
  }
  return q.translation_knot_s;
}

double translation_depth_spread(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, bool ask_flow) {
  ModelParams q = p;
  q.translation_nuisance = true;
  q.translation_depth_px = 0;
  DiagnosisModel::Settled settled;
  const std::vector<Eigen::Vector2d> r = m.residuals(q, idx, settled);  // what the plane leaves
  if (!settled.translation.state) return 0.0;
  const TranslationFit::State& fit = *settled.translation.state;
  const PairGroups& s = *fit.groups;
  const size_t n = s.position.size();
  auto flow = [&](size_t k) {
    return Eigen::Vector2d(fit.plane->factor(k, fit.slope) * unit_depth_flow(s, fit.delta, fit.velocities, k));
  };
  auto left = [&](size_t k) { return r[s.position[k]]; };
  const DepthSpread spread = measured_spread(over(n, flow), over(n, left), fit.in, fit.scale);
  const bool measured = (spread.median_flow >= 1 || !ask_flow) && spread.z > kMinDepthSpreadZ && spread.spread >= kMinDepthSpread;
  return measured ? spread.spread : 0.0;
}

double translation_travel(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p) {
  ModelParams q = p;
  q.translation_nuisance = true;
  q.translation_depth_px = 0;
  q.translation_world_plane = false;
  DiagnosisModel::Settled settled;
  m.residuals(q, idx, settled);
  if (!settled.translation.state) return 0.0;
  const TranslationFit::State& fit = *settled.translation.state;
  // Along (g, 1) in the middle pair's camera, u . (g, 1) is the plane's distance's rate of change
  // over its distance (u is the velocity over the depth at the optical axis: 1 / depth =
  // (1 + g . xn) / depth at the axis, so the normal's distance is depth n_z, n = (g, 1) / |(g, 1)|).
  const Eigen::Vector3d normal = fit.middle * Eigen::Vector3d(fit.slope.x(), fit.slope.y(), 1.0);
  const size_t pairs = fit.pair_t.size(), middle = pairs / 2;
  std::vector<double> moved(pairs, 0.0);  // the distance's change from the first pair's
  for (size_t k = 1; k < pairs; ++k) {
    const double a = normal.dot(fit.world_velocities.block<3, 1>(kW * static_cast<Eigen::Index>(k - 1), 0)),
                 b = normal.dot(fit.world_velocities.block<3, 1>(kW * static_cast<Eigen::Index>(k), 0));
    moved[k] = moved[k - 1] + 0.5 * (a + b) * (fit.pair_t[k] - fit.pair_t[k - 1]);
  }
  double travel = 0;
  for (double x : moved) travel = std::max(travel, std::abs(x - moved[middle]));
  return travel;
}

double own_depth_px(double sigma_px, double spread) { return spread > 0 ? sigma_px / (kOwnDepthPriorWidth * spread) : 0.0; }

}  // namespace rsd::dsp
