#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "dsp/geometry/camera_model.hpp"

using namespace rsd::dsp;
using Eigen::Vector2d;

TEST(CameraModel, HfovGivesTheFocalLength) {
  const CameraModel c = CameraModel::from_hfov(640, 480, 40.0 * M_PI / 180.0);
  EXPECT_NEAR(c.fx, 320.0 / std::tan(20.0 * M_PI / 180.0), 1e-9);  // 879.2
  EXPECT_NEAR(c.fx, 879.19, 0.01);
  EXPECT_DOUBLE_EQ(c.cx, 319.5);  // centre of the top-left pixel is (0, 0)
}

TEST(CameraModel, DistortionMatchesTheSpecFormula) {
  CameraModel c;
  c.dist = {-0.3, 0.1, 0.002, -0.001, 0.02};
  const double x = 0.3, y = -0.2, r2 = x * x + y * y;
  const double rad = 1 - 0.3 * r2 + 0.1 * r2 * r2 + 0.02 * r2 * r2 * r2;
  const Vector2d d = c.distort({x, y});
  EXPECT_NEAR(d.x(), x * rad + 2 * 0.002 * x * y + -0.001 * (r2 + 2 * x * x), 1e-15);
  EXPECT_NEAR(d.y(), y * rad + 0.002 * (r2 + 2 * y * y) + 2 * -0.001 * x * y, 1e-15);
}

TEST(CameraModel, JacobianMatchesFiniteDifferences) {
  CameraModel c;
  c.dist = {-0.3, 0.1, 0.002, -0.001, 0.02};
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  for (int i = 0; i < 100; ++i) {
    const Vector2d p(u(rng), u(rng));
    const double h = 1e-6;
    Eigen::Matrix2d fd;
    for (int k = 0; k < 2; ++k) {
      Vector2d e = Vector2d::Zero();
      e[k] = h;
      fd.col(k) = (c.distort(p + e) - c.distort(p - e)) / (2 * h);
    }
    EXPECT_LT((fd - c.distort_jacobian(p)).norm(), 1e-8);
  }
}

TEST(CameraModel, UndistortInvertsDistort) {
  CameraModel c;
  c.dist = {-0.28, 0.07, 0.001, -0.0008, 0.0};
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0, 639), v(0, 479);
  for (int i = 0; i < 1000; ++i) {
    const Vector2d px(u(rng), v(rng));
    const auto xn = c.from_pixel(px);
    ASSERT_TRUE(xn.has_value());
    EXPECT_LT((c.to_pixel(*xn) - px).norm(), 1e-9);
  }
}

TEST(CameraModel, UndistortFailsCleanlyWhereDistortionFolds) {
  CameraModel c;
  c.dist = {-0.6, 0, 0, 0, 0};  // r(1 - 0.6 r^2) peaks at r = 0.745, value 0.497
  EXPECT_FALSE(c.undistort({0.9, 0.0}).has_value());
  EXPECT_TRUE(c.undistort({0.3, 0.0}).has_value());
}

TEST(CameraModel, ProjectRejectsPointsBehind) {
  CameraModel c;
  EXPECT_FALSE(c.project({0, 0, -1}).has_value());
  EXPECT_FALSE(c.project({1, 0, 0}).has_value());
  const auto p = c.project({0.2, -0.1, 2.0});
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->x(), 500 * 0.1 + 319.5, 1e-12);
  EXPECT_NEAR(p->y(), -500 * 0.05 + 239.5, 1e-12);
}

// rsd's input limits on a camera (dsp/core/input_limits.hpp): issue 38's absurd intrinsics (fx
// 1e300 or 1e-300, cx 1e300, k1 1e6) are refused naming the part; a real camera passes, as do
// the limits' own ends.
TEST(CameraModel, OutOfRangeNamesThePartAndTheField) {
  const CameraModel ok = CameraModel::from_hfov(640, 480, 1.0);
  EXPECT_EQ(out_of_range(ok).part, CameraOutOfRange::None);
  struct Case {
    void (*bend)(CameraModel&);
    CameraOutOfRange::Part part;
    const char* field;
  };
  const Case cases[] = {
      {[](CameraModel& c) { c.fx = 1e300; }, CameraOutOfRange::Focal, "fx"},
      {[](CameraModel& c) { c.fy = 1e-300; }, CameraOutOfRange::Focal, "fy"},
      {[](CameraModel& c) { c.fx = std::nan(""); }, CameraOutOfRange::Focal, "fx"},
      {[](CameraModel& c) { c.cx = 1e300; }, CameraOutOfRange::PrincipalPoint, "cx"},
      {[](CameraModel& c) { c.cy = -5.0 * c.height; }, CameraOutOfRange::PrincipalPoint, "cy"},
      {[](CameraModel& c) { c.dist.k1 = 1e6; }, CameraOutOfRange::Distortion, "k1"},
      {[](CameraModel& c) { c.dist.p2 = -INFINITY; }, CameraOutOfRange::Distortion, "p2"},
      {[](CameraModel& c) { c.width = 8001; }, CameraOutOfRange::Size, "width"},
      {[](CameraModel& c) { c.height = 2; }, CameraOutOfRange::Size, "height"},
  };
  for (const Case& k : cases) {
    CameraModel c = ok;
    k.bend(c);
    const CameraOutOfRange r = out_of_range(c);
    EXPECT_EQ(r.part, k.part) << k.field;
    EXPECT_STREQ(r.field, k.field);
    EXPECT_EQ(r.why.rfind(std::string(k.field) == "cx" || std::string(k.field) == "cy" ? std::string(k.field) + " / " : k.field, 0), 0u) << r.why;
  }
  CameraModel edge = ok;
  edge.fx = 1, edge.fy = 1e7, edge.cx = -4.0 * edge.width, edge.cy = 5.0 * edge.height, edge.dist.k3 = 1000;
  EXPECT_EQ(out_of_range(edge).part, CameraOutOfRange::None) << out_of_range(edge).why;
}

TEST(CameraModel, WidestRayAngleIsTheFarthestCornersAngleOffTheAxis) {
  // Pinhole: the corner farthest from the principal point, by its tangent.
  CameraModel cam;
  cam.width = 640, cam.height = 480, cam.fx = 500, cam.fy = 400, cam.cx = 300, cam.cy = 200;
  EXPECT_NEAR(widest_ray_angle(cam), std::atan(std::hypot(340.0 / 500, 280.0 / 400)), 1e-12);
  // Barrel distortion bends the corner's ray outwards: a wider angle than the pinhole's.
  CameraModel barrel = cam;
  barrel.dist.k1 = -0.05;
  EXPECT_GT(widest_ray_angle(barrel), widest_ray_angle(cam) + 0.01);
}
