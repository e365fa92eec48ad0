// The lens models of rsd's camera (docs/geometry.md, "Lens models"): how a normalised image-plane
// point x_n = (X/Z, Y/Z) is bent on its way to the pixel grid, and back.
//
//   pinhole-radtan  Brown-Conrady: x_d = x_n (1 + k1 r^2 + k2 r^4 + k3 r^6) + tangential(p1, p2),
//                   r = |x_n| (OpenCV's default model, Kalibr's pinhole-radtan, ROS's plumb_bob).
//   pinhole-equi    Kannala-Brandt, equidistant: theta = atan(r),
//                   theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8),
//                   x_d = (theta_d / r) x_n (OpenCV's cv::fisheye, Kalibr's pinhole-equi, ROS's
//                   equidistant).
//
// Both map the normalised plane, so the rest of the geometry (projection, the rolling-shutter
// constraint, rays) is the same for both; the equidistant lens reaches up to 90 degrees off the
// axis (theta < pi/2, Z > 0), and only as far as theta_d still grows with theta: beyond that
// angle its inverse is not unique, and points there are refused.
//
// Pure functions of their arguments: no state, any thread.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string_view>

namespace rsd::dsp {

enum class LensModel { PinholeRadtan, PinholeEqui };

// "pinhole-radtan", "pinhole-equi" (the recording format's `camera.model`) and back.
const char* lens_model_name(LensModel m);
std::optional<LensModel> parse_lens_model(std::string_view name);

// A lens: its coefficients and model. pinhole-radtan uses k1, k2, p1, p2, k3 (OpenCV's order, which
// {k1, k2, p1, p2, k3} initialises); pinhole-equi uses k1..k4 (cv::fisheye's D) and has no
// tangential terms (p1 = p2 = 0).
struct Distortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0, k4 = 0;
  LensModel model = LensModel::PinholeRadtan;
  // Whether the lens leaves the normalised plane as it is: only a radtan lens without terms (an
  // equidistant lens without terms still maps theta, not tan(theta), to the plane).
  bool is_identity() const {
    return model == LensModel::PinholeRadtan && k1 == 0 && k2 == 0 && p1 == 0 && p2 == 0 && k3 == 0 && k4 == 0;
  }
  bool operator==(const Distortion&) const = default;
  static Distortion equidistant(double k1, double k2, double k3, double k4) {
    return {k1, k2, 0, 0, k3, k4, LensModel::PinholeEqui};
  }
};

// The four terms files write for a lens (recording-v1's camera.distortion, Kalibr's
// distortion_coeffs): pinhole-radtan [k1, k2, p1, p2], pinhole-equi [k1, k2, k3, k4]; and back.
std::array<double, 4> file_terms(const Distortion& d);
Distortion from_file_terms(LensModel m, const double* k);

// Normalised point -> distorted normalised point.
Eigen::Vector2d distort(const Distortion& d, const Eigen::Vector2d& xn);
// d(distort)/d(xn), analytic (the rectifier's map steps and the solvers use it).
Eigen::Matrix2d distort_jacobian(const Distortion& d, const Eigen::Vector2d& xn);
// Both at once, sharing the work (the rectifier's Newton steps need both at every node).
Eigen::Vector2d distort(const Distortion& d, const Eigen::Vector2d& xn, Eigen::Matrix2d& jacobian);
// d(distort)/d(k1, k2, k3, k4): how the distorted point moves with the lens's radial terms
// (pinhole-radtan: k1, k2, k3 of r^2, r^4, r^6, and none for k4; pinhole-equi: k1..k4 of theta^3
// .. theta^9). The diagnosis's analytic Jacobian uses it (dsp/diagnosis/match_jacobian.hpp).
Eigen::Matrix<double, 2, 4> distort_radial_jacobian(const Distortion& d, const Eigen::Vector2d& xn);
// The inverse of distort(); nullopt where there is none: a radtan polynomial far outside its
// monotonic region, an equidistant point beyond the lens's field (equi_max_theta).
std::optional<Eigen::Vector2d> undistort(const Distortion& d, const Eigen::Vector2d& xd);

// The distorted normalised radius of a point `theta` radians off the axis (the radial terms
// only): theta_d for pinhole-equi, r (1 + k1 r^2 + k2 r^4 + k3 r^6) with r = tan(theta) for
// pinhole-radtan.
double distorted_radius(const Distortion& d, double theta);

// The equidistant lens's field: the largest angle off the axis (radians) up to which theta_d
// rises with theta, at most pi/2.
double equi_max_theta(const Distortion& d);

// The lens of family `to` whose radial mapping (normalised radius r = tan(theta) to distorted
// radius) is nearest to `from`'s over the angles 0..max_theta off the axis, least squares in
// the distorted radius: pinhole-equi k1..k4, pinhole-radtan k1, k2 (no tangential or k3 term).
// `from`'s tangential terms are ignored. The other family's best stand-in for a lens: where
// the diagnosis starts when it asks whether a recording's lens is of the other family.
Distortion nearest_lens(const Distortion& from, LensModel to, double max_theta);

}  // namespace rsd::dsp
