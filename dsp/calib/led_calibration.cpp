#include "dsp/calib/led_calibration.hpp"

#include "dsp/core/statistics.hpp"

#include <ceres/ceres.h>
#include <fftw3.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <memory>
#include <numeric>
#include <sstream>

namespace rsd::dsp {

namespace {

constexpr double kPi = 3.14159265358979323846;
using cd = std::complex<double>;

// ---------------------------------------------------------------- tuning constants

constexpr int kMaxBlocks = 32;           // column blocks per frame (modulation-weighted)
constexpr double kBlockKeep = 0.25;      // blocks below this fraction of the best are dropped
constexpr double kMinDiversity = 0.1;    // smallest eigenvalue of the per-row phase design
constexpr double kMinCyclesSmooth = 1.5; // bars per frame a smooth illumination model needs
constexpr double kMaxNu = 0.45;          // above: the Bayer / row-Nyquist region is ignored
constexpr double kReadoutSlack = 1.1;    // frame rate may be nominal: allow 10% slower rows
constexpr double kHarmonicRatio = 0.3;   // a sub-harmonic peak this strong is the fundamental
constexpr double kPeakOverFloor = 30;    // spectral peak / median power to count as a peak
constexpr double kMinF = 10;             // F statistic of the sinusoid over the null model
constexpr double kMaxRelSigma = 0.05;    // relative uncertainty above which nu is undetermined
// Systematic floor on the relative uncertainty of the line delay: the largest bias seen on
// noise-free synthetic captures (sharp square waves, blur, vignetting) is below 1e-5.
constexpr double kModelFloor = 2e-5;
constexpr int kMaxHarmonic = 32;        // harmonics of a non-sinusoidal LED in the model
constexpr double kMinNewInfo = 0.1;      // a harmonic must be this far from the span of the others
constexpr double kMaxNuInflation = 2;    // harmonics may raise nu's variance at most this much
constexpr double kMinHarmonicZ = 4;      // a harmonic counts as present at this many sigma

// ---------------------------------------------------------------- small helpers

int next_pow2(int n) {
  int p = 1;
  while (p < n) p *= 2;
  return p;
}

std::string fmt(double x, int precision = 4) {
  std::ostringstream o;
  o.precision(precision);
  o << x;
  return o.str();
}

// Luminance of pixel x of a row: Rec. 601 weights for RGB (the LED's colour does not
// matter: every channel carries the same temporal modulation).
double luminance(const ImageView& f, const std::uint8_t* row, int x) {
  switch (f.format) {
    case PixelFormat::Mono8: return row[x];
    case PixelFormat::Mono16: return reinterpret_cast<const std::uint16_t*>(row)[x];
    case PixelFormat::Rgb8: return 0.299 * row[3 * x] + 0.587 * row[3 * x + 1] + 0.114 * row[3 * x + 2];
  }
  return 0;
}

// ---------------------------------------------------------------- the spatio-temporal image

// The paper's I(y, t): one row per frame, one column per (averaged) image row.
struct Stack {
  Eigen::MatrixXd s;        // K x n
  std::vector<double> yc;   // row y relative to the frame centre
};

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

// ---------------------------------------------------------------- frame timing and the model

struct Plan {
  LedModel model = LedModel::PerFrame;
  std::vector<double> omega;     // LED phase at each frame start, 2 pi f t_k (0 when unknown)
  double nu_hi = kMaxNu;         // largest plausible |nu|
  std::optional<double> period;  // frame period, from the option or the timestamps
};

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

// ---------------------------------------------------------------- spectra (FFTW)

struct FftwFree {
  void operator()(void* p) const { fftw_free(p); }
};
template <class T>
std::unique_ptr<T[], FftwFree> fftw_array(size_t n) {
  return std::unique_ptr<T[], FftwFree>(static_cast<T*>(fftw_malloc(sizeof(T) * n)));
}

// The paper's marginal spectrum: |2-D DFT of x(k, y)|^2 summed over temporal frequency,
// for spatial frequencies i / nfft, i = 0..nfft/2 (Hann window along y, zero padding).
std::vector<double> marginal_spectrum(const Eigen::MatrixXd& x, int nfft) {
  const int K = static_cast<int>(x.rows()), n = static_cast<int>(x.cols()), nh = nfft / 2 + 1;
  auto in = fftw_array<double>(static_cast<size_t>(K) * nfft);
  auto out = fftw_array<fftw_complex>(static_cast<size_t>(K) * nh);
  std::fill(in.get(), in.get() + static_cast<size_t>(K) * nfft, 0.0);
  for (int k = 0; k < K; ++k)
    for (int y = 0; y < n; ++y)
      in[static_cast<size_t>(k) * nfft + y] = x(k, y) * (0.5 - 0.5 * std::cos(2 * kPi * (y + 0.5) / n));
  fftw_plan p = fftw_plan_dft_r2c_2d(K, nfft, in.get(), out.get(), FFTW_ESTIMATE);
  fftw_execute(p);
  fftw_destroy_plan(p);
  std::vector<double> power(nh, 0.0);
  for (int k = 0; k < K; ++k)
    for (int i = 0; i < nh; ++i) {
      const fftw_complex& c = out[static_cast<size_t>(k) * nh + i];
      power[i] += c[0] * c[0] + c[1] * c[1];
    }
  return power;
}

// |DFT|^2 of a complex row signal z_y at signed frequencies (bin i is i / nfft, wrapped).
std::vector<double> complex_spectrum(const std::vector<cd>& z, int nfft) {
  auto buf = fftw_array<fftw_complex>(nfft);
  for (int i = 0; i < nfft; ++i) {
    const cd v = i < static_cast<int>(z.size()) ? z[i] : cd(0);
    buf[i][0] = v.real();
    buf[i][1] = v.imag();
  }
  fftw_plan p = fftw_plan_dft_1d(nfft, buf.get(), buf.get(), FFTW_FORWARD, FFTW_ESTIMATE);
  fftw_execute(p);
  fftw_destroy_plan(p);
  std::vector<double> power(nfft);
  for (int i = 0; i < nfft; ++i) power[i] = buf[i][0] * buf[i][0] + buf[i][1] * buf[i][1];
  return power;
}

// ---------------------------------------------------------------- peak picking

// A power spectrum sampled at frequencies freq(i) (one- or two-sided).
struct Spectrum {
  std::vector<double> power;
  int nfft = 0;
  bool two_sided = false;
  double freq(int i) const { return two_sided && i >= nfft / 2 ? double(i - nfft) / nfft : double(i) / nfft; }
};

struct Peak {
  double nu = 0;       // refined below one bin
  int harmonic = 1;    // 1, or m when the strongest peak was the m-th harmonic
  double over_floor = 0;  // peak power / median power of the usable band
};

// Highest bin with freq in [lo, hi] and |freq| <= nu_hi; -1 if none.
int argmax_in(const Spectrum& s, double lo, double hi, double nu_hi) {
  int best = -1;
  for (int i = 0; i < static_cast<int>(s.power.size()); ++i) {
    const double f = s.freq(i);
    if (f < lo || f > hi || std::abs(f) > nu_hi) continue;
    if (best < 0 || s.power[i] > s.power[best]) best = i;
  }
  return best;
}

// Sub-bin position of the peak at bin i: parabola through the log powers (exact for the
// Gaussian-like lobe of a Hann window, close for the others).
double refine_bin(const Spectrum& s, int i) {
  const int n = static_cast<int>(s.power.size());
  if (!s.two_sided && (i == 0 || i + 1 >= n)) return s.freq(i);
  const auto at = [&](int j) { return std::log(std::max(s.power[(j + n) % n], 1e-300)); };
  const double a = at(i - 1), b = at(i), c = at(i + 1), den = a - 2 * b + c;
  const double off = den < 0 ? std::clamp(0.5 * (a - c) / den, -0.5, 0.5) : 0.0;
  return s.freq(i) + off / s.nfft;
}

bool is_local_max(const Spectrum& s, int i) {
  const int n = static_cast<int>(s.power.size());
  if (!s.two_sided && (i == 0 || i + 1 >= n)) return false;
  return s.power[i] >= s.power[(i + n - 1) % n] && s.power[i] >= s.power[(i + 1) % n];
}

// The LED's fundamental: the strongest peak in [nu_lo, nu_hi] (both signs when two-sided),
// unless a peak at 1/m of its frequency is at least kHarmonicRatio as strong in amplitude,
// in which case the strongest is a harmonic of a square-wave drive (the paper: "high
// frequency components are ignored because the image is not a sine wave").
Peak pick_fundamental(const Spectrum& s, double nu_lo, double nu_hi, int rows) {
  std::vector<double> band;  // the noise floor: over all usable frequencies, not just plausible ones
  for (int i = 0; i < static_cast<int>(s.power.size()); ++i)
    if (std::abs(s.freq(i)) >= nu_lo && std::abs(s.freq(i)) <= kMaxNu) band.push_back(s.power[i]);
  const double floor = std::max(median(band), 1e-300);
  const int top = argmax_in(s, -nu_hi, nu_hi, nu_hi);
  if (top < 0 || (!s.two_sided && s.freq(top) < nu_lo)) return {};
  Peak p{refine_bin(s, top), 1, s.power[top] / floor};
  const double f0 = s.freq(top), raw_bin = 1.0 / rows;
  for (int m = 2; m <= 8 && std::abs(f0) / m >= nu_lo && std::abs(f0) * (1 - 1.0 / m) >= 2 * raw_bin; ++m)
    for (double sign : {1.0, -1.0}) {
      if (!s.two_sided && sign < 0) continue;
      const double target = sign * f0 / m;  // f0 is accurate to a fraction of a bin
      const int i = argmax_in(s, target - 0.5 * raw_bin, target + 0.5 * raw_bin, nu_hi);
      if (i < 0 || !is_local_max(s, i) || s.power[i] < kPeakOverFloor * floor) continue;
      if (std::sqrt(s.power[i] / s.power[top]) >= kHarmonicRatio) p = {refine_bin(s, i), m, s.power[i] / floor};
    }
  return p;
}

// ---------------------------------------------------------------- per-row demodulation

// With known frame phases omega_k, each row's offset and complex amplitude
// z_y = b_y exp(i rho_y) follow from a linear fit of I(k, y) = a_y + Re(z_y exp(i omega_k)).
// rho_y = 2 pi nu y + phi: the 2-D Fourier transform at the LED's temporal frequency.
std::vector<cd> demodulate_rows(const Eigen::MatrixXd& s, const std::vector<double>& omega) {
  const int K = static_cast<int>(s.rows()), n = static_cast<int>(s.cols());
  Eigen::MatrixXd V(K, 3);
  for (int k = 0; k < K; ++k) V.row(k) << 1, std::cos(omega[k]), std::sin(omega[k]);
  const Eigen::MatrixXd coef = (V.transpose() * V).ldlt().solve(V.transpose() * s);  // 3 x n
  std::vector<cd> z(n);
  for (int y = 0; y < n; ++y) z[y] = cd(coef(1, y), -coef(2, y));
  return z;
}

// ---------------------------------------------------------------- the smooth basis

// Uniform cubic B-splines over the rows: 4 non-zero functions at each row.
struct Basis {
  int size = 1;             // functions per nuisance (a or b)
  std::vector<int> first;   // per row: index of the first non-zero function
  std::vector<std::array<double, 4>> w;
  int count(int) const { return size == 1 ? 1 : 4; }
};

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

// ---------------------------------------------------------------- the joint sinusoid model

// One sample I(k, y) with its basis weights and known phase offset.
struct Sample {
  double y = 0, omega = 0, value = 0;
  int row = 0;  // index in the stack (for clustering residuals into bands of rows)
  int first = 0, nw = 1;
  std::array<double, 4> w{1, 0, 0, 0};
};

// Residuals model - data of a group of samples sharing one nuisance block [a coefs, b coefs]
// (2J values), the frequency nu (cycles/row), one phase phi and the waveform's harmonics:
//   model = a(y) + b(y) g(theta),  theta = 2 pi nu y + omega + phi,
//   g(theta) = cos theta + sum_h (p_h cos h theta + q_h sin h theta).
// A square-wave drive, gamma and clipping all make g non-sinusoidal; modelling its
// harmonics keeps them out of the residual (where they would inflate the uncertainty)
// and stops them biasing nu when they alias onto the fundamental.
class SinusoidCost final : public ceres::CostFunction {
 public:
  SinusoidCost(std::vector<Sample> samples, int J, std::vector<int> orders)
      : samples_(std::move(samples)), J_(J), orders_(std::move(orders)) {
    set_num_residuals(static_cast<int>(samples_.size()));
    *mutable_parameter_block_sizes() = {2 * J, 1, 1};
    if (!orders_.empty()) mutable_parameter_block_sizes()->push_back(2 * static_cast<int>(orders_.size()));
  }

  bool Evaluate(double const* const* p, double* r, double** jac) const override {
    const double* coef = p[0];
    const double nu = p[1][0], phi = p[2][0];
    const double* shape = orders_.empty() ? nullptr : p[3];
    const size_t nh = orders_.size();
    for (size_t i = 0; i < samples_.size(); ++i) {
      const Sample& s = samples_[i];
      double a = 0, b = 0;
      for (int j = 0; j < s.nw; ++j) {
        a += s.w[j] * coef[s.first + j];
        b += s.w[j] * coef[J_ + s.first + j];
      }
      const double th = 2 * kPi * nu * s.y + s.omega + phi;
      double g = std::cos(th), dg = -std::sin(th);
      const cd step = std::polar(1.0, th);
      cd e = 1;  // exp(i h th), by repeated multiplication
      for (size_t h = 0, order = 0; h < nh; ++h) {
        for (; order < static_cast<size_t>(orders_[h]); ++order) e *= step;
        const double ch = e.real(), sh = e.imag();
        g += shape[2 * h] * ch + shape[2 * h + 1] * sh;
        dg += orders_[h] * (shape[2 * h + 1] * ch - shape[2 * h] * sh);
        if (jac && jac[3]) {
          jac[3][i * 2 * nh + 2 * h] = b * ch;
          jac[3][i * 2 * nh + 2 * h + 1] = b * sh;
        }
      }
      r[i] = a + b * g - s.value;
      if (!jac) continue;
      if (jac[0]) {
        double* row = jac[0] + i * 2 * J_;
        std::fill(row, row + 2 * J_, 0.0);
        for (int j = 0; j < s.nw; ++j) {
          row[s.first + j] = s.w[j];
          row[J_ + s.first + j] = s.w[j] * g;
        }
      }
      if (jac[1]) jac[1][i] = b * dg * 2 * kPi * s.y;
      if (jac[2]) jac[2][i] = b * dg;
    }
    return true;
  }

 private:
  std::vector<Sample> samples_;
  int J_;
  std::vector<int> orders_;  // harmonic orders h >= 2 in the model
};

struct Group {
  std::vector<Sample> samples;
  int nuisance = 0, phase = 0;
};

// The parameters and data of one fit. Joint per-row: a group per row, own nuisance, one
// phase. Joint smooth: a group per frame, one shared nuisance, one phase. Per frame: a
// group per frame, each with its own nuisance and phase.
struct Model {
  LedModel kind = LedModel::PerFrame;
  int J = 1, rows = 0;
  double nu = 0;
  std::vector<std::vector<double>> nuisance;
  std::vector<double> phase;
  std::vector<int> orders;    // harmonics of the waveform in the model
  std::vector<double> shape;  // their coefficients (p_h, q_h), relative to the fundamental
  std::vector<Group> groups;
  int samples() const {
    int n = 0;
    for (const Group& g : groups) n += static_cast<int>(g.samples.size());
    return n;
  }
  int parameters() const {
    return static_cast<int>(nuisance.size()) * 2 * J + static_cast<int>(phase.size() + shape.size()) + 1;
  }
};

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

// Design row of a sample for the linear parameters, given nu and phi: the a-part, then
// either the b-part (envelope times the cosine) or, relaxed, a constant envelope's
// cosine and sine (any phase).
enum class Linear { OffsetOnly, Envelope, Relaxed };

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

// ---------------------------------------------------------------- the nonlinear fit

struct Fit {
  double nu = 0, nu_sigma = 0, nu_stat = 0, nu_model = 0, rss = 0, rss_null = 0;
  std::vector<int> orders;         // harmonics in the model
  std::vector<double> harmonic_z;  // and their significance
  int samples = 0, parameters = 0, null_parameters = 0;
  double depth = 0, amplitude = 0;
  LedModel kind = LedModel::PerFrame;
  double s2() const { return rss / std::max(1, samples - parameters); }
  double f_statistic() const {
    const int dp = std::max(1, parameters - null_parameters);
    return rss > 0 ? (rss_null - rss) / dp / s2() : std::numeric_limits<double>::infinity();
  }
};

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

// ---------------------------------------------------------------- uncertainty

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

// ---------------------------------------------------------------- seeds

struct Seed {
  double nu = 0, phi = 0;
  Peak peak;
};

// Joint per-row: demodulate every row at the LED's temporal frequency, then find the
// spatial frequency of the row phasors (any sign: the sign is the readout direction).
Seed seed_per_row(const Stack& st, const Plan& plan) {
  const std::vector<cd> z = demodulate_rows(st.s, plan.omega);
  const int n = static_cast<int>(z.size());
  Spectrum sp{complex_spectrum(z, next_pow2(16 * n)), next_pow2(16 * n), true};
  Seed s;
  s.peak = pick_fundamental(sp, 0.0, plan.nu_hi, n);
  s.nu = s.peak.nu;
  cd acc = 0;
  for (int y = 0; y < n; ++y) acc += z[y] * std::polar(1.0, -2 * kPi * s.nu * st.yc[y]);
  s.phi = std::arg(acc);
  return s;
}

// Smooth models: the paper's marginalised 2-D spectrum of the detrended frames.
Seed seed_spectral(const Stack& st, const Plan& plan) {
  const int n = static_cast<int>(st.s.cols());
  const int nfft = next_pow2(8 * n);
  Spectrum sp{marginal_spectrum(detrended(st.s, true), nfft), nfft, false};
  Seed s;
  s.peak = pick_fundamental(sp, kMinCyclesSmooth / n, plan.nu_hi, n);
  s.nu = s.peak.nu;
  return s;
}

// Relaxed grid search around the seed (one raw bin either side), then the exact linear
// parameters at the best nu: the starting point of the nonlinear fit.
double grid_start(Model& m, double nu0, int rows) {
  double best = nu0, best_rss = std::numeric_limits<double>::infinity();
  for (int i = -20; i <= 20; ++i) {
    m.nu = nu0 + i / (20.0 * rows);
    const double rss = solve_linear(m, Linear::Relaxed);
    if (rss < best_rss) best_rss = rss, best = m.nu;
  }
  m.nu = best;
  solve_linear(m, Linear::Relaxed);  // phases at the best nu
  solve_linear(m, Linear::Envelope);
  return best_rss;
}

// ---------------------------------------------------------------- column weighting

// Amplitude of the bars at the seed in a stack (detrended as the model will see it).
double bar_amplitude(const Stack& st, const Plan& plan, double nu) {
  const int K = static_cast<int>(st.s.rows()), n = static_cast<int>(st.s.cols());
  if (plan.model == LedModel::JointPerRow) {
    const Eigen::RowVectorXd mean = st.s.colwise().mean();
    cd acc = 0;
    for (int k = 0; k < K; ++k)
      for (int y = 0; y < n; ++y)
        acc += (st.s(k, y) - mean(y)) * std::polar(1.0, -(plan.omega[k] + 2 * kPi * nu * st.yc[y]));
    return 2 * std::abs(acc) / (K * n);
  }
  const Eigen::MatrixXd x = detrended(st.s, false);
  double sum = 0;
  for (int k = 0; k < K; ++k) {
    cd acc = 0;
    for (int y = 0; y < n; ++y) acc += x(k, y) * std::polar(1.0, -2 * kPi * nu * st.yc[y]);
    sum += 2 * std::abs(acc) / n;
  }
  return sum / K;
}

// Weight of each column block: its bar amplitude, or 0 below kBlockKeep of the best. This
// is the paper's "selected and summed a subset of the columns", chosen by the data: unlit,
// dark and saturated columns carry noise but no bars.
std::vector<double> block_weights(const std::vector<std::vector<double>>& profiles, int blocks, int h,
                                  const Plan& plan, double nu) {
  std::vector<double> amp(blocks);
  for (int b = 0; b < blocks; ++b) {
    std::vector<double> one(blocks, 0.0);
    one[b] = 1;
    amp[b] = bar_amplitude(make_stack(profiles, one, h), plan, nu);
  }
  const double best = *std::max_element(amp.begin(), amp.end());
  for (double& a : amp) a = best > 0 && a >= kBlockKeep * best ? a / best : 0.0;
  return amp;
}

// ---------------------------------------------------------------- the estimator's steps

Plan make_plan(const LedCalibrationOptions& o, const std::vector<std::optional<double>>& times, int h) {
  const int K = static_cast<int>(times.size());
  const bool stamped = std::all_of(times.begin(), times.end(), [](const auto& t) { return t.has_value(); });
  std::vector<double> t;
  Plan p;
  if (stamped) {
    for (const auto& ts : times) t.push_back(*ts - *times.front());
    std::vector<double> dt;
    for (int k = 1; k < K; ++k) dt.push_back(t[k] - t[k - 1]);
    if (o.fps) p.period = 1 / *o.fps;
    else if (!dt.empty() && median(dt) > 0) p.period = median(dt);
  } else if (o.fps) {
    for (int k = 0; k < K; ++k) t.push_back(k / *o.fps);
    p.period = 1 / *o.fps;
  }
  p.omega.assign(K, 0.0);
  if (K >= 2 && !t.empty()) {
    for (int k = 0; k < K; ++k) {  // wrapped before scaling: t_k f may be large
      const double u = o.led_hz * t[k];
      p.omega[k] = 2 * kPi * (u - std::floor(u));
    }
    const bool moving = K >= 3 && phase_diversity(p.omega) >= kMinDiversity;
    p.model = moving ? LedModel::JointPerRow : LedModel::JointSmooth;
  }
  // The readout cannot be slower than the frame period: |nu| <= f * period / rows.
  if (p.period) p.nu_hi = std::min(kMaxNu, kReadoutSlack * o.led_hz * *p.period / h);
  return p;
}

// A flat capture (or one whose rows never change) has nothing to fit.
void require_variation(const Stack& st) {
  const double mean = st.s.mean();
  const double var = (st.s.array() - mean).square().mean();
  if (!(var > 1e-12 * (mean * mean + 1)))
    throw LedCalibrationError("no LED modulation found: the image is flat (no variation between rows)");
}

Seed find_seed(const Stack& st, const Plan& plan) {
  if (plan.model == LedModel::JointPerRow) return seed_per_row(st, plan);
  Seed s = seed_spectral(st, plan);
  if (s.peak.over_floor < kPeakOverFloor)
    throw LedCalibrationError(
        "no LED modulation found: no horizontal bars repeating at least " + fmt(kMinCyclesSmooth) +
        " times per frame (with unknown frame times, or an LED frequency near a multiple of the frame rate, "
        "the bars must be seen within single frames; give several consecutive frames and --fps for slower bars)");
  return s;
}

struct Outcome {
  Fit fit;
  Seed seed;
  std::optional<Readout> readout;
};

// Fits `m` (from its starting point) with the harmonics that are present; a quick fit is
// one solve, without the model-truncation check.
Fit fit_present(Model m, bool quick) {
  m = with_orders(m, present_orders(m));
  if (!quick) return fit_checked(m);
  return fit_model(m);
}

Outcome fit_per_row(const Stack& st, const Plan& plan, const Seed& seed, bool quick) {
  Model m = build_model(st, plan, constant_basis(static_cast<int>(st.s.cols())));
  m.nu = seed.nu;
  m.phase[0] = seed.phi;
  solve_linear(m, Linear::Envelope);
  set_orders(m, identifiable_orders(m, candidate_orders(plan, m.nu)));
  Outcome o{fit_present(m, quick), seed, std::nullopt};
  o.readout = o.fit.nu >= 0 ? Readout::TopToBottom : Readout::BottomToTop;
  return o;
}

// Smooth models. Joint smooth tries both signs of nu: the frames' small phase advance
// tells the readout direction when it is large enough to matter.
Outcome fit_smooth(const Stack& st, const Plan& plan, const Seed& seed, bool quick) {
  const int n = static_cast<int>(st.s.cols());
  Model m = build_model(st, plan, spline_basis(n, segments_for(std::abs(seed.nu) * n)));
  set_orders(m, candidate_orders(plan, seed.nu));
  if (plan.model == LedModel::PerFrame) {
    grid_start(m, seed.nu, n);
    return {fit_present(m, quick), seed, std::nullopt};
  }
  Model neg = m;
  const double rss_pos = grid_start(m, seed.nu, n), rss_neg = grid_start(neg, -seed.nu, n);
  Outcome o{fit_present(rss_pos <= rss_neg ? m : neg, quick), seed, std::nullopt};
  if (std::abs(rss_pos - rss_neg) > 25 * o.fit.s2())  // the better sign fits by 5 sigma
    o.readout = o.fit.nu >= 0 ? Readout::TopToBottom : Readout::BottomToTop;
  return o;
}

Outcome fit_plan(const Stack& st, const Plan& plan, bool quick = false) {
  const Seed seed = find_seed(st, plan);
  return plan.model == LedModel::JointPerRow ? fit_per_row(st, plan, seed, quick)
                                             : fit_smooth(st, plan, seed, quick);
}

bool acceptable(const Fit& f) {
  return f.f_statistic() >= kMinF && f.nu_sigma / std::abs(f.nu) <= kMaxRelSigma;
}

// A joint fit trusts the frame times. When the frames also show enough bars to be fitted
// one by one, that fit (which ignores the times) checks them: if the joint fit found
// nothing, or the frame-by-frame fit explains the data clearly better and disagrees, the
// frames are not consecutive at that rate (dropped frames, a wrong --fps): it is used.
void cross_check(const Stack& st, const Plan& plan, Outcome& out, std::vector<std::string>& warnings) {
  if (plan.model == LedModel::PerFrame) return;
  Plan alone = plan;
  alone.model = LedModel::PerFrame;
  std::fill(alone.omega.begin(), alone.omega.end(), 0.0);
  Outcome other;
  try {
    other = fit_plan(st, alone, true);
  } catch (const LedCalibrationError&) {
    return;
  }
  if (!acceptable(other.fit)) return;
  const double gap = std::abs(std::abs(other.fit.nu) - std::abs(out.fit.nu));
  const double sigma = std::hypot(other.fit.nu_sigma, out.fit.nu_sigma);
  const bool disagree = gap > 5 * sigma && other.fit.s2() < 0.8 * out.fit.s2();
  if (acceptable(out.fit) && !disagree) return;
  warnings.push_back("the frames do not follow the given frame times (dropped frames or a wrong frame rate?): "
                     "the joint fit gave nu = " + fmt(std::abs(out.fit.nu), 6) +
                     " cycles/row; the frame-by-frame fit was used");
  out = fit_plan(st, alone);
}

// The bars must stand out of the noise (F test of the sinusoid against offsets alone),
// and the data must pin nu down.
void require_signal(const Fit& f, const LedCalibrationOptions& o, const Plan& plan) {
  if (!(f.f_statistic() >= kMinF))
    throw LedCalibrationError("no LED modulation found: the best sinusoid (nu = " + fmt(std::abs(f.nu)) +
                              " cycles/row) does not stand out of the noise (F = " + fmt(f.f_statistic(), 3) + ")");
  const double rel = f.nu_sigma / std::abs(f.nu);
  if (rel <= kMaxRelSigma) return;
  std::string why;
  if (plan.period) {
    const double ratio = o.led_hz * *plan.period;
    for (int q = 1; q <= 8 && why.empty(); ++q)
      if (std::abs(ratio * q - std::round(ratio * q)) < 1e-3 * q)
        why = "; the LED frequency is " + fmt(std::round(ratio * q), 3) + "/" + std::to_string(q) +
              " of the frame rate, so every row sees the LED at only " + std::to_string(q) +
              " phases and a non-sinusoidal LED's harmonics alias onto its fundamental: use an LED frequency "
              "that is not a simple fraction of the frame rate";
  }
  if (why.empty()) why = "; use more frames, more bars per frame (a higher LED frequency) or more contrast";
  throw LedCalibrationError("LED bars found (nu = " + fmt(std::abs(f.nu)) + " cycles/row), but the capture does "
                            "not determine the line delay: relative uncertainty " + fmt(100 * rel, 3) + "%" + why);
}

// Alias candidates: on a row grid nu and k +- nu are the same bars. They matter when the
// frame period allows a readout slow enough for them.
void alias_warnings(const LedCalibrationOptions& o, const Plan& plan, double nu, int h,
                    std::vector<std::string>& w) {
  const double a = std::abs(nu);
  if (!plan.period) {
    if (a > 0.25)
      w.push_back("aliasing ambiguity: nu = " + fmt(a) + " is close to the row Nyquist frequency 0.5; if the LED "
                  "is faster than half the row rate, the line delay may be (1 - nu)/f = " + fmt((1 - a) / o.led_hz) +
                  " s (give --fps to rule it out)");
    return;
  }
  const double limit = kReadoutSlack * o.led_hz * *plan.period / h;
  std::string alts;
  for (int k = 1; k <= 4; ++k)
    for (double c : {k - a, k + a})
      if (c <= limit) alts += (alts.empty() ? "" : ", ") + fmt(c / o.led_hz) + " s";
  if (!alts.empty())
    w.push_back("aliasing ambiguity: the LED is fast enough for aliased bars (k +- nu cycles/row) to fit the frame "
                "period; other possible line delays: " + alts);
}

void quality_warnings(const Fit& f, const Outcome& out, std::vector<std::string>& w) {
  if (out.seed.peak.harmonic > 1)
    w.push_back("the strongest spectral peak is harmonic " + std::to_string(out.seed.peak.harmonic) +
                " of the LED (square-wave drive); its fundamental was used");
  if (f.depth < 0.02)
    w.push_back("low contrast: the bars modulate the image by only " + fmt(100 * f.depth, 2) + "%");
  const double snr = f.amplitude / std::sqrt(f.s2());
  if (snr < 1) w.push_back("low signal-to-noise ratio: bar amplitude / residual rms = " + fmt(snr, 2));
}

void timing_warnings(const LedCalibrationResult& r, const Plan& plan, const LedCalibrationOptions& o,
                     std::vector<std::string>& w) {
  if (r.model == LedModel::JointSmooth) {
    const double u = o.led_hz * plan.period.value_or(0);
    w.push_back("the LED frequency is close to a multiple of the frame rate (the bars move " +
                fmt(u - std::round(u), 2) + " cycles per frame): frozen bars, smooth illumination model used");
  }
  if (r.blanking_s && *r.blanking_s < -o.zero_delay_sigmas * *r.blanking_sigma_s)
    w.push_back("the readout (" + fmt(r.frame_readout_s * 1e3) + " ms) is longer than the frame period (" +
                fmt(*r.frame_period_s * 1e3) + " ms): check the LED frequency and the frame rate");
}

LedCalibrationResult assemble(const Outcome& out, const Plan& plan, const LedCalibrationOptions& o, int h) {
  const Fit& f = out.fit;
  LedCalibrationResult r;
  r.model = f.kind;
  r.readout = out.readout;
  r.nu_cycles_per_row = out.readout ? f.nu : std::abs(f.nu);
  r.nu_sigma = f.nu_sigma;
  r.spectral_peak_cycles_per_row = std::abs(out.seed.peak.nu);
  r.line_delay_s = std::abs(f.nu) / o.led_hz;
  // nu's own uncertainty, the model floor and the LED frequency's accuracy, all relative.
  const double rel = std::sqrt(std::pow(f.nu_sigma / f.nu, 2) + kModelFloor * kModelFloor +
                               o.led_hz_accuracy * o.led_hz_accuracy);
  r.line_delay_sigma_s = rel * r.line_delay_s;
  r.row_rate_hz = 1 / r.line_delay_s;
  r.row_rate_sigma_hz = r.line_delay_sigma_s / (r.line_delay_s * r.line_delay_s);
  r.frame_readout_s = h * r.line_delay_s;
  r.frame_readout_sigma_s = h * r.line_delay_sigma_s;
  r.rows = h;
  r.cycles_per_frame = std::abs(f.nu) * h;
  r.modulation_depth = f.depth;
  r.snr = f.amplitude / std::sqrt(f.s2());
  if (plan.period) {  // the paper's test: r = rows * fps means d = 0
    r.frame_period_s = *plan.period;
    r.blanking_s = *plan.period - r.frame_readout_s;
    r.blanking_sigma_s = r.frame_readout_sigma_s;
    r.zero_delay = std::abs(*r.blanking_s) <= o.zero_delay_sigmas * *r.blanking_sigma_s;
  }
  return r;
}

}  // namespace

std::string_view to_string(LedModel m) {
  switch (m) {
    case LedModel::JointPerRow: return "joint (known frame times, per-row offset and gain)";
    case LedModel::JointSmooth: return "joint (known frame times, smooth illumination)";
    case LedModel::PerFrame: return "frame by frame (own phase per frame, smooth illumination)";
  }
  return "";
}

LedCalibrator::LedCalibrator(const LedCalibrationOptions& opt) : opt_(opt) {
  if (!(opt.led_hz > 0) || !std::isfinite(opt.led_hz))
    throw std::invalid_argument("the LED frequency must be a positive number of hertz");
  if (opt.fps && (!(*opt.fps > 0) || !std::isfinite(*opt.fps)))
    throw std::invalid_argument("the frame rate must be a positive number of frames per second");
  if (opt.max_frames < 1) throw std::invalid_argument("max_frames must be at least 1");
  if (!(opt.led_hz_accuracy >= 0)) throw std::invalid_argument("the LED frequency accuracy must be >= 0");
}

void LedCalibrator::add_frame(const ImageView& f, std::optional<double> timestamp_s) {
  if (width_ == 0) {
    if (f.height < 16 || f.width < 2)
      throw std::invalid_argument("frame is " + std::to_string(f.width) + " x " + std::to_string(f.height) +
                                  ": at least 2 columns and 16 rows are needed");
    width_ = f.width;
    height_ = f.height;
    format_ = f.format;
    // Even block widths keep both columns of a Bayer pair in the same block.
    block_width_ = 2 * std::max(1, (f.width + 2 * kMaxBlocks - 1) / (2 * kMaxBlocks));
    blocks_ = std::max(1, f.width / block_width_);
    block_width_ = std::min(block_width_, f.width);
  } else if (f.width != width_ || f.height != height_ || f.format != format_) {
    throw std::invalid_argument("frame is " + std::to_string(f.width) + " x " + std::to_string(f.height) +
                                (f.format != format_ ? " with another pixel format" : "") + ", the first was " +
                                std::to_string(width_) + " x " + std::to_string(height_));
  }
  if (frames() >= opt_.max_frames) {
    ++ignored_;
    return;
  }
  std::vector<double> prof(static_cast<size_t>(blocks_) * height_, 0.0);
  for (int y = 0; y < height_; ++y) {
    const std::uint8_t* row = f.row(y);
    for (int b = 0; b < blocks_; ++b) {
      double sum = 0;
      for (int x = b * block_width_; x < (b + 1) * block_width_; ++x) sum += luminance(f, row, x);
      prof[static_cast<size_t>(b) * height_ + y] = sum;
    }
  }
  profiles_.push_back(std::move(prof));
  times_.push_back(timestamp_s);
}

LedCalibrationResult LedCalibrator::estimate() const {
  if (profiles_.empty()) throw LedCalibrationError("no frames to calibrate from");
  const Plan plan = make_plan(opt_, times_, height_);
  Stack st = make_stack(profiles_, std::vector<double>(blocks_, 1.0), height_);
  require_variation(st);
  // Pass 1 finds the bars with every column; pass 2 weights the columns by their bars.
  const std::vector<double> w = block_weights(profiles_, blocks_, height_, plan, find_seed(st, plan).nu);
  st = make_stack(profiles_, w, height_);
  Outcome out = fit_plan(st, plan);
  std::vector<std::string> warnings;
  cross_check(st, plan, out, warnings);
  require_signal(out.fit, opt_, plan);
  LedCalibrationResult r = assemble(out, plan, opt_, height_);
  r.frames_used = frames();
  r.width = width_;
  r.columns_used = block_width_ * static_cast<int>(std::count_if(w.begin(), w.end(), [](double x) { return x > 0; }));
  if (ignored_ > 0)
    warnings.push_back(std::to_string(ignored_) + " frames beyond the first " + std::to_string(opt_.max_frames) +
                       " were ignored");
  alias_warnings(opt_, plan, out.fit.nu, height_, warnings);
  quality_warnings(out.fit, out, warnings);
  timing_warnings(r, plan, opt_, warnings);
  r.warnings = std::move(warnings);
  return r;
}

LedCalibrationResult calibrate_led(const std::vector<ImageView>& frames, const LedCalibrationOptions& opt) {
  LedCalibrator cal(opt);
  for (const ImageView& f : frames) cal.add_frame(f);
  return cal.estimate();
}

}  // namespace rsd::dsp
