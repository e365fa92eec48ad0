#include "dsp/diagnosis/velocity_spline.hpp"

#include <algorithm>
#include <cmath>

#include "dsp/diagnosis/band_cholesky.hpp"

namespace rsd::dsp {

namespace {

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

// The band of the normal matrix: a pair touches four control points of three components.
constexpr int kBand = 3 * 4 - 1;

}  // namespace

VelocitySpline::VelocitySpline(const std::vector<double>& pair_times, double knot_s) : knot_(knot_s) {
  if (!pair_times.empty()) {
    const auto [lo, hi] = std::minmax_element(pair_times.begin(), pair_times.end());
    t0_ = *lo;
    intervals_ = std::max(1, static_cast<int>(std::ceil((*hi - *lo) / knot_s)));
  }
  at_.reserve(pair_times.size());
  for (double t : pair_times) at_.push_back(at(t));
  blocks_.resize(static_cast<size_t>(controls()));
  clear();
}

VelocitySpline::At VelocitySpline::at(double t) const {
  At a;
  const double s = (t - t0_) / knot_;
  a.first = std::clamp(static_cast<int>(std::floor(s)), 0, intervals_ - 1);
  const double u = std::clamp(s - a.first, 0.0, 1.0);
  a.w = cubic_weights(u), a.dw = cubic_slopes(u);
  for (double& d : a.dw) d /= knot_;
  return a;
}

void VelocitySpline::clear() {
  for (auto& b : blocks_) b.fill(Eigen::Matrix3d::Zero());
  trace_ = 0;
}

// Control points a and c take W_a^T N W_c, W_a = (w_a I; dw_a I), summed as 3 x 3 blocks from
// the four N W_c and written into the band once (formed term by term and scattered entry by
// entry, they were the largest share of a diagnosis under parallax: the walking phone's minute).
void VelocitySpline::add(size_t q, const PairNormal& N) {
  const auto& [j, w, dw] = at_[q];
  std::array<Eigen::Matrix<double, kUnknowns, 3>, 4> NW;
  for (int c = 0; c < 4; ++c) NW[c].noalias() = w[c] * N.leftCols<3>() + dw[c] * N.rightCols<3>();
  for (int a = 0; a < 4; ++a)
    for (int c = a; c < 4; ++c) blocks_[j + a][c - a] += w[a] * NW[c].topRows<3>() + dw[a] * NW[c].bottomRows<3>();
  trace_ += N.topLeftCorner<3, 3>().trace();
}

Eigen::MatrixXd VelocitySpline::velocities(const Eigen::MatrixXd& B) const {
  const int n = 3 * controls();
  Eigen::MatrixXd band = Eigen::MatrixXd::Zero(kBand + 1, n);  // band(i - j + kBand, j) = A(i, j), i <= j
  for (int k = 0; k < controls(); ++k)
    for (int o = 0; o < 4 && k + o < controls(); ++o)  // the blocks on the diagonal: their upper half
      for (int y = 0; y < 3; ++y)
        for (int x = 0; x < (o == 0 ? y + 1 : 3); ++x) band(kBand - 3 * o + x - y, 3 * (k + o) + y) = blocks_[k][o](x, y);
  const double lambda = 1e-4 * trace_ / n, ridge = 1e-9 * trace_ / n + 1e-12;
  const std::array<double, 3> d = {1, -2, 1};
  for (int k = 0; k + 2 < controls(); ++k)
    for (int a = 0; a < 3; ++a)
      for (int c = a; c < 3; ++c)
        for (int x = 0; x < 3; ++x) band(3 * (a - c) + kBand, 3 * (k + c) + x) += lambda * d[a] * d[c];
  band.row(kBand).array() += ridge;
  const BandCholesky normal(std::move(band));
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(B.rows(), B.cols());
  if (!normal.ok()) return U;
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n, B.cols());
  for (Eigen::Index col = 0; col < B.cols(); ++col)
    for (size_t q = 0; q < at_.size(); ++q) {
      const auto& [j, w, dw] = at_[q];
      const Eigen::Index r = kUnknowns * static_cast<Eigen::Index>(q);
      for (int a = 0; a < 4; ++a)
        c.block<3, 1>(3 * (j + a), col) += w[a] * B.block<3, 1>(r, col) + dw[a] * B.block<3, 1>(r + 3, col);
    }
  normal.solve(c);
  for (Eigen::Index col = 0; col < B.cols(); ++col)
    for (size_t q = 0; q < at_.size(); ++q) {
      const auto& [j, w, dw] = at_[q];
      const Eigen::Index r = kUnknowns * static_cast<Eigen::Index>(q);
      for (int a = 0; a < 4; ++a) {
        U.block<3, 1>(r, col) += w[a] * c.block<3, 1>(3 * (j + a), col);
        U.block<3, 1>(r + 3, col) += dw[a] * c.block<3, 1>(3 * (j + a), col);
      }
    }
  return U;
}

}  // namespace rsd::dsp
