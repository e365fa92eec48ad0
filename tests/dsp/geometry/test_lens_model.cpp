// The equidistant (Kannala-Brandt) lens against its definition, written out here independently
// (the spec's formula, in long double), its derivative against finite differences, its inverse
// by round trips up to the lens's field, and the refusals beyond it. The comparison with an
// independent implementation, OpenCV's cv::fisheye, is test_lens_model_opencv.cpp (not in the
// arm64 cross build, which has no OpenCV).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/lens_model.hpp"

using namespace rsd::dsp;
using Eigen::Vector2d;

namespace {

// Lenses of the kind the field has: none, a mild Kalibr-style fisheye, a GoPro-class wide lens
// (gyroflow profiles of 2.7K wide modes), a strong one whose theta_d turns over before 90 deg.
const Distortion kLenses[] = {
    Distortion::equidistant(0, 0, 0, 0),
    Distortion::equidistant(-0.013, 0.021, -0.027, 0.011),
    Distortion::equidistant(0.0469, -0.0135, 0.0021, -0.0003),
    Distortion::equidistant(-0.5, 0.05, 0, 0),
};

// The spec's formula (recording-v1, "Lens models") in long double, straight from theta.
Vector2d spec_equi(const Distortion& d, const Vector2d& xn) {
  const long double x = xn.x(), y = xn.y(), r = std::sqrt(x * x + y * y);
  if (r == 0) return xn;
  const long double t = std::atan(r), t2 = t * t;
  const long double td = t * (1 + d.k1 * t2 + d.k2 * t2 * t2 + d.k3 * t2 * t2 * t2 + d.k4 * t2 * t2 * t2 * t2);
  return {static_cast<double>(td / r * x), static_cast<double>(td / r * y)};
}

// A unit direction at angle theta off the axis, azimuth phi, on the normalised plane.
Vector2d at_angle(double theta, double phi) { return std::tan(theta) * Vector2d(std::cos(phi), std::sin(phi)); }

}  // namespace

TEST(LensModel, NamesRoundTrip) {
  for (const LensModel m : {LensModel::PinholeRadtan, LensModel::PinholeEqui})
    EXPECT_EQ(parse_lens_model(lens_model_name(m)), m);
  EXPECT_FALSE(parse_lens_model("equidistant"));  // the calibration file's word, not the lens's name
  EXPECT_FALSE(parse_lens_model(""));
}

TEST(LensModel, OnlyATermlessRadtanLensIsTheIdentity) {
  EXPECT_TRUE(Distortion{}.is_identity());
  EXPECT_FALSE(Distortion::equidistant(0, 0, 0, 0).is_identity());  // theta, not tan(theta)
  const Vector2d x(0.8, -0.5);
  const Vector2d d = distort(Distortion::equidistant(0, 0, 0, 0), x);
  EXPECT_NEAR(d.norm(), std::atan(x.norm()), 1e-15);  // the pure equidistant lens: rho = theta
}

TEST(LensModel, EquidistantMatchesTheSpecFormula) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> theta(0, 1.45), phi(-M_PI, M_PI);
  for (const Distortion& d : kLenses)
    for (int i = 0; i < 500; ++i) {
      const Vector2d xn = at_angle(theta(rng), phi(rng));
      const Vector2d want = spec_equi(d, xn);
      EXPECT_LE((distort(d, xn) - want).norm(), 1e-14 * std::max(1.0, want.norm())) << xn.transpose();
    }
  // Near and on the axis, where theta_d / r is a limit.
  for (const double r : {0.0, 1e-300, 1e-12, 1e-8, 9.9e-8, 1.01e-7, 1e-6})
    for (const Distortion& d : kLenses) {
      const Vector2d xn(r * 0.6, -r * 0.8);
      EXPECT_LE((distort(d, xn) - spec_equi(d, xn)).norm(), 1e-15 * std::max(r, 1e-300)) << "r = " << r;
    }
}

TEST(LensModel, EquidistantJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> theta(0.01, 1.4), phi(-M_PI, M_PI);
  for (const Distortion& d : kLenses)
    for (int i = 0; i < 200; ++i) {
      const Vector2d xn = at_angle(theta(rng), phi(rng));
      const double h = 1e-6 * std::max(1.0, xn.norm());
      Eigen::Matrix2d fd;
      for (int k = 0; k < 2; ++k) {
        Vector2d e = Vector2d::Zero();
        e[k] = h;
        fd.col(k) = (distort(d, xn + e) - distort(d, xn - e)) / (2 * h);
      }
      EXPECT_LE((distort_jacobian(d, xn) - fd).norm(), 1e-7 * std::max(1.0, fd.norm())) << xn.transpose();
    }
  // At the axis the Jacobian is the identity; just off it, continuous with its limit.
  for (const Distortion& d : kLenses) {
    EXPECT_LE((distort_jacobian(d, Vector2d::Zero()) - Eigen::Matrix2d::Identity()).norm(), 1e-15);
    const Vector2d below(0.99e-7, 0), above(1.01e-7, 0);
    EXPECT_LE((distort_jacobian(d, below) - distort_jacobian(d, above)).norm(), 1e-12);
  }
}

// d(distort)/d(k1..k4) against central differences in each term, for both families (radtan with
// tangential terms: k4 is not one of its terms, its column zero), near the axis and far off it.
TEST(LensModel, RadialTermJacobianMatchesFiniteDifferences) {
  std::vector<Distortion> lenses(std::begin(kLenses), std::end(kLenses));
  lenses.push_back(Distortion{-0.28, 0.07, 1e-3, -2e-3, 0.01});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> theta(0.0, 1.0), phi(-M_PI, M_PI);
  for (const Distortion& d : lenses)
    for (int i = 0; i < 100; ++i) {
      const Vector2d xn = i == 0 ? Vector2d(1e-9, 0) : at_angle(theta(rng), phi(rng));
      const Eigen::Matrix<double, 2, 4> J = distort_radial_jacobian(d, xn);
      for (int k = 0; k < 4; ++k) {
        Distortion hi = d, lo = d;
        double* term_hi[] = {&hi.k1, &hi.k2, &hi.k3, &hi.k4};
        double* term_lo[] = {&lo.k1, &lo.k2, &lo.k3, &lo.k4};
        *term_hi[k] += 1e-6, *term_lo[k] -= 1e-6;
        const Vector2d fd = (distort(hi, xn) - distort(lo, xn)) / 2e-6;
        EXPECT_LE((J.col(k) - fd).norm(), 1e-8 * std::max(1.0, fd.norm())) << "term k" << k + 1 << " at " << xn.transpose();
      }
    }
}

// The one call that gives the point and its Jacobian together (the rectifier's Newton steps)
// gives what the two separate calls give, for both lens families, on and off the axis.
TEST(LensModel, PointAndJacobianTogetherEqualTheSeparateCalls) {
  std::vector<Distortion> lenses(std::begin(kLenses), std::end(kLenses));
  lenses.push_back({-0.28, 0.07, 2e-4, 2e-5, 0});  // pinhole-radtan
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> theta(0.0, 1.4), phi(-M_PI, M_PI);
  for (const Distortion& d : lenses)
    for (int i = 0; i < 100; ++i) {
      const Vector2d xn = i == 0 ? Vector2d::Zero() : i == 1 ? Vector2d(0.5e-7, 0) : at_angle(theta(rng), phi(rng));
      Eigen::Matrix2d J;
      const Vector2d xd = distort(d, xn, J);
      EXPECT_LE((xd - distort(d, xn)).norm(), 1e-15 * std::max(1.0, xd.norm())) << xn.transpose();
      EXPECT_LE((J - distort_jacobian(d, xn)).norm(), 1e-15 * std::max(1.0, J.norm())) << xn.transpose();
    }
}

// Up to 0.1 % short of the field the inverse holds to 1e-12; at the field's edge, where theta_d
// stops rising and the inverse is a square root of the rounding, to 1e-7.
TEST(LensModel, EquidistantRoundTripsToTheLensField) {
  for (const Distortion& d : kLenses) {
    const double field = equi_max_theta(d);
    const double top = field < M_PI / 2 ? field : 1.5707;
    const Vector2d edge = at_angle(top * (1 - 1e-9), 0.3);
    const auto at_edge = undistort(d, distort(d, edge));
    ASSERT_TRUE(at_edge);
    EXPECT_NEAR(std::atan(at_edge->norm()), top * (1 - 1e-9), 1e-7);
    for (int i = 0; i <= 1000; ++i) {
      const double theta = top * i / 1000.0 * (1 - 1e-3);
      const Vector2d xn = at_angle(theta, 0.37 * i);
      const auto back = undistort(d, distort(d, xn));
      ASSERT_TRUE(back) << "theta " << theta << " of a field of " << field;
      EXPECT_NEAR(std::atan(back->norm()), theta, 1e-12) << "theta " << theta;
      EXPECT_LE((*back - xn).norm(), 1e-11 * std::max(1.0, xn.norm() * xn.norm())) << "theta " << theta;
    }
  }
}

TEST(LensModel, TheFieldEndsWhereThetaDStopsRising) {
  // theta_d' = 1 - 1.5 theta^2 + 0.25 theta^4 = 0 at theta^2 = 3 - sqrt(5): 0.8740 rad.
  const Distortion strong = Distortion::equidistant(-0.5, 0.05, 0, 0);
  EXPECT_NEAR(equi_max_theta(strong), std::sqrt(3 - std::sqrt(5.0)), 1e-12);
  EXPECT_DOUBLE_EQ(equi_max_theta(Distortion::equidistant(0, 0, 0, 0)), M_PI / 2);
  // Beyond the largest theta_d the lens reaches there is no ray: refused, not a wrong one.
  const double td_max = distort(strong, at_angle(equi_max_theta(strong), 0)).norm();
  EXPECT_FALSE(undistort(strong, Vector2d(td_max * 1.001, 0)));
  EXPECT_TRUE(undistort(strong, Vector2d(td_max * 0.999, 0)));
  // A pure equidistant lens reaches 90 degrees at rho = pi/2, a point at infinity: refused.
  EXPECT_FALSE(undistort(Distortion::equidistant(0, 0, 0, 0), Vector2d(0, M_PI / 2)));
  EXPECT_FALSE(undistort(Distortion::equidistant(0, 0, 0, 0), Vector2d(2.0, 0)));
  EXPECT_FALSE(undistort(kLenses[1], Vector2d(std::nan(""), 0)));
}

TEST(LensModel, AnEquidistantCameraProjectsAndRefusesLikeAnyCamera) {
  CameraModel cam = CameraModel::from_hfov(1280, 960, 2.6);  // a 150-degree fisheye's focal length
  cam.fx = cam.fy = 400;
  cam.dist = Distortion::equidistant(0.0469, -0.0135, 0.0021, -0.0003);
  // A point 80 degrees off the axis lands on the sensor and its ray comes back.
  const Eigen::Vector3d X(std::sin(80 * M_PI / 180), 0, std::cos(80 * M_PI / 180));
  const auto px = cam.project(X);
  ASSERT_TRUE(px);
  EXPECT_TRUE(cam.contains(*px));
  const auto ray = cam.ray(*px);
  ASSERT_TRUE(ray);
  EXPECT_NEAR(ray->normalized().dot(X), 1.0, 1e-13);
  // Behind the image plane (90 degrees and beyond) is outside this lens model: refused.
  EXPECT_FALSE(cam.project({1, 0, 0}));
  EXPECT_FALSE(cam.project({1, 0, -0.1}));
  // The equidistant lens has no tangential terms, and a radtan lens no k4: refused by name.
  CameraModel bad = cam;
  bad.dist.p1 = 1e-3;
  EXPECT_EQ(out_of_range(bad).part, CameraOutOfRange::Distortion);
  EXPECT_STREQ(out_of_range(bad).field, "p1");
  bad = CameraModel{};
  bad.dist.k4 = 0.01;
  EXPECT_STREQ(out_of_range(bad).field, "k4");
  EXPECT_EQ(out_of_range(cam).part, CameraOutOfRange::None);
}
