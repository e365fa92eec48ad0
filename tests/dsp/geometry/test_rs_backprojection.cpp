// Back-projection must invert projection: the ray of a rolling-shutter pixel passes through
// the point that produced it, and carries its capture time.
#include <gtest/gtest.h>

#include <random>

#include "dsp/geometry/rs_backprojection.hpp"
#include "dsp/geometry/rs_projection.hpp"

using namespace rsd::dsp;
using Eigen::Vector2d;
using Eigen::Vector3d;

TEST(RsBackprojection, RayPassesThroughTheProjectedPoint) {
  CameraModel cam;
  cam.dist = {-0.2, 0.05, 0.0005, 0.0002, 0};
  const RowTiming timing = RowTiming::full_frame(480, 30, Readout::BottomToTop);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1), z(1, 15);
  int n = 0;
  for (int i = 0; i < 300; ++i) {
    Twist tw;
    tw.v = 3 * Vector3d(u(rng), u(rng), u(rng));
    tw.w = 2 * Vector3d(u(rng), u(rng), u(rng));
    const Vector3d X(2 * u(rng), 1.5 * u(rng), z(rng));
    const ScrewMotion motion(tw);
    const auto p = project_trajectory(cam, timing, motion, X);
    if (!p.ok() || !cam.contains(p.pixel)) continue;
    ++n;
    const auto ray = backproject(cam, timing, motion, p.pixel);
    ASSERT_TRUE(ray.has_value());
    EXPECT_NEAR(ray->t_c, p.t_c, 1e-9);
    const Vector3d d = X - ray->origin;
    EXPECT_LT((d - d.dot(ray->direction) * ray->direction).norm(), 1e-9);  // distance to ray
  }
  EXPECT_GT(n, 150);
}

TEST(RsBackprojection, RectifyRecoversTheGlobalShutterPixel) {
  // A plane at z = 4: the rectified pixel is the pinhole projection at t_ref of the point.
  const CameraModel cam;
  const RowTiming timing = RowTiming::full_frame(480, 30);
  Twist tw;
  tw.v = {1.0, -0.5, 0.3};
  tw.w = {0.2, -0.4, 0.9};
  const ScrewMotion motion(tw);
  const DepthModel plane = DepthModel::fronto_parallel(4.0);
  const double t_ref = timing.row_time(239.5);  // middle row
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> x(-1.5, 1.5), y(-1.2, 1.2);
  for (int i = 0; i < 200; ++i) {
    const Vector3d X(x(rng), y(rng), 4.0);
    const auto p = project_trajectory(cam, timing, motion, X);
    if (!p.ok()) continue;
    const auto rect = rectify_pixel(cam, timing, motion, plane, p.pixel, t_ref);
    ASSERT_TRUE(rect.has_value());
    const Vector2d gs = cam.project(motion.at(t_ref) * X).value();
    EXPECT_LT((*rect - gs).norm(), 1e-8);
  }
}

TEST(RsBackprojection, InfiniteDepthUsesRotationOnly) {
  const CameraModel cam;
  const RowTiming timing = RowTiming::full_frame(480, 30);
  Twist tw;
  tw.v = {50, 0, 0};  // translation must not matter at infinite depth
  tw.w = {0, 1.0, 0};
  const ScrewMotion motion(tw);
  const Vector2d px(100, 400);
  const auto rect = rectify_pixel(cam, timing, motion, DepthModel::at_infinity(), px, 0.0);
  ASSERT_TRUE(rect.has_value());
  // Rotate the pixel's ray back by the rotation over its capture time.
  const double t_c = 400 * timing.line_delay_s;
  const Vector3d d = exp_so3(tw.w * t_c).transpose() * cam.ray(px).value();
  EXPECT_LT((*rect - cam.project(d).value()).norm(), 1e-9);
}

TEST(RsBackprojection, ParallelPlaneHasNoIntersection) {
  const CameraModel cam;
  const RowTiming timing;
  const ScrewMotion still{Twist{}};
  const auto r = rectify_pixel(cam, timing, still, DepthModel::plane(Vector3d::UnitX(), 1.0),
                               Vector2d(319.5, 239.5), 0.0);
  EXPECT_FALSE(r.has_value());
}
