// The joint sinusoid model of the LED bars over rows and frames (paper section 5): smooth
// illumination bases, samples, the Ceres cost, linear solves, identifiable harmonics.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>

#include "dsp/calib/led_internal.hpp"

namespace rsd::dsp::led {

Basis constant_basis(int n) {
  Basis b;
  b.first.assign(n, 0);
  b.w.assign(n, {1, 0, 0, 0});
  return b;
}

Basis spline_basis(int n, int segments) {
  Basis b;
  b.size = segments + 3;
  for (int y = 0; y < n; ++y) {
    const double u = n > 1 ? double(y) / (n - 1) * segments : 0;
    const int i = std::min(static_cast<int>(u), segments - 1);
    const double t = u - i, t2 = t * t, t3 = t2 * t;
    b.first.push_back(i);
    b.w.push_back({(1 - t) * (1 - t) * (1 - t) / 6, (3 * t3 - 6 * t2 + 4) / 6, (-3 * t3 + 3 * t2 + 3 * t + 1) / 6,
                   t3 / 6});
  }
  return b;
}

// Illumination must vary slower than the bars: about three bar periods per segment.
int segments_for(double cycles_per_frame) {
  return std::clamp(static_cast<int>(cycles_per_frame / 3), 1, 12);
}

Sample make_sample(const Stack& st, const Basis& basis, int k, int y, double omega) {
  Sample s;
  s.y = st.yc[y];
  s.row = y;
  s.omega = omega;
  s.value = st.s(k, y);
  s.first = basis.first[y];
  s.nw = basis.count(y);
  s.w = basis.w[y];
  return s;
}

Model build_model(const Stack& st, const Plan& plan, const Basis& basis) {
  const int K = static_cast<int>(st.s.rows()), n = static_cast<int>(st.s.cols());
  Model m;
  m.kind = plan.model;
  m.J = basis.size;
  m.rows = n;
  if (plan.model == LedModel::JointPerRow) {
    for (int y = 0; y < n; ++y) {
      Group g{{}, y, 0};
      for (int k = 0; k < K; ++k) g.samples.push_back(make_sample(st, basis, k, y, plan.omega[k]));
      m.groups.push_back(std::move(g));
    }
    m.nuisance.assign(n, std::vector<double>(2, 0.0));
    m.phase.assign(1, 0.0);
    return m;
  }
  const bool shared = plan.model == LedModel::JointSmooth;
  for (int k = 0; k < K; ++k) {
    Group g{{}, shared ? 0 : k, shared ? 0 : k};
    for (int y = 0; y < n; ++y) g.samples.push_back(make_sample(st, basis, k, y, plan.omega[k]));
    m.groups.push_back(std::move(g));
  }
  m.nuisance.assign(shared ? 1 : K, std::vector<double>(2 * basis.size, 0.0));
  m.phase.assign(shared ? 1 : K, 0.0);
  return m;
}

void design_row(const Sample& s, int J, double nu, double phi, Linear kind, Eigen::VectorXd& row) {
  row.setZero();
  for (int j = 0; j < s.nw; ++j) row[s.first + j] = s.w[j];
  const double th = 2 * kPi * nu * s.y + s.omega + phi;
  if (kind == Linear::Envelope)
    for (int j = 0; j < s.nw; ++j) row[J + s.first + j] = s.w[j] * std::cos(th);
  if (kind == Linear::Relaxed) {
    row[J] = std::cos(th);
    row[J + 1] = std::sin(th);
  }
}

// Solves the linear parameters of every nuisance block (nu and the phases fixed) and
// returns the residual sum of squares. Relaxed fits also set the phase of each block's
// groups (the smooth models have one phase per nuisance block).
double solve_linear(Model& m, Linear kind) {
  const int cols = kind == Linear::OffsetOnly ? m.J : kind == Linear::Envelope ? 2 * m.J : m.J + 2;
  const int blocks = static_cast<int>(m.nuisance.size());
  std::vector<Eigen::MatrixXd> ata(blocks, Eigen::MatrixXd::Zero(cols, cols));
  std::vector<Eigen::VectorXd> atb(blocks, Eigen::VectorXd::Zero(cols));
  std::vector<double> btb(blocks, 0.0);
  Eigen::VectorXd row(cols);
  for (const Group& g : m.groups)
    for (const Sample& s : g.samples) {
      design_row(s, m.J, m.nu, kind == Linear::Relaxed ? 0.0 : m.phase[g.phase], kind, row);
      ata[g.nuisance].selfadjointView<Eigen::Lower>().rankUpdate(row);
      atb[g.nuisance] += row * s.value;
      btb[g.nuisance] += s.value * s.value;
    }
  double rss = 0;
  for (int b = 0; b < blocks; ++b) {
    Eigen::MatrixXd A = ata[b].selfadjointView<Eigen::Lower>();
    A.diagonal().array() += 1e-12 * (A.diagonal().maxCoeff() + 1e-300);  // empty rows stay finite
    const Eigen::VectorXd x = A.ldlt().solve(atb[b]);
    rss += std::max(0.0, btb[b] - x.dot(atb[b]));
    std::vector<double>& nz = m.nuisance[b];
    std::fill(nz.begin(), nz.end(), 0.0);
    for (int j = 0; j < std::min(cols, m.J); ++j) nz[j] = x[j];
    if (kind == Linear::Envelope)
      for (int j = 0; j < m.J; ++j) nz[m.J + j] = x[m.J + j];
    if (kind == Linear::Relaxed) {  // c cos + s sin = A cos(th - atan2(s, c))
      for (const Group& g : m.groups)
        if (g.nuisance == b) m.phase[g.phase] = -std::atan2(x[m.J + 1], x[m.J]);
      for (int j = 0; j < m.J; ++j) nz[m.J + j] = std::hypot(x[m.J], x[m.J + 1]);
    }
  }
  return rss;
}

// |mean_k exp(i d omega_k)|: near 1 when two components d apart in temporal frequency
// take the same phases in every frame (they alias onto each other in time).
double temporal_overlap(const std::vector<double>& omega, int d) {
  cd acc = 0;
  for (double w : omega) acc += std::polar(1.0, d * w);
  return std::abs(acc) / static_cast<double>(omega.size());
}

// Harmonics a model may include: below kMaxNu cycles/row (higher ones fold back near the
// fundamental and the Bayer line on the row grid), at most kMaxHarmonic. With per-row offsets, a harmonic
// whose phase does not move between frames is absorbed by the offsets: left out.
std::vector<int> candidate_orders(const Plan& plan, double nu) {
  std::vector<int> orders;
  const int top = std::min(kMaxHarmonic, static_cast<int>(kMaxNu / std::max(std::abs(nu), 1e-9)));
  for (int h = 2; h <= top; ++h)
    if (plan.model != LedModel::JointPerRow || temporal_overlap(plan.omega, h) <= 0.5) orders.push_back(h);
  return orders;
}

// Columns of the Jacobian (nu, phi, then cos/sin of each candidate harmonic) for one row
// of the per-row model at shape = 0, with the row's own offset and gain projected out:
// what is left is what the data can attribute to the global parameters.
Eigen::MatrixXd reduced_columns(const Model& m, const Group& g, const std::vector<int>& cands) {
  const int K = static_cast<int>(g.samples.size()), G = 2 + 2 * static_cast<int>(cands.size());
  const double b = m.nuisance[g.nuisance][1];
  Eigen::MatrixXd X(K, G), P(K, 2);
  for (int k = 0; k < K; ++k) {
    const Sample& s = g.samples[k];
    const double th = 2 * kPi * m.nu * s.y + s.omega + m.phase[g.phase];
    P.row(k) << 1, std::cos(th);
    X(k, 0) = -b * std::sin(th) * 2 * kPi * s.y;
    X(k, 1) = -b * std::sin(th);
    for (size_t c = 0; c < cands.size(); ++c) {
      X(k, 2 + 2 * c) = b * std::cos(cands[c] * th);
      X(k, 3 + 2 * c) = b * std::sin(cands[c] * th);
    }
  }
  const Eigen::MatrixXd coef = (P.transpose() * P + 1e-12 * Eigen::Matrix2d::Identity()).ldlt().solve(P.transpose() * X);
  return X - P * coef;
}

// Smallest eigenvalue of the part of columns `add` not explained by columns `keep`,
// relative to their own size: 1 for independent columns, 0 for redundant ones.
double new_information(const Eigen::MatrixXd& gram, const std::vector<int>& keep, const std::vector<int>& add) {
  const int nk = static_cast<int>(keep.size()), na = static_cast<int>(add.size());
  Eigen::MatrixXd kk(nk, nk), ka(nk, na), aa(na, na);
  for (int i = 0; i < nk; ++i)
    for (int j = 0; j < nk; ++j) kk(i, j) = gram(keep[i], keep[j]);
  for (int i = 0; i < nk; ++i)
    for (int j = 0; j < na; ++j) ka(i, j) = gram(keep[i], add[j]);
  for (int i = 0; i < na; ++i)
    for (int j = 0; j < na; ++j) aa(i, j) = gram(add[i], add[j]);
  const Eigen::MatrixXd rest = aa - ka.transpose() * kk.ldlt().solve(ka);
  const Eigen::VectorXd d = aa.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(d.asDiagonal() * rest * d.asDiagonal()).eigenvalues()(0);
}

// The harmonics the data can tell apart from nu, phi and each other, in order of
// increasing h. With known frame times, harmonics alias onto the fundamental or onto each
// other in time (f a simple fraction of the frame rate). Each must add at least
// kMinNewInfo of new information, and all together may not take more than half of nu's:
// a series of aliased harmonics can otherwise mimic the phase ramp that measures nu (at
// f = fps/3 an unknown duty cycle trades off exactly against the line delay).
std::vector<int> identifiable_orders(const Model& m, const std::vector<int>& cands) {
  if (m.kind != LedModel::JointPerRow || cands.empty()) return cands;
  const int G = 2 + 2 * static_cast<int>(cands.size());
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(G, G);
  for (const Group& g : m.groups) {
    const Eigen::MatrixXd x = reduced_columns(m, g, cands);
    gram.noalias() += x.transpose() * x;
  }
  std::vector<int> keep{1}, orders;  // phi and the harmonics kept (nu is column 0)
  const double nu_info = new_information(gram, keep, {0});
  for (size_t c = 0; c < cands.size(); ++c) {
    const std::vector<int> add{2 + 2 * static_cast<int>(c), 3 + 2 * static_cast<int>(c)};
    std::vector<int> with = keep;
    with.insert(with.end(), add.begin(), add.end());
    std::vector<int> all = keep;
    all.push_back(0);
    if (new_information(gram, all, add) < kMinNewInfo) continue;
    if (new_information(gram, with, {0}) * kMaxNuInflation < nu_info) continue;
    keep = with;
    orders.push_back(cands[c]);
  }
  return orders;
}

void set_orders(Model& m, std::vector<int> orders) {
  m.orders = std::move(orders);
  m.shape.assign(2 * m.orders.size(), 0.0);
}

}  // namespace rsd::dsp::led
