// Spectra of the spatio-temporal image (FFTW), the fundamental spatial frequency of the LED bars,
// per-row demodulation.
#include <fftw3.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>

#include "dsp/calib/led_internal.hpp"
#include "dsp/core/statistics.hpp"

namespace rsd::dsp::led {

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

}  // namespace rsd::dsp::led
