#include "dsp/diagnosis/translation.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>

#include "dsp/core/statistics.hpp"
#include "dsp/diagnosis/model.hpp"
#include "dsp/diagnosis/parallax.hpp"
#include "dsp/diagnosis/robust_stats.hpp"

namespace rsd::dsp {

namespace {

// One frame pair's share of the velocity fit: its time and the normal equations of its inliers
// in the velocity over depth (world axes), and how a velocity turns into its translation over
// depth (camera axes): beta = dt R^T u.
struct PairSums {
  double t = 0;
  Eigen::Matrix3d turn = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
};

// Uniform cubic B-spline: the weights of the four control points at fraction u of an interval.
std::array<double, 4> cubic_weights(double u) {
  const double u2 = u * u, u3 = u2 * u, v = 1 - u;
  return {v * v * v / 6, (3 * u3 - 6 * u2 + 4) / 6, (-3 * u3 + 3 * u2 + 3 * u + 1) / 6, u3 / 6};
}

// The velocity spline over [t0, t0 + intervals x knot_s]: a time's first control point and weights.
struct Spline {
  double t0, knot;
  int intervals;
  int controls() const { return intervals + 3; }
  int first(double t, std::array<double, 4>& w) const {
    const double s = (t - t0) / knot;
    const int j = std::clamp(static_cast<int>(std::floor(s)), 0, intervals - 1);
    w = cubic_weights(std::clamp(s - j, 0.0, 1.0));
    return j;
  }
};

// The control points (3 per knot, world axes) minimising the pairs' squared residuals, with a
// light penalty on the second difference of the control points (it decides only where the data
// leave a direction free: a stretch without pairs, a component no pair shows).
Eigen::VectorXd fit_velocity(const Spline& sp, const std::vector<PairSums>& pairs) {
  const int n = 3 * sp.controls();
  std::vector<Eigen::Triplet<double>> tr;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  double trace = 0;
  for (const PairSums& p : pairs) {
    std::array<double, 4> w;
    const int j = sp.first(p.t, w);
    for (int a = 0; a < 4; ++a) {
      rhs.segment<3>(3 * (j + a)) += w[a] * p.b;
      for (int c = 0; c < 4; ++c)
        for (int x = 0; x < 3; ++x)
          for (int y = 0; y < 3; ++y) tr.emplace_back(3 * (j + a) + x, 3 * (j + c) + y, w[a] * w[c] * p.N(x, y));
    }
    trace += p.N.trace();
  }
  const double lambda = 1e-4 * trace / n, ridge = 1e-9 * trace / n + 1e-12;
  for (int k = 0; k + 2 < sp.controls(); ++k) {
    const std::array<double, 3> d = {1, -2, 1};
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c)
        for (int x = 0; x < 3; ++x) tr.emplace_back(3 * (k + a) + x, 3 * (k + c) + x, lambda * d[a] * d[c]);
  }
  for (int i = 0; i < n; ++i) tr.emplace_back(i, i, ridge);
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(tr.begin(), tr.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
  if (ldlt.info() != Eigen::Success) return Eigen::VectorXd::Zero(n);
  return ldlt.solve(rhs);
}

// The scene's slope g (inverse depth 1 + g . xn over the depth at the optical axis) that best
// explains the inliers' residuals given the translations u: r - f = (g . xn) f, f = J u per
// observation, linear in g. A light ridge keeps g at zero where the translation shows none.
template <class Residual>
Eigen::Vector2d scene_slope(const std::vector<Eigen::Matrix<double, 2, 3>>& J, const std::vector<Eigen::Vector2d>& xn,
                            const std::vector<int>& pair_of, const std::vector<Eigen::Vector3d>& u, const std::vector<bool>& in,
                            const Residual& r) {
  Eigen::Matrix2d N = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (size_t k = 0; k < J.size(); ++k) {
    if (!in[k]) continue;
    const Eigen::Vector2d f = J[k] * u[pair_of[k]];
    const Eigen::Matrix2d A = f * xn[k].transpose();  // d(flow)/dg
    N += A.transpose() * A, b += A.transpose() * (r(k) - f);
  }
  N.diagonal().array() += 1e-3 * N.trace() + 1e-12;
  return N.ldlt().solve(b);
}

}  // namespace

void remove_translation(const DiagnosisModel& m, const std::vector<int>& idx, std::vector<Eigen::Vector2d>& r,
                        const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t, double knot_s) {
  const CameraModel& cam = m.recording().nominal.cam;
  // The pairs (frame_a's rank and frame_b's time: a frame may be matched to more than one other)
  // and each observation's pair and flow per unit translation.
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
  if (by_pair.empty()) return;
  std::sort(by_pair.begin(), by_pair.end());
  std::vector<PairSums> pairs;
  std::vector<int> pair_of(by_pair.size());
  std::vector<Eigen::Matrix<double, 2, 3>> J(by_pair.size());
  std::vector<Eigen::Vector2d> xn(by_pair.size());  // normalised image coordinates
  for (size_t k = 0; k < by_pair.size(); ++k) {
    const int i = idx[by_pair[k].second];
    if (k == 0 || !by_pair[k].same_pair(by_pair[k - 1])) {
      PairSums s;
      s.t = 0.5 * (m.frame_time(i) + m.frame_time_b(i));
      const Eigen::Matrix3d world_from_camera = track.camera_at(tm.motion_time(m.frame_time(i))) * mount_t;
      s.turn = (m.frame_time_b(i) - m.frame_time(i)) * world_from_camera.transpose();
      pairs.push_back(s);
    }
    pair_of[k] = static_cast<int>(pairs.size()) - 1;
    J[k] = translation_flow(cam, m.observed(i)) * pairs.back().turn;  // per unit u, world axes
    xn[k] = Eigen::Vector2d((m.observed(i).x() - cam.cx) / cam.fx, (m.observed(i).y() - cam.cy) / cam.fy);
  }
  double t_lo = pairs.front().t, t_hi = t_lo;
  for (const PairSums& p : pairs) t_lo = std::min(t_lo, p.t), t_hi = std::max(t_hi, p.t);
  const Spline sp{t_lo, knot_s, std::max(1, static_cast<int>(std::ceil((t_hi - t_lo) / knot_s)))};
  // Four passes from no translation over a flat scene: the inliers are the residuals within 4
  // robust scales of the current fit (one scale for the whole set: the noise does not depend on
  // the pair, and a pair with a handful of observations is judged as well as one with
  // hundreds). From the second on, the scene's slope too (scene_slope): one plane's inverse
  // depth is affine in the normalised image coordinates, and a ground ahead of a forward-flying
  // drone or a car leaves, at one depth, pixels of parallax growing towards the image's bottom.
  std::vector<Eigen::Vector3d> u(pairs.size(), Eigen::Vector3d::Zero());
  std::vector<double> len(by_pair.size());
  std::vector<bool> in(by_pair.size());
  Eigen::Vector2d slope = Eigen::Vector2d::Zero();
  auto depth_factor = [&](size_t k) { return 1.0 + slope.dot(xn[k]); };
  auto flow = [&](size_t k) { return Eigen::Vector2d(depth_factor(k) * (J[k] * u[pair_of[k]])); };
  auto left = [&](size_t k) { return Eigen::Vector2d(r[by_pair[k].second] - flow(k)); };
  for (int pass = 0; pass < 4; ++pass) {
    for (size_t k = 0; k < len.size(); ++k) len[k] = left(k).norm();
    const double limit = 4 * std::max(median(len) / std::sqrt(2 * std::log(2.0)), 1e-6);
    for (size_t k = 0; k < len.size(); ++k) in[k] = len[k] <= limit;
    if (pass >= 1) slope = scene_slope(J, xn, pair_of, u, in, [&](size_t k) { return r[by_pair[k].second]; });
    for (PairSums& p : pairs) p.N.setZero(), p.b.setZero();
    for (size_t k = 0; k < len.size(); ++k) {
      if (!in[k]) continue;
      PairSums& p = pairs[pair_of[k]];
      const Eigen::Matrix<double, 2, 3> Jk = depth_factor(k) * J[k];
      p.N += Jk.transpose() * Jk, p.b += Jk.transpose() * r[by_pair[k].second];
    }
    const Eigen::VectorXd c = fit_velocity(sp, pairs);
    for (size_t q = 0; q < pairs.size(); ++q) {
      std::array<double, 4> w;
      const int j = sp.first(pairs[q].t, w);
      u[q].setZero();
      for (int a = 0; a < 4; ++a) u[q] += w[a] * c.segment<3>(3 * (j + a));
    }
  }
  for (size_t k = 0; k < by_pair.size(); ++k) r[by_pair[k].second] = left(k);
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
