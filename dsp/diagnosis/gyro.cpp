#include "dsp/diagnosis/gyro.hpp"

#include <algorithm>
#include <stdexcept>

#include "dsp/geometry/camera_motion.hpp"
#include "dsp/diagnosis/pose_track.hpp"

namespace rsd::dsp {

std::vector<GyroSample> clean_gyro(std::vector<GyroSample> g) {
  std::stable_sort(g.begin(), g.end(), [](const GyroSample& a, const GyroSample& b) { return a.t < b.t; });
  std::vector<GyroSample> out;
  for (const GyroSample& s : g)
    if (out.empty() || s.t > out.back().t) out.push_back(s);
  return out;
}

namespace {

// Integral of the Hermite rate over the first share tau of an interval of length h, and the
// rate at its end. Hermite basis integrated: H00 = tau^4/2 - tau^3 + tau, H10 = tau^4/4 -
// 2 tau^3/3 + tau^2/2, H01 = -tau^4/2 + tau^3, H11 = tau^4/4 - tau^3/3.
struct Partial {
  Eigen::Vector3d integral, rate;
};
Partial hermite(const Eigen::Vector3d& w0, const Eigen::Vector3d& s0, const Eigen::Vector3d& w1,
                const Eigen::Vector3d& s1, double h, double tau) {
  const double t2 = tau * tau, t3 = t2 * tau, t4 = t3 * tau;
  const double H00 = 0.5 * t4 - t3 + tau, H10 = 0.25 * t4 - 2.0 / 3.0 * t3 + 0.5 * t2;
  const double H01 = -0.5 * t4 + t3, H11 = 0.25 * t4 - t3 / 3.0;
  const double h00 = 2 * t3 - 3 * t2 + 1, h10 = t3 - 2 * t2 + tau, h01 = -2 * t3 + 3 * t2, h11 = t3 - t2;
  return {h * (H00 * w0 + H10 * h * s0 + H01 * w1 + H11 * h * s1), h00 * w0 + h10 * h * s0 + h01 * w1 + h11 * h * s1};
}

// d/dt of the Hermite rate at share tau of an interval of length h.
Eigen::Vector3d hermite_slope(const Eigen::Vector3d& w0, const Eigen::Vector3d& s0, const Eigen::Vector3d& w1,
                              const Eigen::Vector3d& s1, double h, double tau) {
  const double t2 = tau * tau;
  const double d00 = 6 * t2 - 6 * tau, d10 = 3 * t2 - 4 * tau + 1, d01 = -d00, d11 = 3 * t2 - 2 * tau;
  return (d00 * w0 + d01 * w1) / h + d10 * s0 + d11 * s1;
}

// Rotation over the first share tau of interval k: the Hermite integral plus the second Magnus
// term for dR/dt = R [w]x, (dt^2 / 12) w(0) x w(dt) (as integrate_gyro).
Eigen::Vector3d step(const Eigen::Vector3d& w0, const Eigen::Vector3d& s0, const Eigen::Vector3d& w1,
                     const Eigen::Vector3d& s1, double h, double tau) {
  const Partial p = hermite(w0, s0, w1, s1, h, tau);
  const double dt = tau * h;
  return p.integral + dt * dt / 12.0 * w0.cross(p.rate);
}

// The shortest interval a slope divides by: half the median interval. A shorter one is the
// stamps' jitter more than the sampling: a regular 200 Hz gyro whose stamps jitter by 2 ms
// has neighbours stamped almost together, or swapped, and the parabola's slope, which weighs
// the shorter interval's secant most, divided by almost nothing (the rotation over a frame
// pair erred by 27% RMS; floored, by 1.3%). Irregular sampling keeps its own intervals: at
// 20-200 Hz the shortest, 5 ms, is over half the median, 9 ms.
double shortest_slope_interval(const std::vector<GyroSample>& g) {
  return g.size() < 2 ? 0.0 : 0.5 * interval_percentile(g, 50);
}

}  // namespace

double interval_percentile(const std::vector<GyroSample>& g, int percent) {
  std::vector<double> dt(g.size() - 1);
  for (size_t k = 1; k < g.size(); ++k) dt[k - 1] = g[k].t - g[k - 1].t;
  std::nth_element(dt.begin(), dt.begin() + dt.size() * percent / 100, dt.end());
  return dt[dt.size() * percent / 100];
}

double gyro_gap_limit(const std::vector<GyroSample>& g) {
  if (g.size() < 2) return std::numeric_limits<double>::infinity();
  return std::max(1.5 * interval_percentile(g, 95), 0.02);
}

GyroTrack::GyroTrack(const std::vector<GyroSample>& g, const Eigen::Vector3d& bias, const Eigen::Matrix3d& imu_to_camera,
                     double max_interval, const Eigen::Vector3d& scale)
    : bias_(bias), scale_(scale), imu_to_camera_t_(imu_to_camera.transpose()), imu_to_camera_(imu_to_camera) {
  if (g.empty()) throw std::invalid_argument("gyro track: no gyro samples");
  const size_t n = g.size();
  knots_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    knots_[i].t = g[i].t;
    knots_[i].w = scale.cwiseProduct(g[i].w - bias);
  }
  // Slopes: the derivative of the parabola through each sample and its neighbours, second
  // order on an irregular grid (the plain central difference is only first order there):
  // f' = (h2 d1 + h1 d2) / (h1 + h2), d1 and d2 the secants over h1 and h2, the intervals
  // before and after. One-sided at the ends and next to a gap; zero between two gaps.
  const double shortest = shortest_slope_interval(g);
  auto one_sided = [&](size_t a, size_t b) { return Eigen::Vector3d((knots_[b].w - knots_[a].w) / (knots_[b].t - knots_[a].t)); };
  for (size_t i = 0; i < n; ++i) {
    Knot& k = knots_[i];
    const bool before = i > 0 && k.t - knots_[i - 1].t <= max_interval;
    const bool after = i + 1 < n && knots_[i + 1].t - k.t <= max_interval;
    if (before && after) {
      const Knot &a = knots_[i - 1], &b = knots_[i + 1];
      const double h1 = std::max(k.t - a.t, shortest), h2 = std::max(b.t - k.t, shortest);
      k.s = (h2 * (k.w - a.w) / h1 + h1 * (b.w - k.w) / h2) / (h1 + h2);
    } else if (before || after) {
      k.s = before ? one_sided(i - 1, i) : one_sided(i, i + 1);
    } else {
      k.s.setZero();
    }
  }
  knots_[0].R.setIdentity();
  for (size_t i = 1; i < n; ++i) {
    const Knot &a = knots_[i - 1];
    const double h = knots_[i].t - a.t;
    knots_[i].R = a.R * exp_so3(step(a.w, a.s, knots_[i].w, knots_[i].s, h, 1.0));
  }
}

const std::vector<GyroTrack::ByGyro>& GyroTrack::knots_by_gyro() const {
  std::call_once(by_gyro_once_, [this] {
    by_gyro_.assign(knots_.size(), ByGyro::Zero());
    for (size_t i = 1; i < knots_.size(); ++i) {
      const Knot &a = knots_[i - 1], &b = knots_[i];
      const Eigen::Vector3d phi = step(a.w, a.s, b.w, b.s, b.t - a.t, 1.0);
      // R_a Exp(e) Exp(phi) Exp(J_r(phi) d phi) = R_a Exp(phi) Exp(Exp(phi)^T e + J_r(phi) d phi).
      by_gyro_[i] = exp_so3_fast(-phi) * by_gyro_[i - 1] + so3_right_jacobian(phi) * step_by_gyro(a, b, 1.0);
    }
  });
  return by_gyro_;
}

// The step is linear in the knots' rates and slopes but for the Magnus term's product: with
// w = diag(S) (w_m - b), a bias moves every rate by -S_k e_k (the slopes, differences of rates,
// not at all) and a scale S_k each rate's and slope's k-th component by w_k / S_k, s_k / S_k
// (nothing when S_k is zero: the rate is then zero whatever the measurement).
GyroTrack::ByGyro GyroTrack::step_by_gyro(const Knot& a, const Knot& b, double tau) const {
  const double h = b.t - a.t, dt = tau * h;
  const Eigen::Vector3d w = hermite(a.w, a.s, b.w, b.s, h, tau).rate;
  ByGyro D;
  for (int j = 0; j < 6; ++j) {
    const int k = j % 3;
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(k);
    Eigen::Vector3d dw0, ds0, dw1, ds1;
    if (j < 3) {
      dw0 = dw1 = -scale_[k] * e, ds0 = ds1 = Eigen::Vector3d::Zero();
    } else {
      const double per = scale_[k] != 0 ? 1.0 / scale_[k] : 0.0;
      dw0 = a.w[k] * per * e, ds0 = a.s[k] * per * e, dw1 = b.w[k] * per * e, ds1 = b.s[k] * per * e;
    }
    const Partial dp = hermite(dw0, ds0, dw1, ds1, h, tau);
    D.col(j) = dp.integral + dt * dt / 12.0 * (dw0.cross(w) + a.w.cross(dp.rate));
  }
  return D;
}

const GyroTrack::Knot& GyroTrack::interval(double t, Eigen::Vector3d& phi, size_t& hint) const {
  phi.setZero();
  if (t < knots_.front().t) return knots_.front();
  if (t >= knots_.back().t) return knots_.back();
  locate(t, hint);
  const Knot &a = knots_[hint], &b = knots_[hint + 1];
  const double h = b.t - a.t;
  phi = step(a.w, a.s, b.w, b.s, h, (t - a.t) / h);
  return a;
}

void GyroTrack::locate(double t, size_t& hint) const {
  // knots_[hint].t <= t < knots_[hint + 1].t: walked to from the hint when it is a few
  // intervals off (the next observation's frame, mostly the same or the next), else searched.
  if (hint + 1 >= knots_.size()) hint = 0;
  for (int walk = 0; walk < kWalk && !(knots_[hint].t <= t && t < knots_[hint + 1].t); ++walk)
    hint = t < knots_[hint].t ? hint - 1 : hint + 1;  // stays inside: front().t <= t < back().t
  if (!(knots_[hint].t <= t && t < knots_[hint + 1].t)) {
    auto hi = std::upper_bound(knots_.begin(), knots_.end(), t, [](double tt, const Knot& k) { return tt < k.t; });
    hint = static_cast<size_t>(hi - knots_.begin()) - 1;
  }
}

Eigen::Vector3d GyroTrack::rate_at(double t, size_t& hint) const {
  if (!(t >= knots_.front().t && t < knots_.back().t)) return Eigen::Vector3d::Zero();
  locate(t, hint);
  const Knot &a = knots_[hint], &b = knots_[hint + 1];
  const double h = b.t - a.t;
  return imu_to_camera_ * hermite(a.w, a.s, b.w, b.s, h, (t - a.t) / h).rate;
}

Eigen::Matrix3d GyroTrack::camera_at(double t) const {
  size_t hint = 0;
  return camera_at(t, hint);
}

Eigen::Matrix3d GyroTrack::camera_at(double t, size_t& hint) const {
  Eigen::Vector3d phi;
  const Knot& a = interval(t, phi, hint);
  return a.R * exp_so3_fast(phi) * imu_to_camera_t_;
}

Eigen::Matrix3d GyroTrack::camera_at(double t, size_t& hint, Eigen::Vector3d& rate, ByGyro* by_gyro) const {
  Eigen::Vector3d phi;
  const Knot& a = interval(t, phi, hint);
  rate.setZero();
  const std::vector<ByGyro>* G = by_gyro ? &knots_by_gyro() : nullptr;
  if (by_gyro) *by_gyro = (*G)[&a - knots_.data()];  // held at the ends
  if (t >= knots_.front().t && t < knots_.back().t) {
    // R_imu = R_k Exp(phi(t)): the body rate is J_r(phi) phi', phi' the Hermite rate and the
    // Magnus term's derivative (across a long gap, where dt is large, it is not small).
    const Knot& b = knots_[hint + 1];
    const double h = b.t - a.t, tau = (t - a.t) / h, dt = t - a.t;
    const Eigen::Vector3d w = hermite(a.w, a.s, b.w, b.s, h, tau).rate;
    const Eigen::Vector3d slope = hermite_slope(a.w, a.s, b.w, b.s, h, tau);
    const Eigen::Vector3d dphi = w + dt / 6.0 * a.w.cross(w) + dt * dt / 12.0 * a.w.cross(slope);
    const Eigen::Matrix3d Jr = so3_right_jacobian(phi);
    rate = imu_to_camera_ * (Jr * dphi);
    if (by_gyro) *by_gyro = exp_so3_fast(-phi) * (*G)[hint] + Jr * step_by_gyro(a, b, tau);
  }
  return a.R * exp_so3_fast(phi) * imu_to_camera_t_;
}

Eigen::Vector3d GyroTrack::to_world(double t, const Eigen::Vector3d& v, size_t& hint) const {
  Eigen::Vector3d phi;
  const Knot& a = interval(t, phi, hint);
  return a.R * rotate_so3(phi, imu_to_camera_t_ * v);
}

Eigen::Vector3d GyroTrack::to_camera(double t, const Eigen::Vector3d& d, size_t& hint) const {
  Eigen::Vector3d phi;
  const Knot& a = interval(t, phi, hint);
  return imu_to_camera_ * rotate_so3(-phi, a.R.transpose() * d);
}

}  // namespace rsd::dsp
