// The nonlinear fit of the sinusoid model and its uncertainty (robust, clustered by bands of rows).
#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

#include "dsp/calib/led_internal.hpp"

namespace rsd::dsp::led {

// Harmonics up to the highest one present at kMinHarmonicZ sigma: fitting absent ones
// only fits noise, and makes the fit less stable.
std::vector<int> significant_orders(const Fit& f) {
  int top = 0;
  for (size_t i = 0; i < f.orders.size() && i < f.harmonic_z.size(); ++i)
    if (f.harmonic_z[i] >= kMinHarmonicZ) top = f.orders[i];
  std::vector<int> out;
  for (int h : f.orders)
    if (h <= top) out.push_back(h);
  return out;
}

ceres::Solver::Options solver_options(const Model& m) {
  ceres::Solver::Options o;
  o.linear_solver_type = m.nuisance.size() > 1 ? ceres::DENSE_SCHUR : ceres::DENSE_QR;
  o.max_num_iterations = 100;
  // Near the optimum a relative cost change of 1e-11 is a nu step of ~1e-4 sigma.
  o.function_tolerance = 1e-11;
  o.gradient_tolerance = 1e-14;
  o.parameter_tolerance = 1e-14;  // relative to all parameters, offsets included: keep tiny
  o.logging_type = ceres::SILENT;
  o.num_threads = 1;  // dsp/ starts no threads
  return o;
}

constexpr int kBands = 32;  // bands of rows per frame: the clusters of the robust variance

// One group's residuals and Jacobian at the current parameters, split into the columns of
// its own parameters (to be eliminated) and of the shared ones (nu first).
struct GroupJacobian {
  Eigen::MatrixXd own, shared;
  Eigen::VectorXd r;
};

GroupJacobian group_jacobian(const Model& m, const Group& g, bool own_nuisance, bool own_phase) {
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const int n = static_cast<int>(g.samples.size()), nn = 2 * m.J, ns = static_cast<int>(m.shape.size());
  RowMajor jn(n, nn), js(n, std::max(ns, 1));
  Eigen::VectorXd jnu(n), jph(n), r(n);
  double* jac[4] = {jn.data(), jnu.data(), jph.data(), js.data()};
  const double* params[4] = {m.nuisance[g.nuisance].data(), &m.nu, &m.phase[g.phase], m.shape.data()};
  SinusoidCost(g.samples, m.J, m.orders).Evaluate(params, r.data(), jac);
  GroupJacobian out;
  out.r = r;
  out.own.resize(n, (own_nuisance ? nn : 0) + (own_phase ? 1 : 0));
  out.shared.resize(n, 1 + (own_phase ? 0 : 1) + (own_nuisance ? 0 : nn) + ns);
  int o = 0, c = 0;
  out.shared.col(c++) = jnu;
  if (own_nuisance) out.own.middleCols(o, nn) = jn, o += nn;
  else out.shared.middleCols(c, nn) = jn, c += nn;
  if (own_phase) out.own.col(o) = jph;
  else out.shared.col(c++) = jph;
  if (ns > 0) out.shared.rightCols(ns) = js;
  return out;
}

// The normal equations of the shared parameters (nu first, harmonics last) after
// eliminating each group's own parameters (Schur complement), at the model's current
// parameters: information J^T J, gradient J^T r, the same gradient per cluster of
// residuals (bands of rows, per frame for the smooth models), and the residual sum of squares.
struct Reduced {
  Eigen::MatrixXd info;
  Eigen::VectorXd grad;
  std::vector<Eigen::VectorXd> cluster_grad;
  double rss = 0;
};

Reduced reduce(const Model& m) {
  const bool own_nuisance = m.nuisance.size() == m.groups.size(), own_phase = m.phase.size() == m.groups.size();
  const int band = std::max(1, m.rows / kBands);
  Reduced red;
  for (size_t gi = 0; gi < m.groups.size(); ++gi) {
    GroupJacobian j = group_jacobian(m, m.groups[gi], own_nuisance, own_phase);
    if (j.own.cols() > 0) {
      Eigen::MatrixXd ata = j.own.transpose() * j.own;
      ata.diagonal().array() += 1e-12 * (ata.diagonal().maxCoeff() + 1e-300);
      j.shared -= j.own * ata.ldlt().solve(j.own.transpose() * j.shared);
    }
    if (red.info.size() == 0) {
      red.info = Eigen::MatrixXd::Zero(j.shared.cols(), j.shared.cols());
      red.grad = Eigen::VectorXd::Zero(j.shared.cols());
    }
    red.info.noalias() += j.shared.transpose() * j.shared;
    red.grad.noalias() += j.shared.transpose() * j.r;
    red.rss += j.r.squaredNorm();
    const size_t base = m.kind == LedModel::JointPerRow ? 0 : gi * (kBands + 1);
    for (int i = 0; i < j.shared.rows(); ++i) {
      const size_t c = base + m.groups[gi].samples[i].row / band;
      if (red.cluster_grad.size() <= c) red.cluster_grad.resize(c + 1, Eigen::VectorXd::Zero(red.info.cols()));
      red.cluster_grad[c] += j.shared.row(i).transpose() * j.r[i];
    }
  }
  return red;
}

// Inverse of an information matrix, or nothing when it is singular. Columns differ in
// scale by many orders (nu's grows with the row index): conditioning is judged on the
// correlation matrix.
std::optional<Eigen::MatrixXd> inverse(const Eigen::MatrixXd& info) {
  const Eigen::VectorXd d = info.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(d.asDiagonal() * info * d.asDiagonal());
  const Eigen::VectorXd ev = eig.eigenvalues();
  if (!(ev(0) > 1e-10 * ev(ev.size() - 1))) return std::nullopt;
  return d.asDiagonal() * eig.eigenvectors() * ev.cwiseInverse().asDiagonal() * eig.eigenvectors().transpose() *
         d.asDiagonal();
}

// Amplitude / standard error of each harmonic for coefficients `shape` (after `first`).
std::vector<double> harmonic_z(const Eigen::MatrixXd& inv, const Eigen::VectorXd& shape, double s2) {
  const int first = static_cast<int>(inv.rows() - shape.size());
  std::vector<double> z;
  for (int h = 0; h + 1 < shape.size(); h += 2)
    z.push_back(std::sqrt(shape[h] * shape[h] / (s2 * inv(first + h, first + h)) +
                          shape[h + 1] * shape[h + 1] / (s2 * inv(first + h + 1, first + h + 1))));
  return z;
}

struct Covariance {
  double nu_var = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> harmonic_z;  // per harmonic: fitted amplitude / its standard error
};

// Variance of nu two ways: the classical s^2 (J^T J)^-1, which assumes independent
// residuals of equal variance, and a cluster-robust (sandwich) one over bands of rows,
// which does not. The residuals of sharp bar edges are neither: they crowd where the
// Jacobian is largest and are shared by neighbouring rows. The larger counts.
Covariance nu_variance(const Model& m, double s2) {
  const Reduced red = reduce(m);
  const auto inv = inverse(red.info);
  if (!inv) return {};  // singular fit
  Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(red.info.rows(), red.info.cols());
  int clusters = 0;
  for (const Eigen::VectorXd& u : red.cluster_grad)
    if (u.squaredNorm() > 0) meat += u * u.transpose(), ++clusters;
  const double robust = clusters > 1 ? (*inv * meat * *inv)(0, 0) * clusters / (clusters - 1.0) : 0.0;
  Covariance c;
  c.nu_var = std::max(s2 * (*inv)(0, 0), robust);
  c.harmonic_z = harmonic_z(*inv, Eigen::Map<const Eigen::VectorXd>(m.shape.data(), m.shape.size()), s2);
  return c;
}

// The harmonics present in the data, judged before the nonlinear fit by one linearised
// (Gauss-Newton) step from shape = 0: fitting absent ones only fits noise (and costs time).
std::vector<int> present_orders(const Model& m) {
  if (m.orders.empty()) return {};
  const Reduced red = reduce(m);
  const auto inv = inverse(red.info);
  if (!inv) return m.orders;
  const Eigen::VectorXd step = -(*inv * red.grad);
  // Noise level after the step (the Gauss-Newton prediction): the residual before it still
  // holds every harmonic and would hide the weaker ones.
  const double rss = std::max(red.rss + red.grad.dot(step), 1e-12 * red.rss);
  const double s2 = rss / std::max(1, m.samples() - m.parameters());
  Fit probe;
  probe.orders = m.orders;
  probe.harmonic_z = harmonic_z(*inv, step.tail(m.shape.size()), s2);
  return significant_orders(probe);
}

// Modulation depth and rms amplitude of the fitted bars. The waveform's size is |b| times
// the rms of g times sqrt 2 (so a pure sinusoid's amplitude is |b|): with a short duty
// cycle most of it is in the harmonics. The depth is the bars' rms amplitude over the mean
// offset (short pulses seen at few phases leave many rows unlit: a median would be 0).
void describe(const Model& m, Fit& f) {
  double g2 = 1;
  for (double c : m.shape) g2 += c * c;
  double amp2 = 0, offset = 0;
  int n = 0;
  for (const Group& g : m.groups)
    for (const Sample& s : g.samples) {
      double a = 0, b = 0;
      for (int j = 0; j < s.nw; ++j) {
        a += s.w[j] * m.nuisance[g.nuisance][s.first + j];
        b += s.w[j] * m.nuisance[g.nuisance][m.J + s.first + j];
      }
      offset += a;
      amp2 += b * b * g2;
      ++n;
    }
  f.amplitude = std::sqrt(amp2 / std::max(1, n));
  f.depth = offset > 0 ? f.amplitude * n / offset : 0.0;
}

// Joint least-squares fit of all samples from the model's current parameters (Ceres,
// Levenberg-Marquardt); nu's uncertainty from the covariance scaled by the residual variance.
Fit fit_model(Model& m) {
  ceres::Problem problem;
  for (const Group& g : m.groups) {
    std::vector<double*> blocks{m.nuisance[g.nuisance].data(), &m.nu, &m.phase[g.phase]};
    if (!m.orders.empty()) blocks.push_back(m.shape.data());
    problem.AddResidualBlock(new SinusoidCost(g.samples, m.J, m.orders), nullptr, blocks);
  }
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options(m), &problem, &summary);
  Fit f;
  f.kind = m.kind;
  f.samples = m.samples();
  f.parameters = m.parameters();
  f.rss = 2 * summary.final_cost;
  f.nu = m.nu;
  const Covariance cov = nu_variance(m, f.s2());
  f.nu_stat = f.nu_sigma = std::sqrt(cov.nu_var);
  f.orders = m.orders;
  f.harmonic_z = cov.harmonic_z;
  describe(m, f);
  Model null = m;  // offsets only: what is left without the LED
  f.rss_null = solve_linear(null, Linear::OffsetOnly);
  f.null_parameters = static_cast<int>(m.nuisance.size()) * m.J;
  return f;
}

// Harmonics up to half the highest one of `orders`.
std::vector<int> lower_half(const std::vector<int>& orders) {
  std::vector<int> out;
  for (int h : orders)
    if (2 * h <= orders.back()) out.push_back(h);
  return out;
}

// `m` with only the harmonics in `orders` (a subset), keeping their current coefficients.
Model with_orders(const Model& m, const std::vector<int>& orders) {
  Model out = m;
  out.orders = orders;
  out.shape.clear();
  for (int h : orders) {
    const size_t i = std::find(m.orders.begin(), m.orders.end(), h) - m.orders.begin();
    out.shape.push_back(i < m.orders.size() ? m.shape[2 * i] : 0.0);
    out.shape.push_back(i < m.orders.size() ? m.shape[2 * i + 1] : 0.0);
  }
  return out;
}

// The fit, with the truncation of the waveform as a systematic uncertainty: the same fit
// with half the harmonics differs from it by about what the harmonics left out may still
// do (their effect shrinks with their order), so that difference is added to nu's
// statistical sigma. A fit its harmonics make singular is retried with half of them;
// refits start from the previous solution.
Fit fit_checked(const Model& start) {
  Model m = start;
  Fit f = fit_model(m);
  while (!std::isfinite(f.nu_sigma) && !m.orders.empty()) {
    m = with_orders(start, lower_half(m.orders));
    f = fit_model(m);
  }
  if (std::isfinite(f.nu_sigma) && f.orders != significant_orders(f)) {
    m = with_orders(m, significant_orders(f));
    f = fit_model(m);
  }
  if (m.orders.empty()) return f;
  Model half = with_orders(m, lower_half(m.orders));
  const Fit g = fit_model(half);
  if (std::isfinite(g.nu)) f.nu_model = std::abs(g.nu - f.nu);
  f.nu_sigma = std::hypot(f.nu_stat, f.nu_model);
  return f;
}

}  // namespace rsd::dsp::led
