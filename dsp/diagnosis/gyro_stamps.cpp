#include "dsp/diagnosis/gyro_stamps.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace rsd::dsp {

namespace {

// The rate curve at time s from the four samples around sample k (two on either side, at
// their current times), k itself left out: the cubic through them, its slope there, and
// g = 1 + sum of the squared weights (how much of the neighbours' own noise the prediction
// carries, next to the sample's) and h = the sum of the slope's squared weights (its noise).
struct CurveAt {
  Eigen::Vector3d rate, slope;
  double g, h = 0;
};

CurveAt predict(const std::vector<double>& t, const std::vector<GyroSample>& gyro, size_t k, double s) {
  const std::array<size_t, 4> j{k - 2, k - 1, k + 1, k + 2};
  CurveAt p{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 1.0};
  for (size_t a = 0; a < 4; ++a) {
    // Lagrange's basis polynomial of node a and its derivative at s.
    double num = 1, den = 1, dnum = 0;
    for (size_t b = 0; b < 4; ++b) {
      if (b == a) continue;
      den *= t[j[a]] - t[j[b]];
      double others = 1;  // product over the nodes other than a and b
      for (size_t c = 0; c < 4; ++c)
        if (c != a && c != b) others *= s - t[j[c]];
      dnum += others;
      num *= s - t[j[b]];
    }
    const double L = num / den, dL = dnum / den;
    p.rate += L * gyro[j[a]].w;
    p.slope += dL * gyro[j[a]].w;
    p.g += L * L;
    p.h += dL * dL;
  }
  return p;
}

// Whether sample k has two neighbours on either side with no gap among them.
bool usable(const std::vector<GyroSample>& g, size_t k, double max_interval) {
  if (k < 2 || k + 2 >= g.size()) return false;
  for (size_t i = k - 1; i <= k + 2; ++i)
    if (g[i].t - g[i - 1].t > max_interval) return false;
  return true;
}

// What sample k's rate says of its stamp at the current times t: the prediction at its stamp
// and the sample's departure from it, split along the curve's slope and across it.
struct Departure {
  CurveAt p;
  double along, across2, slope2;  // u.d, |d|^2 - (u.d)^2, |w'|^2; u the slope's direction
};

Departure departure(const std::vector<double>& t, const std::vector<GyroSample>& g, size_t k) {
  const CurveAt p = predict(t, g, k, g[k].t);
  const Eigen::Vector3d d = g[k].w - p.rate;
  const double slope2 = p.slope.squaredNorm();
  const double along = slope2 > 0 ? p.slope.dot(d) / std::sqrt(slope2) : 0.0;
  return {p, along, std::max(d.squaredNorm() - along * along, 0.0), slope2};
}

struct Spread {
  double noise2 = 0;   // per-axis variance of a sample's rate about the curve
  double jitter2 = 0;  // variance of the stamps about the sampling times
};

// Across the slope a departure is noise (the sample's and, weighted, its neighbours'); along it
// the stamps' errors add |w'|^2 var(stamp) for the sample and each neighbour alike. Departures
// beyond 5 times the median are outliers of the rates (a saturated or glitched sample) and left
// out of both sums. The jitter is measured only where the slope stands clear of its own noise
// (|w'|^2 over 9 times what the neighbours' noise gives it): where the noise makes the slope,
// the slope's direction follows the neighbours' noise, which the departure carries too, and a
// noisy gyro on a still camera would show a spread of milliseconds along it.
Spread measure_spread(const std::vector<Departure>& d) {
  std::vector<double> size;
  for (const Departure& x : d)
    if (x.p.g > 0) size.push_back(x.along * x.along + x.across2);
  if (size.size() < 20) return {};
  std::nth_element(size.begin(), size.begin() + size.size() / 2, size.end());
  const double limit = 25 * size[size.size() / 2];
  auto outlier = [&](const Departure& x) { return x.p.g <= 0 || x.along * x.along + x.across2 > limit; };
  double across = 0, g = 0;
  for (const Departure& x : d)
    if (!outlier(x)) across += x.across2 / 2, g += x.p.g;
  Spread s;
  if (g <= 0) return s;
  s.noise2 = across / g;
  double along = 0, across_clear = 0, slope_g = 0;
  for (const Departure& x : d)
    if (!outlier(x) && x.slope2 > 9 * 3 * s.noise2 * x.p.h)
      along += x.along * x.along, across_clear += x.across2 / 2, slope_g += x.slope2 * x.p.g;
  if (slope_g > 0) s.jitter2 = std::max(0.0, (along - across_clear) / slope_g);
  return s;
}

// Whether the stamps' errors move the rates by enough to be estimated: |w'| sigma_t at least
// a third of the rates' noise, over the recording (a gyro sampled on time measures a spread of
// a few hundredths of a millisecond from the curve's own error, which moves no rate by much).
bool worth_moving(const std::vector<Departure>& d, const Spread& s) {
  if (s.jitter2 <= 0 || s.noise2 <= 0) return false;
  double slope2 = 0, g = 0;
  for (const Departure& x : d) slope2 += x.slope2 * x.p.g, g += x.p.g;
  return slope2 * s.jitter2 >= 0.1 * g * s.noise2;
}

// The rates' noise is seldom alike on the three axes (a drone's propellers shake it about one
// axis most: the Karma clip's gyro moves 110, 45 and 13 mrad/s RMS from sample to sample), and
// where the slope lies along the noisiest axis the departures along it would pass for stamp
// errors. On each gyro axis a departure's square is var_a + var_t w'_a^2 (over g), so a least-
// squares fit of the squares on (1, w'_a^2) over the recording separates each axis's noise from
// the stamps, and dividing each axis by its noise's sigma makes the noise alike on all three,
// where the split along and across the slope holds. (A full covariance from the departures'
// products was tried: its smallest eigenvalue came out at a sixth of the truth on a phone's
// isotropic noise, and whitening by it lost most of what the stamps' estimate gains.)
Eigen::Vector3d noise_whitening(const std::vector<GyroSample>& g, const std::vector<Departure>& d) {
  using Vector4d = Eigen::Vector4d;
  auto scaled = [&](size_t k) { return Eigen::Vector3d((g[k].w - d[k].p.rate) / std::sqrt(d[k].p.g)); };
  std::vector<double> size;  // departures beyond 5 times the median are glitches, left out
  for (size_t k = 0; k < d.size(); ++k)
    if (d[k].p.g > 0) size.push_back(scaled(k).squaredNorm());
  if (size.size() < 20) return Eigen::Vector3d::Ones();
  std::nth_element(size.begin(), size.begin() + size.size() / 2, size.end());
  const double limit = 25 * size[size.size() / 2];
  // Unknowns (var_x, var_y, var_z, var_t); one equation per axis and sample.
  Eigen::Matrix4d AtA = Eigen::Matrix4d::Zero();
  Vector4d Atb = Vector4d::Zero();
  for (size_t k = 0; k < d.size(); ++k) {
    if (d[k].p.g <= 0) continue;
    const Eigen::Vector3d r = scaled(k), s = d[k].p.slope;
    if (r.squaredNorm() > limit) continue;
    for (int a = 0; a < 3; ++a) {
      Vector4d row = Vector4d::Zero();
      row[a] = 1, row[3] = s[a] * s[a];
      AtA += row * row.transpose(), Atb += row * (r[a] * r[a]);
    }
  }
  const Vector4d x = AtA.ldlt().solve(Atb);
  const double top = x.head<3>().maxCoeff();
  if (!x.allFinite() || !(top > 0)) return Eigen::Vector3d::Ones();
  return x.head<3>().cwiseMax(1e-6 * top).cwiseSqrt().cwiseInverse();
}

}  // namespace

GyroStamps estimate_gyro_stamps(const std::vector<GyroSample>& stamped, double max_interval) {
  GyroStamps out{stamped, {}};
  const size_t n = stamped.size();
  if (n < 5) return out;
  std::vector<double> t(n);
  for (size_t k = 0; k < n; ++k) t[k] = stamped[k].t;
  auto departures = [&](const std::vector<GyroSample>& g) {
    std::vector<Departure> d(n, Departure{{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0}, 0, 0, 0});
    for (size_t k = 0; k < n; ++k)
      if (usable(g, k, max_interval)) d[k] = departure(t, g, k);
    return d;
  };
  // Everything from here on in the whitened rates, where the noise is alike on every axis.
  std::vector<GyroSample> gyro = stamped;
  const Eigen::Vector3d W = noise_whitening(stamped, departures(stamped));
  for (GyroSample& x : gyro) x.w = W.cwiseProduct(x.w);
  const std::vector<Departure> d = departures(gyro);
  const Spread spread = measure_spread(d);
  out.spread.jitter_s = std::sqrt(spread.jitter2);
  if (!worth_moving(d, spread)) return out;
  // The times that best explain the rates and the stamps together: the sum over samples of
  // |w_k - curve through the neighbours at t_k|^2 / (g_k var_w) (capped at 25: a glitched
  // rate does not drag its neighbours), plus (t_k - stamp_k)^2 / var_t, minimised one time
  // after another (coordinate descent: each step lowers the sum, so the sweeps cannot run away
  // as independent estimates from jittered neighbours do; the sum's change is a parabola in
  // t_k, sampled a stamp's sigma either side). A time stays within 0.4 of the intervals beside
  // its stamp, so the order holds.
  const double var_w = spread.noise2, var_t = spread.jitter2;
  auto cost_near = [&](size_t k) {  // the terms that t[k] enters: its own rate and its neighbours'
    double c = (t[k] - gyro[k].t) * (t[k] - gyro[k].t) / var_t;
    for (size_t j = k >= 2 ? k - 2 : 0; j <= std::min(k + 2, n - 1); ++j)
      if (usable(gyro, j, max_interval)) {
        const CurveAt p = predict(t, gyro, j, t[j]);
        c += std::min((gyro[j].w - p.rate).squaredNorm() / (p.g * var_w), 25.0);
      }
    return c;
  };
  const double step = std::sqrt(var_t);
  // Eight sweeps: on a walking phone's irregular gyro with 0.5 ms of jitter the stamps' error
  // goes 0.50 -> 0.45, 0.43, 0.39 ms after one, two, four sweeps, 0.36 after eight, 0.355
  // after thirty-two (tests/dsp/diagnosis/test_gyro_stamps.cpp).
  for (int sweep = 0; sweep < 8; ++sweep)
    for (size_t k = 0; k < n; ++k) {
      if (!usable(gyro, k, max_interval)) continue;
      const double t0 = t[k], c0 = cost_near(k);
      t[k] = t0 - step;
      const double before = cost_near(k);
      t[k] = t0 + step;
      const double after = cost_near(k);
      const double curvature = after + before - 2 * c0;
      const double best = curvature > 0 ? t0 - 0.5 * step * (after - before) / curvature : (after < before ? t0 + step : t0 - step);
      const double lo = gyro[k].t - 0.4 * (gyro[k].t - gyro[k - 1].t), hi = gyro[k].t + 0.4 * (gyro[k + 1].t - gyro[k].t);
      t[k] = std::clamp(best, lo, hi);
      if (cost_near(k) > c0) t[k] = t0;
    }
  double moved2 = 0;
  for (size_t k = 0; k < n; ++k) {
    moved2 += (t[k] - gyro[k].t) * (t[k] - gyro[k].t);
    out.gyro[k].t = t[k];
  }
  out.spread.moved_rms_s = std::sqrt(moved2 / static_cast<double>(n));
  return out;
}

}  // namespace rsd::dsp
