// The spatio-temporal image: column profiles of every frame stacked in time, detrended; frame
// timing and the plan of the fit.

#include <Eigen/Dense>
#include <cmath>
#include <sstream>

#include "dsp/calib/led_internal.hpp"

namespace rsd::dsp::led {

int next_pow2(int n) {
  int p = 1;
  while (p < n) p *= 2;
  return p;
}

std::string fmt(double x, int precision) {
  std::ostringstream o;
  o.precision(precision);
  o << x;
  return o.str();
}

// Luminance of pixel x of a row: Rec. 601 weights for RGB, the luma of YUV, a mosaic's raw
// site (the LED's colour does not matter: every channel carries the same temporal modulation;
// the mosaic's row-parity gain is taken out below).
double luminance(const ImageView& f, const std::uint8_t* row, int x) {
  if (f.format == PixelFormat::Rgb8) return 0.299 * row[3 * x] + 0.587 * row[3 * x + 1] + 0.114 * row[3 * x + 2];
  if (f.format == PixelFormat::Yuyv) return row[2 * x];
  if (sample_bytes(f.format) == 2) return row[2 * x] | row[2 * x + 1] << 8;
  return row[x];  // Mono8, the luma plane of NV12 and I420, 8-bit mosaics
}

// Sums the column blocks with weights into I(k, y). A 2x2 Bayer mosaic makes alternate
// rows differ in gain (a strong 0.5 cycles/row line): the rows of each parity are scaled to
// the same mean. (Averaging row pairs would also do, but would correlate the noise of
// neighbouring rows, which the uncertainty would then have to model.)
Stack make_stack(const std::vector<std::vector<double>>& profiles, const std::vector<double>& w, int h) {
  const int K = static_cast<int>(profiles.size()), blocks = static_cast<int>(w.size());
  Eigen::MatrixXd raw = Eigen::MatrixXd::Zero(K, h);
  for (int k = 0; k < K; ++k)
    for (int b = 0; b < blocks; ++b)
      if (w[b] != 0)
        for (int y = 0; y < h; ++y) raw(k, y) += w[b] * profiles[k][static_cast<size_t>(b) * h + y];
  double even = 0, odd = 0;
  for (int y = 0; y < h; ++y) (y % 2 ? odd : even) += raw.col(y).sum();
  even /= (h + 1) / 2;
  odd /= h / 2;
  if (even > 0 && odd > 0)
    for (int y = 0; y < h; ++y) raw.col(y) *= 0.5 * (even + odd) / (y % 2 ? odd : even);
  Stack st;
  st.s = raw;
  for (int y = 0; y < h; ++y) st.yc.push_back(y - 0.5 * (h - 1));
  return st;
}

// Least-squares cubic trend of one profile (Legendre basis for conditioning).
Eigen::VectorXd cubic_trend(const Eigen::VectorXd& v) {
  const int n = static_cast<int>(v.size());
  Eigen::MatrixXd A(n, 4);
  for (int y = 0; y < n; ++y) {
    const double x = n > 1 ? 2.0 * y / (n - 1) - 1 : 0;
    A.row(y) << 1, x, 0.5 * (3 * x * x - 1), 0.5 * (5 * x * x * x - 3 * x);
  }
  return A * A.colPivHouseholderQr().solve(v);
}

// Each frame relative to its smooth trend: removes the illumination's slow variation
// (and, dividing, its gain) so the bars dominate the spectrum.
Eigen::MatrixXd detrended(const Eigen::MatrixXd& s, bool relative) {
  Eigen::MatrixXd x(s.rows(), s.cols());
  for (int k = 0; k < s.rows(); ++k) {
    const Eigen::VectorXd row = s.row(k).transpose();
    const Eigen::VectorXd t = cubic_trend(row);
    if (relative && t.minCoeff() > 0)
      x.row(k) = (row.array() / t.array() - 1).matrix().transpose();
    else
      x.row(k) = (row - t).transpose();
  }
  return x;
}

// Smallest eigenvalue of the mean of [1 cos w sin w]^T [1 cos w sin w]: how well the frames'
// LED phases separate a row's offset from its modulation (0.5 for evenly spread phases,
// 0 when the bars are frozen, f a multiple of the frame rate).
double phase_diversity(const std::vector<double>& omega) {
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  for (double w : omega) {
    const Eigen::Vector3d v(1, std::cos(w), std::sin(w));
    m += v * v.transpose();
  }
  m /= static_cast<double>(omega.size());
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m).eigenvalues()(0);
}

}  // namespace rsd::dsp::led
