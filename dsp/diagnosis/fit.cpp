#include "dsp/diagnosis/fit.hpp"

#include "dsp/diagnosis/match_jacobian.hpp"
#include "dsp/diagnosis/robust_stats.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <utility>
#include <vector>

namespace rsd::dsp {

namespace {

// The loss of a residual of squared length s2 (sigma units): Huber (quadratic to kHuberSigmas,
// then linear), and beyond kTailSigmas logarithmic, so that the influence of a residual falls
// as 1/length there. Gross outliers (a match to a random point lies hundreds of sigmas away)
// then barely pull: with Huber's constant pull, 10% random matches, whose residuals point
// on average against the image motion, biased the line delay by 4%. C1 at both joints.
double huber(double s2) {
  const double d = kHuberSigmas, R = kTailSigmas;
  if (s2 <= d * d) return s2;
  const double l = std::sqrt(s2);
  return l <= R ? 2 * d * l - d * d : 2 * d * R * (1 + std::log(l / R)) - d * d;
}

}  // namespace

double robust_loss(const Eigen::Vector2d& e, double sigma) {
  return huber(e.allFinite() ? e.squaredNorm() / (sigma * sigma) : 2 * kFailSigmas * kFailSigmas);
}

double robust_chi2(const std::vector<Eigen::Vector2d>& r, double sigma) {
  double c = 0;
  for (const auto& e : r) c += robust_loss(e, sigma);
  return c;
}

std::vector<int> subsample(const std::vector<int>& idx, size_t count) {
  if (idx.size() <= count || count == 0) return idx;
  std::vector<int> out;
  out.reserve(count);
  for (size_t k = 0; k < count; ++k) out.push_back(idx[k * idx.size() / count]);
  return out;
}

namespace {

// One frame's inlier residuals, where they were observed, and how many pairs of them are
// closer than kSharedWindowPx.
struct Group {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> at;  // (pixel, residual)
  double near_pairs = 0;
};

// Per coordinate, the summed products of the residuals of each frame's observations closer than
// kSharedWindowPx to each other (their pairs counted into each group), and how many pairs.
std::pair<double, double> shared_window_products(std::vector<Group>& groups) {
  double products = 0, pairs = 0;
  for (Group& g : groups) {
    std::sort(g.at.begin(), g.at.end(), [](const auto& a, const auto& b) { return a.first.x() < b.first.x(); });
    for (size_t i = 0; i < g.at.size(); ++i)
      for (size_t j = i + 1; j < g.at.size() && g.at[j].first.x() - g.at[i].first.x() < kSharedWindowPx; ++j)
        if ((g.at[j].first - g.at[i].first).squaredNorm() < kSharedWindowPx * kSharedWindowPx)
          products += 0.5 * g.at[i].second.dot(g.at[j].second), g.near_pairs += 1;
    pairs += g.near_pairs;
  }
  return {products, pairs};
}

}  // namespace

double design_effect(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx, double sigma) {
  const auto r = m.residuals(p, idx);
  std::vector<Group> g;
  double var = 0;
  int n = 0;
  for (size_t k = 0; k < idx.size(); ++k) {
    if (!r[k].allFinite() || r[k].norm() > 3 * sigma) continue;  // the Gaussian core
    const int f = m.frame_rank(idx[k]);
    if (f >= static_cast<int>(g.size())) g.resize(f + 1);
    g[f].sum += r[k], g[f].at.push_back({m.observed(idx[k]), r[k]});
    var += 0.5 * r[k].squaredNorm(), ++n;
  }
  if (n < 10) return 1.0;
  var /= n;
  // Twin features (closer than a tracker's window) covary by c_near, measured on their pairs.
  const auto [products, pairs] = shared_window_products(g);
  const double c_near = pairs > 0 ? products / pairs : 0.0;
  // Per coordinate: E[mean^2] = tau^2 + var / n_g + 2 P_g c_near / n_g^2 for a common part of
  // variance tau^2 and P_g twin pairs. The frame means alone would count the twins too, as a
  // common part, but from one number a frame: on 6 s of matches with a correlated twin each,
  // 1.33 where the twins' own pairs say 1.46 of the true 1.5 (DesignEffect.CountsWhatTwinFeaturesShare).
  double tau2 = 0, groups = 0;
  for (const Group& x : g) {
    const double size = static_cast<double>(x.at.size());
    if (size >= 2)
      tau2 += 0.5 * (x.sum / size).squaredNorm() - var / size - 2 * x.near_pairs * c_near / (size * size), groups += 1;
  }
  if (groups < 2) return 1.0;
  tau2 /= groups;
  const double rho = std::max(0.0, tau2 / var);
  // The twins' covariance beyond the common part, once for each such neighbour an observation
  // has (k, the mean over the observations): Var(sum) = n var (1 + (n_g - 1) rho + k rho_near).
  const double rho_near = pairs > 0 ? std::max(0.0, (c_near - rho * var) / var) : 0.0;
  const double k = 2 * pairs / n;
  return 1.0 + (static_cast<double>(n) / groups - 1.0) * rho + k * rho_near;
}

// ---------------------------------------------------------------- the fit, by Ceres

// Physical limits of a parameter: a line delay between zero and a readout filling the frame
// period; an offset inside the motion data; focal lengths within a factor two; generous
// ranges elsewhere (they only keep a wild step from leaving the model's domain).
std::pair<double, double> param_bounds(Param p, const DiagnosisModel& m) {
  const NominalModel& n = m.recording().nominal;
  switch (p) {
    case Param::LineDelay: return {0.0, 1.0 / (n.frame_rate_hz * n.cam.height)};
    case Param::TimeOffset: {
      // Motion data shorter than the frames: no offset keeps them all inside; allow +-1 s.
      const auto [lo, hi] = m.offset_range();
      const double t = n.time.time_offset_s;
      return lo < hi ? std::pair(lo, hi) : std::pair(t - 1.0, t + 1.0);
    }
    case Param::Fx: return {0.5 * n.cam.fx, 2.0 * n.cam.fx};
    case Param::Fy: return {0.5 * n.cam.fy, 2.0 * n.cam.fy};
    case Param::K1:
    case Param::K2:
    case Param::K3:
    case Param::K4: return {-1.0, 1.0};
    case Param::Drift: return {-1e4, 1e4};
    case Param::BiasX:
    case Param::BiasY:
    case Param::BiasZ: return {-1.0, 1.0};
    case Param::MountX:
    case Param::MountY:
    case Param::MountZ: return {-0.5, 0.5};  // rad: a mount is not turned by more than ~30 degrees unknowingly
    case Param::ScaleX:
    case Param::ScaleY:
    case Param::ScaleZ: return {0.5, 2.0};
    case Param::Cx: return {0.0, n.cam.width - 1.0};
    case Param::Cy: return {0.0, n.cam.height - 1.0};
    default: return {-2.0, 2.0};  // lever arm, metres
  }
}

namespace {

// The fit's coordinates: x_j = (p_j - start_j) / scale_j for the free parameters.
struct Coordinates {
  const NominalModel& nominal;
  ModelParams start;
  std::vector<Param> free;
  Eigen::VectorXd scale, lo, hi;

  Coordinates(const DiagnosisModel& m, ModelParams s, const ParamMask& mask)
      : nominal(m.recording().nominal), start(s), free(params_in(mask)) {
    const int n = static_cast<int>(free.size());
    scale.resize(n), lo.resize(n), hi.resize(n);
    for (int j = 0; j < n; ++j) {
      const auto [a, b] = param_bounds(free[j], m);
      set_param(start, free[j], std::clamp(start[free[j]], a, std::max(a, b)), nominal);
      scale[j] = param_scale(free[j], nominal);
      lo[j] = (a - start[free[j]]) / scale[j];
      hi[j] = (std::max(a, b) - start[free[j]]) / scale[j];
    }
  }
  ModelParams at(const double* x) const {
    ModelParams p = start;
    for (size_t j = 0; j < free.size(); ++j) set_param(p, free[j], start[free[j]] + x[j] * scale[j], nominal);
    return p;
  }
};

// The robust loss for Ceres: rho(s) = huber(s) on the squared residual length s in sigmas, with
// analytic derivatives (rho' is continuous at both joints). rho'' is negative beyond
// kHuberSigmas (the loss is concave in s there); Ceres's corrector then scales a block's
// residual and Jacobian by sqrt(rho'), i.e. iteratively reweighted least squares with weight
// rho', as the hand-written solver this replaces did.
class RobustLoss final : public ceres::LossFunction {
 public:
  void Evaluate(double s, double rho[3]) const override {
    const double d = kHuberSigmas, R = kTailSigmas;
    rho[0] = huber(s);
    if (s <= d * d) {
      rho[1] = 1.0, rho[2] = 0.0;
    } else if (s <= R * R) {
      const double l = std::sqrt(s);
      rho[1] = d / l, rho[2] = -0.5 * d / (s * l);
    } else {
      rho[1] = d * R / s, rho[2] = -d * R / (s * s);
    }
  }
};

// All residuals (sigma units) and, on demand, their forward-difference Jacobian (param_scale
// units) at one point x, computed in bulk. DiagnosisModel::residuals is far cheaper for all
// observations at once (it caches the motion track per parameter value) than per observation,
// while Ceres wants one residual block per observation (so that the loss applies to each
// observation's residual length): every block's cost function is a view onto this evaluator,
// which recomputes only when x changes. Ceres asks for residuals alone when it tries a step
// and for Jacobians at accepted points, so the two are cached separately. Not thread safe:
// the solver runs single-threaded.
class BulkEvaluator {
 public:
  BulkEvaluator(const DiagnosisModel& m, const std::vector<int>& idx, const Coordinates& c, double sigma)
      : m_(m), idx_(idx), c_(c), sigma_(sigma), k_(static_cast<int>(c.free.size())) {}

  int size() const { return k_; }

  // Residual of observation i at x, and its 2 x k row-major Jacobian when `jac` is non-null.
  void get(const double* x, size_t i, double* r, double* jac) {
    const Values& v = jac ? with_jacobian(x) : residuals_at(x);
    r[0] = v.r[i].x(), r[1] = v.r[i].y();
    if (jac) std::copy_n(v.J.data() + 2 * i * k_, 2 * k_, jac);  // rows 2i, 2i + 1 (row-major)
  }

 private:
  struct Values {
    Eigen::VectorXd x;  // the point these values are at (empty: none yet)
    std::vector<Eigen::Vector2d> r;
    std::vector<bool> ok;
    DiagnosisModel::Settled settled;  // the fixed points and the translation as they settled at x
    // with_jacobian only: rows 2i, 2i + 1 are observation i's, laid out as Ceres wants them
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J;
  };

  bool same(const Values& v, const double* x) const {
    return v.x.size() == k_ && std::equal(x, x + k_, v.x.data());
  }

  // Residuals in sigma units; a failed prediction becomes a constant kFailSigmas residual. With
  // `near`, from what settled there: its fixed points as starts and, under the translation
  // nuisance, its translation held (DiagnosisModel::residuals_near: a Jacobian column's step).
  // Without, the fixed points start from the solver's current point when it has one (a trial
  // step's: two projections a match, not three) and the translation is fitted afresh.
  void evaluate(const double* x, Values& v, const Values* near = nullptr) const {
    v.x = Eigen::Map<const Eigen::VectorXd>(x, k_);
    const DiagnosisModel::Settled* current = jac_.x.size() == k_ && &v != &jac_ ? &jac_.settled : nullptr;
    v.r = near ? m_.residuals_near(c_.at(x), idx_, near->settled) : m_.residuals(c_.at(x), idx_, v.settled, current);
    v.ok.assign(v.r.size(), false);
    for (size_t i = 0; i < v.r.size(); ++i) {
      v.ok[i] = v.r[i].allFinite();
      v.r[i] = v.ok[i] ? Eigen::Vector2d(v.r[i] / sigma_) : Eigen::Vector2d::Constant(kFailSigmas);
    }
  }

  const Values& residuals_at(const double* x) {
    if (!same(res_, x)) evaluate(x, res_);
    return res_;
  }

  // A matches recording's columns come from the rotation model's analytic derivatives
  // (analytic_columns); the rest (landmarks, the lever arm) by forward differences, stepping away
  // from the nearer bound. A failed prediction (at x or at the step) gets a zero Jacobian row,
  // so its constant residual pulls nowhere. Each step starts every match's rolling-shutter fixed
  // point from its solution at x (two projections instead of three), and under the translation
  // nuisance keeps the inliers and the scene's slope the translation settled on at x
  // (translation.hpp, TranslationFit): a column costs the rotation model's residuals and one
  // pass of the velocity fit, not four passes (a diagnosis under parallax took a third less time).
  const Values& with_jacobian(const double* x) {
    if (same(jac_, x)) return jac_;
    if (same(res_, x)) jac_.x = res_.x, jac_.r = res_.r, jac_.ok = res_.ok, jac_.settled = res_.settled;
    else evaluate(x, jac_);
    const size_t n = idx_.size();
    jac_.J.setZero(2 * n, k_);
    std::vector<bool> done(k_, false);
    analytic_columns(done);
    Values step;
    for (int j = 0; j < k_; ++j) {
      if (done[j]) continue;
      Eigen::VectorXd xh = jac_.x;
      xh[j] += step_of(j);
      evaluate(xh.data(), step, &jac_);
      for (size_t i = 0; i < n; ++i)
        if (jac_.ok[i] && step.ok[i]) jac_.J.block<2, 1>(2 * i, j) = (step.r[i] - jac_.r[i]) / step_of(j);
    }
    return jac_;
  }

  // A difference's step: away from the nearer bound.
  double step_of(int j) const { return (jac_.x[j] + 1e-3 > c_.hi[j]) ? -1e-3 : 1e-3; }

  // The columns of a matches recording's parameters (all but the lever arm, which matches do not
  // see) from the rotation model's analytic derivatives (DiagnosisModel::rotation_jacobian,
  // match_jacobian.hpp), through the chain x_j -> p (param_scale, and a parameter that follows
  // another, fy after fx): one pass over the matches for every column, where differences cost a
  // pass per column (the walking phone under parallax: 30 -> 23 s; the benchmark's minute 7.4 ->
  // 5.8 s). Under the translation nuisance the column is the difference the translation pass
  // makes of the linearised rotation residuals, r + h dr/dx_j, at x + h e_j (the pass moves with
  // the clock, the mount and the gyro), as a column by differences takes it of the residuals;
  // where the pass does not move (the line delay, the intrinsics, the lens) it is linear, and
  // takes those columns with one factorisation (held_columns).
  void analytic_columns(std::vector<bool>& done) {
    if (m_.kind() != ObservationKind::Matches) return;
    bool any = false, gyro = false;  // gyro: a bias or scale column asked for (they come last)
    for (int j = 0; j < k_; ++j) {
      any = any || analytic_column(c_.free[j]) >= 0;
      gyro = gyro || analytic_column(c_.free[j]) >= analytic_column(Param::BiasX);
    }
    if (!any) return;
    const ModelParams p = c_.at(jac_.x.data());
    const std::vector<MatchJacobian> D = m_.rotation_jacobian(p, idx_, jac_.settled, gyro);
    const size_t n = idx_.size();
    std::vector<int> held;  // under the nuisance: columns whose translation pass holds
    for (int j = 0; j < k_; ++j) {
      if (analytic_column(c_.free[j]) < 0) continue;
      Eigen::Matrix<double, MatchJacobian::ColsAtCompileTime, 1> chain;
      chain.setZero();
      chain[analytic_column(c_.free[j])] = c_.scale[j];
      bool all = true;
      for (int q = 0; q < kParamCount; ++q)
        if (const auto f = follows(Param(q), c_.nominal); f && f->leader == c_.free[j]) {
          const int a = analytic_column(Param(q));
          all = all && a >= 0;
          if (a >= 0) chain[a] = c_.scale[j] * f->factor;
        }
      if (!all) continue;
      done[j] = true;
      bool moves = false;  // whether the column moves the translation pass (the pairs' turns)
      for (int a = 0; a < chain.size(); ++a)
        moves = moves || (chain[a] != 0 && DiagnosisModel::moves_translation_pass(kAnalyticParams[a]));
      if (!p.translation_nuisance || !moves) {
        for (size_t i = 0; i < n; ++i)
          if (jac_.ok[i]) jac_.J.block<2, 1>(2 * i, j) = D[i] * chain / sigma_;
        if (p.translation_nuisance) held.push_back(j);
        continue;
      }
      const double h = step_of(j);
      std::vector<Eigen::Vector2d> r = jac_.settled.rotation;
      for (size_t i = 0; i < n; ++i) r[i] += h * (D[i] * chain);
      Eigen::VectorXd xh = jac_.x;
      xh[j] += h;
      r = m_.translation_out_near(c_.at(xh.data()), idx_, std::move(r), jac_.settled);
      for (size_t i = 0; i < n; ++i)
        if (jac_.ok[i] && r[i].allFinite()) jac_.J.block<2, 1>(2 * i, j) = (r[i] / sigma_ - jac_.r[i]) / h;
    }
    held_columns(p, held);
  }

  // The columns `held` (the rotation model's, scaled) with the translation taken out: the pass is
  // linear in the residuals where the pairs' turns hold, one factorisation for all of them.
  void held_columns(const ModelParams& p, const std::vector<int>& held) {
    if (held.empty()) return;
    Eigen::MatrixXd cols(jac_.J.rows(), static_cast<Eigen::Index>(held.size()));
    for (size_t c = 0; c < held.size(); ++c) cols.col(c) = jac_.J.col(held[c]);
    m_.translation_out_of_columns(p, idx_, cols, jac_.settled);
    for (size_t i = 0; i < idx_.size(); ++i)
      if (jac_.ok[i])
        for (size_t c = 0; c < held.size(); ++c) jac_.J.block<2, 1>(2 * i, held[c]) = cols.block<2, 1>(2 * i, c);
  }

  const DiagnosisModel& m_;
  const std::vector<int>& idx_;
  const Coordinates& c_;
  const double sigma_;
  const int k_;
  Values res_, jac_;
};

// One observation's residual block: two residuals, the k free parameters.
class ObservationCost final : public ceres::CostFunction {
 public:
  ObservationCost(BulkEvaluator& e, size_t i) : e_(e), i_(i) {
    set_num_residuals(2);
    mutable_parameter_block_sizes()->push_back(e.size());
  }
  bool Evaluate(double const* const* x, double* r, double** jac) const override {
    e_.get(x[0], i_, r, jac ? jac[0] : nullptr);
    return true;
  }

 private:
  BulkEvaluator& e_;
  size_t i_;
};

}  // namespace

ModelParams fit_params(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& start,
                       const ParamMask& mask, double sigma, int max_iterations, FitEnd* end) {
  const Coordinates c(m, start, mask);
  if (end) *end = {true, 0};  // nothing to iterate: any cap gives the same
  if (c.free.empty() || idx.empty()) return c.start;
  if (max_iterations <= 0) {
    if (end) end->converged = false;
    return c.start;
  }
  const int k = static_cast<int>(c.free.size());
  std::vector<double> x(k, 0.0);
  BulkEvaluator bulk(m, idx, c, sigma);
  RobustLoss loss;
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.disable_all_safety_checks = true;  // thousands of identical blocks, built right here
  ceres::Problem pb(po);
  for (size_t i = 0; i < idx.size(); ++i) pb.AddResidualBlock(new ObservationCost(bulk, i), &loss, x.data());
  std::vector<int> fixed;  // a degenerate range (Ceres rejects lower == upper): held at start
  for (int j = 0; j < k; ++j) {
    if (!(c.lo[j] < c.hi[j])) {
      fixed.push_back(j);
      continue;
    }
    pb.SetParameterLowerBound(x.data(), j, c.lo[j]);
    pb.SetParameterUpperBound(x.data(), j, c.hi[j]);
  }
  if (static_cast<int>(fixed.size()) == k) return c.start;
  if (!fixed.empty()) pb.SetManifold(x.data(), new ceres::SubsetManifold(k, fixed));
  ceres::Solver::Options so;
  so.minimizer_type = ceres::TRUST_REGION;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  // k is small (at most kParamCount) and the blocks share the one parameter block: the dense
  // normal equations are k x k.
  so.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  so.max_num_iterations = max_iterations;
  // Comparable to the hand-written solver's test: a relative cost decrease or a step (in
  // param_scale units, which are each parameter's natural resolution) below 1e-7.
  so.function_tolerance = 1e-7;
  so.parameter_tolerance = 1e-7;
  so.gradient_tolerance = 1e-12;
  // With bounds, Ceres follows every trust-region step by a projected Armijo line search. Its
  // default cubic interpolation asks for the gradient, i.e. the whole Jacobian (a pass over the
  // observations and a translation pass per column), at each trial point, and backtracking
  // costs more bulk evaluations per rejected step. One trial of the full step, by bisection (costs alone), is
  // plain Levenberg-Marquardt: the trial is the candidate Ceres then evaluates (cached), and a
  // rejected step shrinks the trust region instead.
  so.line_search_interpolation_type = ceres::BISECTION;
  so.max_num_line_search_step_size_iterations = 1;
  so.num_threads = 1;  // dsp runs on its caller's thread; the bulk evaluator's cache needs it
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &pb, &summary);
  if (end) *end = {summary.termination_type == ceres::CONVERGENCE, static_cast<int>(summary.iterations.size()) - 1};
  return c.at(x.data());
}

}  // namespace rsd::dsp
