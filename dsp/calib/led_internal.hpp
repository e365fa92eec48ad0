// Internals of the LED-flicker calibration shared by its files (dsp/calib/led_*.cpp): tuning
// constants, the spatio-temporal image, spectra, the sinusoid model, its fit and seeds. Not an
// API: led_calibration.hpp is.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <complex>
#include <optional>
#include <string>
#include <vector>

#include "dsp/calib/led_calibration.hpp"

namespace rsd::dsp::led {

constexpr double kPi = 3.14159265358979323846;

using cd = std::complex<double>;

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

// The paper's I(y, t): one row per frame, one column per (averaged) image row.
struct Stack {
  Eigen::MatrixXd s;        // K x n
  std::vector<double> yc;   // row y relative to the frame centre
};

struct Plan {
  LedModel model = LedModel::PerFrame;
  std::vector<double> omega;     // LED phase at each frame start, 2 pi f t_k (0 when unknown)
  double nu_hi = kMaxNu;         // largest plausible |nu|
  std::optional<double> period;  // frame period, from the option or the timestamps
};

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

// Uniform cubic B-splines over the rows: 4 non-zero functions at each row.
struct Basis {
  int size = 1;             // functions per nuisance (a or b)
  std::vector<int> first;   // per row: index of the first non-zero function
  std::vector<std::array<double, 4>> w;
  int count(int) const { return size == 1 ? 1 : 4; }
};

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

// Design row of a sample for the linear parameters, given nu and phi: the a-part, then
// either the b-part (envelope times the cosine) or, relaxed, a constant envelope's
// cosine and sine (any phase).
enum class Linear { OffsetOnly, Envelope, Relaxed };

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

struct Seed {
  double nu = 0, phi = 0;
  Peak peak;
};

int next_pow2(int n);

std::string fmt(double x, int precision = 4);

// Sums the column blocks with weights into I(k, y). A 2x2 Bayer mosaic makes alternate
// rows differ in gain (a strong 0.5 cycles/row line): the rows of each parity are scaled to
// the same mean. (Averaging row pairs would also do, but would correlate the noise of
// neighbouring rows, which the uncertainty would then have to model.)
Stack make_stack(const std::vector<std::vector<double>>& profiles, const std::vector<double>& w, int h);

// Each frame relative to its smooth trend: removes the illumination's slow variation
// (and, dividing, its gain) so the bars dominate the spectrum.
Eigen::MatrixXd detrended(const Eigen::MatrixXd& s, bool relative);

// Smallest eigenvalue of the mean of [1 cos w sin w]^T [1 cos w sin w]: how well the frames'
// LED phases separate a row's offset from its modulation (0.5 for evenly spread phases,
// 0 when the bars are frozen, f a multiple of the frame rate).
double phase_diversity(const std::vector<double>& omega);

// The paper's marginal spectrum: |2-D DFT of x(k, y)|^2 summed over temporal frequency,
// for spatial frequencies i / nfft, i = 0..nfft/2 (Hann window along y, zero padding).
std::vector<double> marginal_spectrum(const Eigen::MatrixXd& x, int nfft);

// |DFT|^2 of a complex row signal z_y at signed frequencies (bin i is i / nfft, wrapped).
std::vector<double> complex_spectrum(const std::vector<cd>& z, int nfft);

// The LED's fundamental: the strongest peak in [nu_lo, nu_hi] (both signs when two-sided),
// unless a peak at 1/m of its frequency is at least kHarmonicRatio as strong in amplitude,
// in which case the strongest is a harmonic of a square-wave drive (the paper: "high
// frequency components are ignored because the image is not a sine wave").
Peak pick_fundamental(const Spectrum& s, double nu_lo, double nu_hi, int rows);

// With known frame phases omega_k, each row's offset and complex amplitude
// z_y = b_y exp(i rho_y) follow from a linear fit of I(k, y) = a_y + Re(z_y exp(i omega_k)).
// rho_y = 2 pi nu y + phi: the 2-D Fourier transform at the LED's temporal frequency.
std::vector<cd> demodulate_rows(const Eigen::MatrixXd& s, const std::vector<double>& omega);

Basis constant_basis(int n);

Basis spline_basis(int n, int segments);

// Illumination must vary slower than the bars: about three bar periods per segment.
int segments_for(double cycles_per_frame);

Model build_model(const Stack& st, const Plan& plan, const Basis& basis);

// Solves the linear parameters of every nuisance block (nu and the phases fixed) and
// returns the residual sum of squares. Relaxed fits also set the phase of each block's
// groups (the smooth models have one phase per nuisance block).
double solve_linear(Model& m, Linear kind);

// Harmonics a model may include: below kMaxNu cycles/row (higher ones fold back near the
// fundamental and the Bayer line on the row grid), at most kMaxHarmonic. With per-row offsets, a harmonic
// whose phase does not move between frames is absorbed by the offsets: left out.
std::vector<int> candidate_orders(const Plan& plan, double nu);

// The harmonics the data can tell apart from nu, phi and each other, in order of
// increasing h. With known frame times, harmonics alias onto the fundamental or onto each
// other in time (f a simple fraction of the frame rate). Each must add at least
// kMinNewInfo of new information, and all together may not take more than half of nu's:
// a series of aliased harmonics can otherwise mimic the phase ramp that measures nu (at
// f = fps/3 an unknown duty cycle trades off exactly against the line delay).
std::vector<int> identifiable_orders(const Model& m, const std::vector<int>& cands);

void set_orders(Model& m, std::vector<int> orders);

// The harmonics present in the data, judged before the nonlinear fit by one linearised
// (Gauss-Newton) step from shape = 0: fitting absent ones only fits noise (and costs time).
std::vector<int> present_orders(const Model& m);

// Joint least-squares fit of all samples from the model's current parameters (Ceres,
// Levenberg-Marquardt); nu's uncertainty from the covariance scaled by the residual variance.
Fit fit_model(Model& m);

// `m` with only the harmonics in `orders` (a subset), keeping their current coefficients.
Model with_orders(const Model& m, const std::vector<int>& orders);

// The fit, with the truncation of the waveform as a systematic uncertainty: the same fit
// with half the harmonics differs from it by about what the harmonics left out may still
// do (their effect shrinks with their order), so that difference is added to nu's
// statistical sigma. A fit its harmonics make singular is retried with half of them;
// refits start from the previous solution.
Fit fit_checked(const Model& start);

// Joint per-row: demodulate every row at the LED's temporal frequency, then find the
// spatial frequency of the row phasors (any sign: the sign is the readout direction).
Seed seed_per_row(const Stack& st, const Plan& plan);

// Smooth models: the paper's marginalised 2-D spectrum of the detrended frames.
Seed seed_spectral(const Stack& st, const Plan& plan);

// Relaxed grid search around the seed (one raw bin either side), then the exact linear
// parameters at the best nu: the starting point of the nonlinear fit.
double grid_start(Model& m, double nu0, int rows);

// Luminance of pixel x of a row: Rec. 601 weights for RGB (the LED's colour does not
// matter: every channel carries the same temporal modulation).
double luminance(const ImageView& f, const std::uint8_t* row, int x);

// Weight of each column block: its bar amplitude, or 0 below kBlockKeep of the best.
std::vector<double> block_weights(const std::vector<std::vector<double>>& profiles, int blocks, int h,
                                  const Plan& plan, double nu);

}  // namespace rsd::dsp::led
