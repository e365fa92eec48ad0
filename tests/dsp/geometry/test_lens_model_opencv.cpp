// The equidistant lens against an independent implementation: OpenCV's cv::fisheye (the same
// Kannala-Brandt model, Kalibr's pinhole-equi). Projection agrees to 1e-9 relative; back-projection
// (cv::fisheye::undistortPoints, run to convergence) too, over each lens's field.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "dsp/geometry/camera_model.hpp"

using namespace rsd::dsp;

namespace test_lens_model_opencv {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

CameraModel fisheye(const Distortion& d) {
  CameraModel c;
  c.width = 1920, c.height = 1440;
  c.fx = 610.3, c.fy = 611.9, c.cx = 957.2, c.cy = 721.8;
  c.dist = d;
  return c;
}

cv::Matx33d K(const CameraModel& c) { return {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1}; }
cv::Vec4d D(const CameraModel& c) { return {c.dist.k1, c.dist.k2, c.dist.k3, c.dist.k4}; }

const Distortion kLenses[] = {
    Distortion::equidistant(0, 0, 0, 0),
    Distortion::equidistant(-0.013, 0.021, -0.027, 0.011),
    Distortion::equidistant(0.0469, -0.0135, 0.0021, -0.0003),
    Distortion::equidistant(-0.5, 0.05, 0, 0),
};

// Directions up to 95 % of each lens's field (and 85 degrees), azimuths all round.
std::vector<cv::Point3d> directions(const Distortion& d, int n) {
  std::mt19937 rng(11);
  const double top = std::min(0.95 * equi_max_theta(d), 85 * M_PI / 180);
  std::uniform_real_distribution<double> theta(0, top), phi(-M_PI, M_PI);
  std::vector<cv::Point3d> out;
  for (int i = 0; i < n; ++i) {
    const double t = theta(rng), p = phi(rng), depth = 0.5 + i % 7;
    out.emplace_back(depth * std::sin(t) * std::cos(p), depth * std::sin(t) * std::sin(p), depth * std::cos(t));
  }
  return out;
}

}  // namespace

TEST(LensModelOpenCv, EquidistantProjectionAgreesWithCvFisheyeProjectPoints) {
  for (const Distortion& d : kLenses) {
    const CameraModel cam = fisheye(d);
    const std::vector<cv::Point3d> X = directions(d, 2000);
    std::vector<cv::Point2d> cv_px;
    cv::fisheye::projectPoints(X, cv_px, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K(cam), D(cam));
    for (size_t i = 0; i < X.size(); ++i) {
      const auto px = cam.project({X[i].x, X[i].y, X[i].z});
      ASSERT_TRUE(px);
      const Eigen::Vector2d want(cv_px[i].x, cv_px[i].y);
      EXPECT_LE((*px - want).norm(), 1e-9 * want.norm()) << "point " << i;
    }
  }
}

TEST(LensModelOpenCv, EquidistantBackProjectionAgreesWithCvFisheyeUndistortPoints) {
  // Newton's method until a step below 1e-12 (quadratic convergence: the root then holds to the
  // last digit); OpenCV marks a point it gives up on with -1e6.
  const cv::TermCriteria converged(cv::TermCriteria::MAX_ITER + cv::TermCriteria::EPS, 200, 1e-12);
  for (const Distortion& d : kLenses) {
    const CameraModel cam = fisheye(d);
    const std::vector<cv::Point3d> X = directions(d, 2000);
    std::vector<cv::Point2d> px;
    for (const auto& x : X) {
      const Eigen::Vector2d p = *cam.project({x.x, x.y, x.z});
      px.emplace_back(p.x(), p.y());
    }
    std::vector<cv::Point2d> cv_xn;  // normalised plane (no new camera matrix)
    cv::fisheye::undistortPoints(px, cv_xn, K(cam), D(cam), cv::noArray(), cv::noArray(), converged);
    for (size_t i = 0; i < px.size(); ++i) {
      const auto ray = cam.ray({px[i].x, px[i].y});
      ASSERT_TRUE(ray);
      const Eigen::Vector2d want(cv_xn[i].x, cv_xn[i].y);
      EXPECT_LE((ray->head<2>() - want).norm(), 1e-9 * std::max(1.0, want.norm())) << "pixel " << i;
    }
  }
}

}  // namespace test_lens_model_opencv
