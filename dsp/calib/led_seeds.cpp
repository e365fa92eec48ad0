// Starting values of the fit: per-row and spectral seeds, a grid over the spatial frequency, column
// weighting by bar amplitude.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

#include "dsp/calib/led_internal.hpp"

namespace rsd::dsp::led {

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

}  // namespace rsd::dsp::led
