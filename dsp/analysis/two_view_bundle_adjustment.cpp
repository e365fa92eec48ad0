#include "dsp/analysis/two_view_bundle_adjustment.hpp"

#include <ceres/ceres.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace rsd::dsp {

const char* to_string(ProjectionModel m) {
  return m == ProjectionModel::RollingShutter ? "rolling_shutter" : "perspective";
}

namespace {

// Ceres' parameter blocks: camera 1's pose (held constant: the gauge), camera 2's pose and
// the points, as flat arrays. Quaternions in Ceres' (w, x, y, z) order.
struct Blocks {
  std::array<std::array<double, 4>, 2> q{};
  std::array<std::array<double, 3>, 2> t{};
  std::vector<double> X;  // 3 per point
};

Blocks pack(const TwoViewEstimate& est) {
  Blocks b;
  b.q[0] = {1, 0, 0, 0};
  const Eigen::Quaterniond q = est.cam2.q.normalized();
  b.q[1] = {q.w(), q.x(), q.y(), q.z()};
  b.t[0] = {0, 0, 0};
  b.t[1] = {est.cam2.t.x(), est.cam2.t.y(), est.cam2.t.z()};
  for (const auto& X : est.points) b.X.insert(b.X.end(), {X.x(), X.y(), X.z()});
  return b;
}

TwoViewEstimate unpack(const Blocks& b) {
  TwoViewEstimate est;
  est.cam2.q = Eigen::Quaterniond(b.q[1][0], b.q[1][1], b.q[1][2], b.q[1][3]).normalized();
  est.cam2.t = Eigen::Vector3d(b.t[1][0], b.t[1][1], b.t[1][2]);
  for (size_t j = 0; j + 2 < b.X.size(); j += 3)
    est.points.emplace_back(b.X[j], b.X[j + 1], b.X[j + 2]);
  return est;
}

ceres::CostFunction* make_cost(const TwoViewData& data, ProjectionModel model, int cam,
                               const Eigen::Vector2d& observed) {
  if (model == ProjectionModel::Perspective)
    return new ceres::AutoDiffCostFunction<PerspectiveReprojection, 2, 4, 3, 3>(
        new PerspectiveReprojection{data.cam, observed});
  return new ceres::AutoDiffCostFunction<RollingShutterReprojection, 2, 4, 3, 3>(
      new RollingShutterReprojection{data.cam, normalised_readout(data.cam, data.timing),
                                     data.motion[cam], observed});
}

void add_residuals(ceres::Problem& problem, const TwoViewData& data, const TwoViewBaOptions& opt,
                   Blocks& b) {
  for (int i = 0; i < 2; ++i)
    for (size_t j = 0; j < data.pixels[i].size(); ++j) {
      // Huber bounds the pull of a gross outlier; without outliers plain least squares is
      // the maximum-likelihood estimate, hence the default.
      ceres::LossFunction* loss = opt.huber_px > 0 ? new ceres::HuberLoss(opt.huber_px) : nullptr;
      problem.AddResidualBlock(make_cost(data, opt.model, i, data.pixels[i][j]), loss,
                               b.q[i].data(), b.t[i].data(), &b.X[3 * j]);
    }
}

// The gauge: camera 1 fixed; camera 2's rotation a unit quaternion and its translation on
// the sphere of the initial radius (fixed scale, free direction).
void set_gauge(ceres::Problem& problem, Blocks& b) {
  problem.SetParameterBlockConstant(b.q[0].data());
  problem.SetParameterBlockConstant(b.t[0].data());
  problem.SetManifold(b.q[1].data(), new ceres::QuaternionManifold);
  problem.SetManifold(b.t[1].data(), new ceres::SphereManifold<3>);
}

ceres::Solver::Options solver_options(const TwoViewBaOptions& opt) {
  ceres::Solver::Options o;
  // One camera and many points: the Schur complement is a 5x5 dense system.
  o.linear_solver_type = ceres::DENSE_SCHUR;
  o.num_threads = 1;  // callers parallelise over problems
  o.max_num_iterations = opt.max_iterations;
  // Tight tolerances: noise-free data must be fitted to the last digits (the tests ask
  // for 1e-6 degrees), and the extra iterations cost little on problems this small.
  o.function_tolerance = 1e-14;
  o.gradient_tolerance = 1e-14;
  o.parameter_tolerance = 1e-12;
  o.logging_type = ceres::SILENT;
  return o;
}

void check(const TwoViewData& data, const TwoViewEstimate& initial) {
  const size_t n = initial.points.size();
  if (data.pixels[0].size() != n || data.pixels[1].size() != n)
    throw std::invalid_argument("two_view_bundle_adjust: one observation per point and camera");
  if (!(initial.cam2.t.norm() > 0))
    throw std::invalid_argument("two_view_bundle_adjust: the initial translation sets the scale");
  if (!data.cam.dist.is_identity())
    throw std::invalid_argument("two_view_bundle_adjust: lens distortion is not modelled");
}

}  // namespace

TwoViewBaResult two_view_bundle_adjust(const TwoViewData& data, const TwoViewEstimate& initial,
                                       const TwoViewBaOptions& options) {
  check(data, initial);
  Blocks b = pack(initial);
  ceres::Problem problem;
  add_residuals(problem, data, options, b);
  set_gauge(problem, b);
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options(options), &problem, &summary);
  TwoViewBaResult r;
  r.estimate = unpack(b);
  r.converged = summary.termination_type == ceres::CONVERGENCE;
  r.iterations = static_cast<int>(summary.iterations.size());
  r.rms_px = two_view_rms(data, options.model, r.estimate);
  return r;
}

std::optional<Eigen::Vector2d> two_view_predict(const TwoViewData& data, ProjectionModel model,
                                                int cam_index, const RigidPose& pose,
                                                const Eigen::Vector3d& X) {
  const Eigen::Quaterniond qn = pose.q.normalized();
  const double q[4] = {qn.w(), qn.x(), qn.y(), qn.z()};
  const Eigen::Vector2d zero = Eigen::Vector2d::Zero();
  Eigen::Vector2d px;
  // The functors with a zero observation return the prediction itself.
  const bool ok =
      model == ProjectionModel::Perspective
          ? PerspectiveReprojection{data.cam, zero}(q, pose.t.data(), X.data(), px.data())
          : RollingShutterReprojection{data.cam, normalised_readout(data.cam, data.timing),
                                       data.motion[cam_index],
                                       zero}(q, pose.t.data(), X.data(), px.data());
  if (!ok) return std::nullopt;
  return px;
}

double two_view_rms(const TwoViewData& data, ProjectionModel model, const TwoViewEstimate& est) {
  const RigidPose poses[2] = {RigidPose{}, est.cam2};
  double sum = 0;
  size_t n = 0;
  for (int i = 0; i < 2; ++i)
    for (size_t j = 0; j < est.points.size(); ++j) {
      const auto px = two_view_predict(data, model, i, poses[i], est.points[j]);
      if (!px) return std::numeric_limits<double>::infinity();
      sum += (*px - data.pixels[i][j]).squaredNorm();
      ++n;
    }
  return n ? std::sqrt(sum / n) : 0.0;
}

}  // namespace rsd::dsp
