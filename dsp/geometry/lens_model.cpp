#include "dsp/geometry/lens_model.hpp"

#include <Eigen/QR>

#include <algorithm>

#include <Eigen/LU>
#include <cmath>
#include <numbers>

namespace rsd::dsp {

const char* lens_model_name(LensModel m) { return m == LensModel::PinholeEqui ? "pinhole-equi" : "pinhole-radtan"; }

std::optional<LensModel> parse_lens_model(std::string_view name) {
  if (name == "pinhole-radtan") return LensModel::PinholeRadtan;
  if (name == "pinhole-equi") return LensModel::PinholeEqui;
  return std::nullopt;
}

std::array<double, 4> file_terms(const Distortion& d) {
  if (d.model == LensModel::PinholeEqui) return {d.k1, d.k2, d.k3, d.k4};
  return {d.k1, d.k2, d.p1, d.p2};
}

Distortion from_file_terms(LensModel m, const double* k) {
  return m == LensModel::PinholeEqui ? Distortion::equidistant(k[0], k[1], k[2], k[3]) : Distortion{k[0], k[1], k[2], k[3], 0};
}

namespace {

// ---- pinhole-radtan (Brown-Conrady) ----

Eigen::Vector2d radtan(const Distortion& d, const Eigen::Vector2d& xn) {
  const double x = xn.x(), y = xn.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  return {x * radial + 2 * d.p1 * x * y + d.p2 * (r2 + 2 * x * x), y * radial + d.p1 * (r2 + 2 * y * y) + 2 * d.p2 * x * y};
}

Eigen::Matrix2d radtan_jacobian(const Distortion& d, const Eigen::Vector2d& xn) {
  const double x = xn.x(), y = xn.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  // d(radial)/d(r2); d(r2)/dx = 2x, d(r2)/dy = 2y.
  const double dradial = d.k1 + r2 * (2 * d.k2 + 3 * r2 * d.k3);
  Eigen::Matrix2d J;
  J(0, 0) = radial + x * dradial * 2 * x + 2 * d.p1 * y + d.p2 * 6 * x;
  J(0, 1) = x * dradial * 2 * y + 2 * d.p1 * x + d.p2 * 2 * y;
  J(1, 0) = y * dradial * 2 * x + d.p1 * 2 * x + 2 * d.p2 * y;
  J(1, 1) = radial + y * dradial * 2 * y + d.p1 * 6 * y + 2 * d.p2 * x;
  return J;
}

// Newton's method in the plane: the distortion is a perturbation of the identity, so start there.
std::optional<Eigen::Vector2d> radtan_inverse(const Distortion& d, const Eigen::Vector2d& xd) {
  Eigen::Vector2d xn = xd;
  for (int it = 0; it < 50; ++it) {
    const Eigen::Vector2d err = radtan(d, xn) - xd;
    if (err.norm() < 1e-15) return xn;
    const Eigen::Matrix2d J = radtan_jacobian(d, xn);
    if (std::abs(J.determinant()) < 1e-12) return std::nullopt;
    xn -= J.partialPivLu().solve(err);
    if (!xn.allFinite()) return std::nullopt;
  }
  if ((radtan(d, xn) - xd).norm() < 1e-12) return xn;
  return std::nullopt;
}

// ---- pinhole-equi (Kannala-Brandt) ----

// theta_d(theta) and its derivative, Horner in theta^2.
double theta_d(const Distortion& d, double t) {
  const double t2 = t * t;
  return t * (1 + t2 * (d.k1 + t2 * (d.k2 + t2 * (d.k3 + t2 * d.k4))));
}
double theta_d_slope(const Distortion& d, double t) {
  const double t2 = t * t;
  return 1 + t2 * (3 * d.k1 + t2 * (5 * d.k2 + t2 * (7 * d.k3 + t2 * 9 * d.k4)));
}

// Below this radius the scale theta_d / r and its derivative take their limits at r = 0 (the
// series to r^2), where the quotients would lose every digit.
constexpr double kSmallR = 1e-7;

// s(r) = theta_d(atan r) / r, the factor x_d = s x_n.
double equi_scale(const Distortion& d, double r) {
  if (r < kSmallR) return 1 + (d.k1 - 1.0 / 3.0) * r * r;
  return theta_d(d, std::atan(r)) / r;
}

Eigen::Vector2d equi(const Distortion& d, const Eigen::Vector2d& xn) { return equi_scale(d, xn.norm()) * xn; }

// x_d = s(r) x_n: J = s I + (s'(r) / r) x_n x_n^T, with s'(r) = (theta_d'(theta) / (1 + r^2) - s) / r.
// The point and its Jacobian share the arc tangent.
Eigen::Vector2d equi_with_jacobian(const Distortion& d, const Eigen::Vector2d& xn, Eigen::Matrix2d& J) {
  const double r = xn.norm();
  double s, ds_over_r;
  if (r < kSmallR) {
    s = equi_scale(d, r), ds_over_r = 2 * (d.k1 - 1.0 / 3.0);
  } else {
    const double t = std::atan(r);
    s = theta_d(d, t) / r, ds_over_r = (theta_d_slope(d, t) / (1 + r * r) - s) / (r * r);
  }
  J = s * Eigen::Matrix2d::Identity() + ds_over_r * xn * xn.transpose();
  return s * xn;
}

Eigen::Matrix2d equi_jacobian(const Distortion& d, const Eigen::Vector2d& xn) {
  Eigen::Matrix2d J;
  equi_with_jacobian(d, xn, J);
  return J;
}

// theta with theta_d(theta) = rho on [0, theta_max]: Newton's method kept inside a bracket that
// bisection narrows whenever a step would leave it.
std::optional<double> equi_theta(const Distortion& d, double rho, double theta_max) {
  if (!(rho <= theta_d(d, theta_max))) return std::nullopt;  // beyond the field (or NaN)
  double lo = 0, hi = theta_max, t = std::min(rho, theta_max);
  for (int it = 0; it < 100; ++it) {
    const double f = theta_d(d, t) - rho;
    if (std::abs(f) <= 1e-16 * std::max(1.0, rho)) return t;
    (f < 0 ? lo : hi) = t;
    const double slope = theta_d_slope(d, t);
    double next = slope > 0 ? t - f / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (next == t) return t;
    t = next;
  }
  return std::abs(theta_d(d, t) - rho) <= 1e-12 * std::max(1.0, rho) ? std::optional<double>(t) : std::nullopt;
}

// equi_max_theta of the lens this thread asked about last, remembered: a map or a render asks for
// the same lens's field at every node or pixel, and the field is a scan of 256 slopes.
double field_of(const Distortion& d) {
  thread_local Distortion lens{};
  thread_local double field = -1;
  if (field < 0 || !(d == lens)) lens = d, field = equi_max_theta(d);
  return field;
}

std::optional<Eigen::Vector2d> equi_inverse(const Distortion& d, const Eigen::Vector2d& xd) {
  const double rho = xd.norm();
  if (rho < kSmallR * 1e-3) return xd / equi_scale(d, rho);  // r = rho to this order
  const auto theta = equi_theta(d, rho, field_of(d));
  // At 90 degrees off the axis the point is at infinity on the plane: refused.
  if (!theta || !(*theta < 0.5 * std::numbers::pi * (1 - 1e-12))) return std::nullopt;
  return xd * (std::tan(*theta) / rho);
}

}  // namespace

double equi_max_theta(const Distortion& d) {
  // theta_d' is a polynomial in theta^2 with theta_d'(0) = 1: its first zero, if below pi/2, is
  // found on a grid fine enough for a degree-4 polynomial in theta^2, then by bisection.
  constexpr double kHalfPi = 0.5 * std::numbers::pi;
  constexpr int kSteps = 256;
  double prev = 0;
  for (int i = 1; i <= kSteps; ++i) {
    const double t = kHalfPi * i / kSteps;
    if (theta_d_slope(d, t) > 0) {
      prev = t;
      continue;
    }
    double lo = prev, hi = t;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      (theta_d_slope(d, mid) > 0 ? lo : hi) = mid;
    }
    return lo;
  }
  return kHalfPi;
}

Eigen::Vector2d distort(const Distortion& d, const Eigen::Vector2d& xn) {
  return d.model == LensModel::PinholeEqui ? equi(d, xn) : radtan(d, xn);
}

Eigen::Matrix2d distort_jacobian(const Distortion& d, const Eigen::Vector2d& xn) {
  return d.model == LensModel::PinholeEqui ? equi_jacobian(d, xn) : radtan_jacobian(d, xn);
}

Eigen::Vector2d distort(const Distortion& d, const Eigen::Vector2d& xn, Eigen::Matrix2d& jacobian) {
  if (d.model == LensModel::PinholeEqui) return equi_with_jacobian(d, xn, jacobian);
  jacobian = radtan_jacobian(d, xn);
  return radtan(d, xn);
}

Eigen::Matrix<double, 2, 4> distort_radial_jacobian(const Distortion& d, const Eigen::Vector2d& xn) {
  const double r = xn.norm();
  Eigen::Matrix<double, 2, 4> J;
  if (d.model == LensModel::PinholeRadtan) {
    const double r2 = r * r;
    J << xn * r2, xn * (r2 * r2), xn * (r2 * r2 * r2), Eigen::Vector2d::Zero();
    return J;
  }
  // x_d = (theta_d / r) x_n and d(theta_d)/dk_j = theta^(2j + 1): the column is x_n theta^(2j) (theta / r),
  // theta / r -> 1 at the axis.
  const double t = std::atan(r), t2 = t * t, q = r < kSmallR ? 1.0 : t / r;
  J << xn * (q * t2), xn * (q * t2 * t2), xn * (q * t2 * t2 * t2), xn * (q * t2 * t2 * t2 * t2);
  return J;
}

std::optional<Eigen::Vector2d> undistort(const Distortion& d, const Eigen::Vector2d& xd) {
  if (d.is_identity()) return xd;
  return d.model == LensModel::PinholeEqui ? equi_inverse(d, xd) : radtan_inverse(d, xd);
}

double distorted_radius(const Distortion& d, double theta) {
  if (d.model == LensModel::PinholeEqui) return theta_d(d, theta);
  const double r = std::tan(theta), r2 = r * r;
  return r * (1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3)));
}

Distortion nearest_lens(const Distortion& from, LensModel to, double max_theta) {
  // rho(theta) - base(theta) = base(theta) sum_j k_j x^(2j), x = theta (equi) or tan(theta)
  // (radtan): linear in the k_j, solved over a grid of angles.
  const bool equi = to == LensModel::PinholeEqui;
  const int terms = equi ? 4 : 2, samples = 200;
  const double top = std::clamp(max_theta, 1e-3, equi ? 0.5 * std::numbers::pi - 1e-3 : 1.4);
  Eigen::MatrixXd A(samples, terms);
  Eigen::VectorXd b(samples);
  for (int i = 0; i < samples; ++i) {
    const double theta = top * (i + 1) / samples;
    const double x = equi ? theta : std::tan(theta);
    double xp = x * x;
    for (int j = 0; j < terms; ++j, xp *= x * x) A(i, j) = x * xp;
    b(i) = distorted_radius(from, theta) - x;
  }
  const Eigen::VectorXd k = A.colPivHouseholderQr().solve(b);
  if (equi) return Distortion::equidistant(k(0), k(1), k(2), k(3));
  Distortion d;
  d.k1 = k(0), d.k2 = k(1);
  return d;
}

}  // namespace rsd::dsp
