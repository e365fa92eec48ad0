// The rolling-shutter row by secant iteration (dsp/geometry/row_fixed_point.hpp): against a
// linear map's closed form, against the bracketing root finder of rs_projection.hpp on screw
// motions, and its refusals.
#include <gtest/gtest.h>

#include <random>

#include "dsp/geometry/row_fixed_point.hpp"
#include "dsp/geometry/rs_projection.hpp"
#include "tests/support/random_twist.hpp"

using namespace rsd::dsp;
using Eigen::Vector2d;
using Eigen::Vector3d;

// pixel_at(v).y = a + b v has its row at a / (1 - b); the secant on a line is exact, so from the
// observed row two evaluations settle it, and from a start given the line's slope (b - 1), one.
TEST(RowFixedPoint, SolvesALinearMapInTwoEvaluationsOrOneWithItsSlope) {
  const double a = 130, b = 0.04;
  int calls = 0;
  auto line = [&](double v) -> std::optional<Vector2d> {
    ++calls;
    return Vector2d(7, a + b * v);
  };
  const auto s = fixed_point_row(line, 100.0);
  ASSERT_TRUE(s.has_value());
  EXPECT_NEAR(s->row, a / (1 - b), 1e-9);
  EXPECT_NEAR(s->px.y(), s->row, 1e-6);
  EXPECT_NEAR(s->slope, b - 1, 1e-12);
  EXPECT_LE(calls, 3);
  calls = 0;
  const auto again = fixed_point_row(line, 120.0, b - 1);
  ASSERT_TRUE(again.has_value());
  EXPECT_NEAR(again->row, a / (1 - b), 1e-9);
  EXPECT_LE(calls, 2);
}

// On screw motions (constant v and w) the row is where project_trajectory's bracketing and
// Brent's method put the capture time: the same pixel, by a different code path.
TEST(RowFixedPoint, AgreesWithTheBracketingSolverOnScrewMotions) {
  CameraModel cam;
  cam.dist = {-0.2, 0.05, 0.0005, 0.0002, 0};
  const RowTiming timing = RowTiming::full_frame(480, 30);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1), z(2, 15);
  int n = 0;
  for (int i = 0; i < 300; ++i) {
    const Twist tw = rsd::test::random_twist(rng, Vector3d::Ones(), Vector3d::Ones(), 2, 1.5);
    const Vector3d X(2 * u(rng), 1.5 * u(rng), z(rng));
    const ScrewMotion motion(tw);
    const RsProjection p = project_trajectory(cam, timing, motion, X);
    if (!p.ok() || !cam.contains(p.pixel)) continue;
    const auto pixel_at = [&](double v) { return cam.project(motion.at(timing.row_time(v)) * X); };
    const auto start = cam.project(motion.at(timing.row_time(240)) * X);  // the middle row's projection
    ASSERT_TRUE(start.has_value());
    const auto s = fixed_point_row(pixel_at, start->y());
    ASSERT_TRUE(s.has_value()) << "twist " << tw.w.transpose() << " | " << tw.v.transpose() << ", X " << X.transpose();
    EXPECT_LT((s->px - p.pixel).norm(), 1e-5);
    EXPECT_NEAR(timing.row_time(s->row), p.t_c, 1e-9);
    ++n;
  }
  EXPECT_GT(n, 150);
}

// No pixel on the way, or a map that never settles (the row moves with the readout: the point
// keeps pace with the rows), is refused, not answered.
TEST(RowFixedPoint, RefusesWhatItCannotSolve) {
  EXPECT_FALSE(fixed_point_row([](double) -> std::optional<Vector2d> { return std::nullopt; }, 10.0).has_value());
  EXPECT_FALSE(fixed_point_row([](double v) -> std::optional<Vector2d> { return Vector2d(0, v + 1); }, 10.0).has_value());
  EXPECT_FALSE(fixed_point_row([](double v) -> std::optional<Vector2d> {
                 if (v > 50) return std::nullopt;
                 return Vector2d(0, 100 + 0.1 * v);
               }, 10.0).has_value());
}
