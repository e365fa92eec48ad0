// The rolling-shutter camera under fronto-parallel translation is a crossed-slits camera
// (Meingast, Geyer, Sastry 2005, section "Fronto-parallel motion"). Ground truth here is
// independent of crossed_slits(): rays come from backproject() (the camera motion), slit
// positions from the raw timing fields, transversals from lines constructed to meet.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "dsp/analysis/crossed_slits.hpp"
#include "dsp/geometry/rs_backprojection.hpp"

using namespace rsd::dsp;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

// Mismatch between two lines as lines: each one's point off the other, plus the sine of
// the angle between them. Zero iff they are the same line.
double line_mismatch(const Line3& a, const Line3& b) {
  return distance(a, b.point) + distance(b, a.point) + a.direction.cross(b.direction).norm();
}

std::string sci(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3e", x);
  return buf;
}

// Mismatch between two found lines and two expected ones, in the better of both orders.
double pair_mismatch(const std::vector<Line3>& found, const Line3& a, const Line3& b) {
  const double direct = std::max(line_mismatch(found[0], a), line_mismatch(found[1], b));
  const double swapped = std::max(line_mismatch(found[0], b), line_mismatch(found[1], a));
  return std::min(direct, swapped);
}

std::array<const CameraMotion*, 2> both_motions(const CameraMotion& a, const CameraMotion& b) {
  return {&a, &b};
}

Line3 as_line(const RsRay& r) { return Line3::through(r.origin, r.direction); }

// A camera with fx != fy and an off-centre principal point.
CameraModel skewed_camera() {
  CameraModel c;
  c.fx = 540;
  c.fy = 500;
  c.cx = 301.3;
  c.cy = 255.7;
  return c;
}

RowTiming timing_of(Readout dir, double line_delay) {
  RowTiming t = RowTiming::full_frame(480, 30, dir);
  t.line_delay_s = line_delay;
  return t;
}

std::vector<RowTiming> timings() {
  return {timing_of(Readout::TopToBottom, 1.0 / (480 * 30)),
          timing_of(Readout::BottomToTop, 1.0 / (480 * 30)),
          timing_of(Readout::TopToBottom, 1.0 / (480 * 60)),
          timing_of(Readout::BottomToTop, 1.0 / (480 * 15))};
}

// The paper's r and v0 straight from the timing fields (not through RowTiming::r/v0):
// the row read at t is first_row + sign * t / line_delay = r t - v0.
struct RawRate {
  double r, v0;
};
RawRate raw_rate(const RowTiming& t) {
  const bool down = t.readout == Readout::TopToBottom;
  const double first = t.first_row >= 0 ? t.first_row : (down ? 0.0 : t.height - 1.0);
  return {(down ? 1.0 : -1.0) / t.line_delay_s, -first};
}

// Random fronto-parallel translation, 1-5 m/s, with |vy| > 0.1 m/s.
Twist random_translation(std::mt19937& rng) {
  std::uniform_real_distribution<double> mag(1, 5), ang(0, 2 * M_PI);
  Twist tw;
  do {
    const double a = ang(rng), m = mag(rng);
    tw.v = {m * std::cos(a), m * std::sin(a), 0};
  } while (std::abs(tw.v.y()) <= 0.1);
  return tw;
}

Vector2d random_pixel(std::mt19937& rng, const CameraModel& cam) {
  std::uniform_real_distribution<double> u(0, cam.width - 1), v(0, cam.height - 1);
  return {u(rng), v(rng)};
}

Line3 ray_of(const CameraModel& cam, const RowTiming& timing, const CameraMotion& motion,
             const Vector2d& px) {
  return as_line(backproject(cam, timing, motion, px).value());
}

Line3 random_line(std::mt19937& rng, double extent) {
  std::normal_distribution<double> n(0, 1);
  const Vector3d p(n(rng), n(rng), n(rng)), d(n(rng), n(rng), n(rng));
  return Line3::through(extent * p, d);
}

}  // namespace

// ---------------------------------------------------------------- lines and Plücker

TEST(Line3, DistanceAlongAKnownCommonPerpendicular) {
  // Both lines orthogonal to e3 and h apart along it: the distance is |h| at any angle,
  // including exactly and nearly parallel ones (the two branches of distance()).
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-3, 3);
  for (double angle : {M_PI / 2, 0.3, 1e-6, 1e-9, 1e-12, 0.0}) {
    for (int i = 0; i < 50; ++i) {
      const Eigen::Matrix3d R = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
      const Vector3d e1 = R.col(0), e2 = R.col(1), e3 = R.col(2), c(u(rng), u(rng), u(rng));
      const double h = u(rng);
      const Line3 a = Line3::through(c + u(rng) * e1, e1);
      const Vector3d d2 = std::cos(angle) * e1 + std::sin(angle) * e2;
      const Line3 b = Line3::through(c + h * e3 + u(rng) * d2, d2);
      EXPECT_NEAR(distance(a, b), std::abs(h), 1e-9) << "angle " << angle;
      EXPECT_NEAR(distance(b, a), std::abs(h), 1e-9) << "angle " << angle;
    }
  }
  const Line3 x = Line3::through(Vector3d(5, 0, 0), Vector3d(2, 0, 0));
  EXPECT_NEAR(distance(x, Vector3d(-7, 3, 4)), 5.0, 1e-15);
  EXPECT_NEAR(distance(x, Line3::through(Vector3d(1, 1, 1), Vector3d(0, 1, 1))), 0.0, 1e-15);
}

TEST(Line3, PluckerRoundTripAndReciprocalProduct) {
  std::mt19937 rng(2);
  for (int i = 0; i < 100; ++i) {
    const Line3 a = random_line(rng, 3), b = random_line(rng, 3);
    const Plucker A = to_plucker(a), B = to_plucker(b);
    EXPECT_NEAR(A.head<3>().dot(A.tail<3>()), 0, 1e-14);  // on the Klein quadric
    EXPECT_LT(line_mismatch(from_plucker(A).value(), a), 1e-12);
    EXPECT_LT(line_mismatch(from_plucker(-2.5 * A).value(), a), 1e-12);  // homogeneous
    // For unit directions |(a, b)| = sin(angle) * distance.
    EXPECT_NEAR(std::abs(reciprocal_product(A, B)),
                a.direction.cross(b.direction).norm() * distance(a, b), 1e-12);
  }
  Plucker at_inf;
  at_inf << 0, 0, 0, 0, 0, 1;  // the line at infinity of the planes z = const
  EXPECT_FALSE(from_plucker(at_inf).has_value());
}

TEST(CommonTransversals, RecoversTwoConstructedLines) {
  // Four random lines, each through a random point of L1 and one of L2: the transversals
  // must be L1 and L2 themselves.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> s(-4, 4);
  double worst = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Line3 L1 = random_line(rng, 2), L2 = random_line(rng, 2);
    std::array<Line3, 4> lines;
    for (auto& l : lines) {
      const Vector3d p = L1.point_at(s(rng)), q = L2.point_at(s(rng));
      l = Line3::through(p, q - p);
    }
    const Transversals t = common_transversals(lines);
    ASSERT_FALSE(t.degenerate);
    ASSERT_EQ(t.lines.size(), 2u);
    worst = std::max(worst, pair_mismatch(t.lines, L1, L2));
    for (const Line3& tr : t.lines)
      for (const Line3& l : lines) EXPECT_LT(distance(tr, l), 1e-9);
  }
  EXPECT_LT(worst, 1e-8);
  RecordProperty("worst_mismatch", sci(worst));
}

TEST(CommonTransversals, HyperboloidGivesZeroOneOrTwo) {
  // x^2 + y^2 - z^2 = 1 carries two reguli through (cos th, sin th, 0): A along
  // (-sin th, cos th, 1), B along (sin th, -cos th, 1). Three A lines have all B lines as
  // transversals, so a fourth line's transversals are the B lines through the points where
  // it meets the hyperboloid: none for the z axis, two for the x axis (at x = +-1), one
  // for the tangent x = 1, y = 0.
  auto A = [](double th) {
    return Line3::through({std::cos(th), std::sin(th), 0}, {-std::sin(th), std::cos(th), 1});
  };
  auto B = [](double th) {
    return Line3::through({std::cos(th), std::sin(th), 0}, {std::sin(th), -std::cos(th), 1});
  };
  const Line3 a1 = A(1.0), a2 = A(2.5), a3 = A(4.0);

  const Transversals none = common_transversals({a1, a2, a3, Line3::through({0, 0, 0}, {0, 0, 1})});
  EXPECT_FALSE(none.degenerate);
  EXPECT_TRUE(none.lines.empty());

  const Transversals two = common_transversals({a1, a2, a3, Line3::through({0, 0, 0}, {1, 0, 0})});
  ASSERT_EQ(two.lines.size(), 2u);
  const double m00 = line_mismatch(two.lines[0], B(0)), m0pi = line_mismatch(two.lines[0], B(M_PI));
  EXPECT_LT(std::min(m00, m0pi), 1e-12);
  EXPECT_LT(line_mismatch(two.lines[1], m00 < m0pi ? B(M_PI) : B(0)), 1e-12);

  const Transversals one = common_transversals({a1, a2, a3, Line3::through({1, 0, 0}, {0, 0, 1})});
  ASSERT_EQ(one.lines.size(), 1u);
  EXPECT_LT(line_mismatch(one.lines[0], B(0)), 1e-6);  // a double root: ~sqrt(eps) accuracy

  // Four lines of one regulus: every line of the other is a transversal.
  EXPECT_TRUE(common_transversals({a1, a2, a3, A(5.5)}).degenerate);
}

// ---------------------------------------------------------------- the crossed slits

TEST(CrossedSlits, EveryRayMeetsBothSlits) {
  const CameraModel cam = skewed_camera();
  std::mt19937 rng(7);
  double worst = 0;
  int rays = 0;
  for (const RowTiming& timing : timings()) {
    for (int k = 0; k < 20; ++k) {
      const Twist tw = random_translation(rng);
      const auto cs = crossed_slits(cam, timing, tw);
      ASSERT_TRUE(cs.has_value());
      const LinearisedMotion lin(tw);
      const ScrewMotion screw(tw);  // identical to the linearised motion when w = 0
      for (int i = 0; i < 10; ++i) {
        const Vector2d px = random_pixel(rng, cam);
        for (const CameraMotion* m : both_motions(lin, screw)) {
          const Line3 ray = ray_of(cam, timing, *m, px);
          worst = std::max({worst, distance(ray, cs->slit1), distance(ray, cs->slit2)});
          ++rays;
        }
      }
    }
  }
  EXPECT_GE(rays, 400);
  EXPECT_LT(worst, 1e-9);
  RecordProperty("worst_ray_slit_distance", sci(worst));
}

TEST(CrossedSlits, SlitPositionsMatchTheFormula) {
  const CameraModel cam = skewed_camera();
  std::mt19937 rng(8);
  for (const RowTiming& timing : timings()) {
    const RawRate raw = raw_rate(timing);
    const double r_n = raw.r / cam.fy, v0_n = (raw.v0 + cam.cy) / cam.fy;
    for (int k = 0; k < 20; ++k) {
      const Twist tw = random_translation(rng);
      const auto cs = crossed_slits(cam, timing, tw).value();
      const double vy = tw.v.y();
      // Slit 2: the x-parallel line at depth vy / r_n and height -v0_n vy / r_n.
      EXPECT_LT(distance(cs.slit2, Vector3d(0, -v0_n * vy / r_n, vy / r_n)), 1e-14);
      EXPECT_LT(cs.slit2.direction.cross(Vector3d::UnitX()).norm(), 1e-15);
      // Slit 1: through the camera centre at frame start, along the velocity.
      EXPECT_LT(distance(cs.slit1, Vector3d::Zero()), 1e-15);
      EXPECT_LT(cs.slit1.direction.cross(tw.v.normalized()).norm(), 1e-15);
      // Distinct: skew, the depth of slit 2 apart (they never meet while vy != 0).
      EXPECT_NEAR(distance(cs.slit1, cs.slit2), std::abs(vy / r_n), 1e-12);
    }
  }
  // vx = 0: the paper's orthogonal crossed-slits camera (its Figure, left).
  Twist tw;
  tw.v = {0, 2, 0};
  const auto cs = crossed_slits(cam, timings()[0], tw).value();
  EXPECT_NEAR(cs.slit1.direction.dot(cs.slit2.direction), 0, 1e-15);
}

TEST(CrossedSlits, ThePaperPrintedSignMissesTheRays) {
  // The paper prints slit 2 through (+-1, +v0 vy / r, vy / r). With eq. (1), r t - v0,
  // the rays cross the plane z = vy / r_n at y = -c, c = v0_n vy / r_n, so they pass the
  // printed line (y = +c in that plane, along x) at exactly 2 |c| / sqrt(1 + v_n^2).
  const CameraModel cam = skewed_camera();
  std::mt19937 rng(9);
  double smallest = 1e300;
  for (const RowTiming& timing : timings()) {
    const RawRate raw = raw_rate(timing);
    const double r_n = raw.r / cam.fy, v0_n = (raw.v0 + cam.cy) / cam.fy;
    ASSERT_GT(std::abs(v0_n), 0.4);
    for (int k = 0; k < 10; ++k) {
      const Twist tw = random_translation(rng);
      const double c = v0_n * tw.v.y() / r_n;
      const Line3 printed = Line3::through(Vector3d(1, c, tw.v.y() / r_n), Vector3d::UnitX());
      const LinearisedMotion motion(tw);
      for (int i = 0; i < 20; ++i) {
        const Vector2d px = random_pixel(rng, cam);
        const double v_n = (px.y() - cam.cy) / cam.fy;
        const double d = distance(ray_of(cam, timing, motion, px), printed);
        EXPECT_NEAR(d, 2 * std::abs(c) / std::sqrt(1 + v_n * v_n), 1e-12);
        smallest = std::min(smallest, d);
      }
    }
  }
  EXPECT_GT(smallest, 1e-3);  // millimetres at least: not rounding
  RecordProperty("smallest_printed_slit_distance", sci(smallest));

  // The two signs agree only when v0_n = 0: the first row read is the principal row.
  CameraModel centred = cam;
  centred.cy = 240;
  RowTiming from_centre = timings()[0];
  from_centre.first_row = 240;
  Twist tw;
  tw.v = {1.5, -2.5, 0};
  const auto cs = crossed_slits(centred, from_centre, tw).value();
  const RawRate raw = raw_rate(from_centre);
  const double r_n = raw.r / centred.fy;
  const Line3 printed = Line3::through(Vector3d(1, 0, tw.v.y() / r_n), Vector3d::UnitX());
  EXPECT_LT(line_mismatch(cs.slit2, printed), 1e-15);
  const LinearisedMotion motion(tw);
  for (int i = 0; i < 50; ++i)
    EXPECT_LT(distance(ray_of(centred, from_centre, motion, random_pixel(rng, centred)), printed),
              1e-9);
}

TEST(CrossedSlits, NulloptOutsideFrontoParallelTranslation) {
  const CameraModel cam = skewed_camera();
  const RowTiming timing = timings()[0];
  Twist tw;
  tw.v = {1, 2, 0};
  EXPECT_TRUE(crossed_slits(cam, timing, tw).has_value());

  Twist rot = tw;
  rot.w = {0, 0, 1};
  EXPECT_FALSE(crossed_slits(cam, timing, rot).has_value());
  rot.w = {1e-9, 0, 0};
  EXPECT_FALSE(crossed_slits(cam, timing, rot).has_value());

  Twist forward = tw;
  forward.v.z() = 0.5;
  EXPECT_FALSE(crossed_slits(cam, timing, forward).has_value());

  Twist sideways = tw;
  sideways.v.y() = 0;  // both slits on the x axis
  EXPECT_FALSE(crossed_slits(cam, timing, sideways).has_value());
  EXPECT_FALSE(crossed_slits(cam, timing, Twist{}).has_value());

  CameraModel lens = cam;
  lens.dist.k1 = -0.1;
  EXPECT_FALSE(crossed_slits(lens, timing, tw).has_value());
}

TEST(CrossedSlits, TransversalsOfFourRaysAreTheSlits) {
  // Without knowing the slits: four rays determine two transversals, which must be the
  // slits, and every other ray must meet them.
  const CameraModel cam = skewed_camera();
  std::mt19937 rng(10);
  double worst_slit = 0, worst_ray = 0;
  for (const RowTiming& timing : timings()) {
    for (int k = 0; k < 10; ++k) {
      const Twist tw = random_translation(rng);
      const auto cs = crossed_slits(cam, timing, tw).value();
      const LinearisedMotion motion(tw);
      std::array<Line3, 4> four;
      for (auto& l : four) l = ray_of(cam, timing, motion, random_pixel(rng, cam));
      const Transversals t = common_transversals(four);
      ASSERT_EQ(t.lines.size(), 2u);
      worst_slit = std::max(worst_slit, pair_mismatch(t.lines, cs.slit1, cs.slit2));
      for (int i = 0; i < 200; ++i) {
        const Line3 ray = ray_of(cam, timing, motion, random_pixel(rng, cam));
        worst_ray = std::max({worst_ray, distance(ray, t.lines[0]), distance(ray, t.lines[1])});
      }
    }
  }
  EXPECT_LT(worst_slit, 1e-9);
  EXPECT_LT(worst_ray, 1e-9);
  RecordProperty("worst_transversal_slit_mismatch", sci(worst_slit));
  RecordProperty("worst_ray_transversal_distance", sci(worst_ray));
}

namespace {

// For w != 0: several quadruples of rays, each with its transversals (the only candidates
// for a pair of slits through them) tested against 200 further rays. Per quadruple, the
// largest distance by which a ray misses one transversal (a crossed-slits camera: ~0) and
// the largest by which one misses both; the smallest of each over the quadruples.
struct BreakResult {
  double misses_one = 1e300, misses_both = 1e300;
  int with_two = 0;
};
BreakResult crossed_slits_break(const CameraModel& cam, const RowTiming& timing,
                                const CameraMotion& motion, std::mt19937& rng) {
  BreakResult res;
  for (int q = 0; q < 20; ++q) {
    std::array<Line3, 4> four;
    for (auto& l : four) l = ray_of(cam, timing, motion, random_pixel(rng, cam));
    const Transversals t = common_transversals(four);
    if (t.lines.size() != 2) continue;  // no pair of slits at all through these four rays
    ++res.with_two;
    for (const Line3& tr : t.lines)
      for (const Line3& l : four) EXPECT_LT(distance(tr, l), 1e-9);  // the routine still works
    double one = 0, both = 0;
    for (int i = 0; i < 200; ++i) {
      const Line3 ray = ray_of(cam, timing, motion, random_pixel(rng, cam));
      const double d0 = distance(ray, t.lines[0]), d1 = distance(ray, t.lines[1]);
      one = std::max(one, std::max(d0, d1));
      both = std::max(both, std::min(d0, d1));
    }
    res.misses_one = std::min(res.misses_one, one);
    res.misses_both = std::min(res.misses_both, both);
  }
  return res;
}

}  // namespace

TEST(CrossedSlits, RotationBreaksTheCrossedSlits) {
  // The paper's Figure (right): with w != 0 no two lines meet all rays. 640x480, fy = 500,
  // line delay 1/(480*30) s, |v| = 5 m/s, |w| ~ 1 rad/s: rays miss the transversals of any
  // four rays by a tenth of a millimetre or more, against ~1e-14 m of rounding for w = 0.
  const CameraModel cam = skewed_camera();
  std::mt19937 rng(11);
  Twist tw;
  tw.v = {3, -4, 0};
  double one = 1e300, both = 1e300;
  for (const Vector3d& w : {Vector3d(0, 0, 1), Vector3d(0.6, -0.8, 0.5)}) {
    tw.w = w;
    EXPECT_FALSE(crossed_slits(cam, timings()[0], tw).has_value());
    const LinearisedMotion lin(tw);
    const ScrewMotion screw(tw);
    for (const RowTiming& timing : {timings()[0], timings()[1]}) {
      for (const CameraMotion* m : both_motions(lin, screw)) {
        const BreakResult b = crossed_slits_break(cam, timing, *m, rng);
        EXPECT_GE(b.with_two, 10);
        EXPECT_GT(b.misses_one, 1e-4);
        one = std::min(one, b.misses_one);
        // The linearised roll keeps one slit (next test); otherwise rays miss both.
        if (m == &lin && w.head<2>().isZero()) continue;
        EXPECT_GT(b.misses_both, 1e-5);
        both = std::min(both, b.misses_both);
      }
    }
  }
  RecordProperty("smallest_miss_one", sci(one));
  RecordProperty("smallest_miss_both", sci(both));
}

TEST(CrossedSlits, LinearisedRollKeepsOneSlit) {
  // With the paper's linearised P(t) and w = (0, 0, wz), the plane of the rays of one row,
  // (y + v0_n z) + t (wz x + vy - r_n z) = 0, is linear in t: the row planes form a pencil
  // and every ray meets its axis { y = -v0_n z, r_n z = vy + wz x } (slit 2 when wz = 0).
  // Only the other slit is lost (previous test). The exact screw motion loses both.
  const CameraModel cam = skewed_camera();
  std::mt19937 rng(12);
  double worst = 0, screw_best = 1e300;
  for (const RowTiming& timing : timings()) {
    const RawRate raw = raw_rate(timing);
    const double r_n = raw.r / cam.fy, v0_n = (raw.v0 + cam.cy) / cam.fy;
    for (int k = 0; k < 5; ++k) {
      Twist tw = random_translation(rng);
      tw.w = {0, 0, 1};
      // Two points of the axis: x = 0 and x = 1.
      const Vector3d p0(0, -v0_n * tw.v.y() / r_n, tw.v.y() / r_n);
      const Vector3d p1(1, -v0_n * (tw.v.y() + 1) / r_n, (tw.v.y() + 1) / r_n);
      const Line3 axis = Line3::through(p0, p1 - p0);
      const LinearisedMotion lin(tw);
      const ScrewMotion screw(tw);
      double screw_worst = 0;
      for (int i = 0; i < 100; ++i) {
        const Vector2d px = random_pixel(rng, cam);
        worst = std::max(worst, distance(ray_of(cam, timing, lin, px), axis));
        screw_worst = std::max(screw_worst, distance(ray_of(cam, timing, screw, px), axis));
      }
      screw_best = std::min(screw_best, screw_worst);
    }
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_GT(screw_best, 1e-7);  // second order in wz t: small but far above rounding
  RecordProperty("worst_linearised_axis_distance", sci(worst));
  RecordProperty("smallest_screw_axis_miss", sci(screw_best));
}
