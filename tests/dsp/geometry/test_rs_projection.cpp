// Every row of the paper's Table 1 against a brute-force solver of the rolling-shutter
// constraint (dense scan plus bisection), the perspective limit r -> inf, and the
// near-degenerate cases that must say "no solution".
#include <gtest/gtest.h>

#include <random>

#include "dsp/geometry/rs_projection.hpp"
#include "tests/support/brute_force.hpp"
#include "tests/support/random_twist.hpp"
#include "tests/support/sanitizer.hpp"

using namespace rsd::dsp;
using rsd::test::brute_force_project;
using Eigen::Vector2d;
using Eigen::Vector3d;
using rsd::test::random_twist;

namespace {

// The linearised P(t) written out independently of LinearisedMotion.
auto linearised(const Twist& tw) {
  return FunctionMotion([tw](double t) {
    Eigen::Affine3d a = Eigen::Affine3d::Identity();
    a.linear() << 1, -t * tw.w.z(), t * tw.w.y(), t * tw.w.z(), 1, -t * tw.w.x(), -t * tw.w.y(),
        t * tw.w.x(), 1;
    a.translation() = t * tw.v;
    return a;
  });
}

struct Scenario {
  CameraModel cam;
  RowTiming timing;
};

std::vector<Scenario> scenarios() {
  std::vector<Scenario> s;
  CameraModel vga;  // 640x480, f = 500
  s.push_back({vga, RowTiming::full_frame(480, 30)});
  s.push_back({vga, RowTiming::full_frame(480, 15, Readout::BottomToTop)});
  CameraModel hd;
  hd.width = 1920, hd.height = 1080, hd.fx = 1329.75, hd.fy = 1340.0, hd.cx = 959.5, hd.cy = 539.5;
  RowTiming hd_t = RowTiming::full_frame(1080, 30);
  hd_t.line_delay_s = 0.8 / (1080 * 30);  // readout shorter than the frame: blanking
  s.push_back({hd, hd_t});
  return s;
}

// A point that a static camera would see inside the image, at depth z.
Vector3d random_point(const CameraModel& cam, std::mt19937& rng, double zmin, double zmax) {
  std::uniform_real_distribution<double> u(0, cam.width - 1), v(0, cam.height - 1), z(zmin, zmax);
  const double zz = z(rng);
  const Vector2d px(u(rng), v(rng));
  return zz * Vector3d((px.x() - cam.cx) / cam.fx, (px.y() - cam.cy) / cam.fy, 1.0);
}

using Solver = RsProjection (*)(const CameraModel&, const RowTiming&, const Twist&, const Vector3d&);

// Compares a closed-form or root-finding case with brute force over random points and
// velocities; both must agree on existence, and on the pixel to 1e-6 px where it exists.
void check_against_brute_force(Solver solve, bool exact_motion, const Vector3d& vmask,
                               const Vector3d& wmask, unsigned seed) {
  std::mt19937 rng(seed);
  for (const auto& sc : scenarios()) {
    const CaptureWindow win = default_capture_window(sc.timing);
    // A sanitizer or qemu makes the brute force ten to thirty times slower: fewer points there.
    int solved = 0, trials = rsd::test::kSlowBuild ? 50 : 400;
    for (int i = 0; i < trials; ++i) {
      const Vector3d X = random_point(sc.cam, rng, 0.5, 20);
      const Twist tw = random_twist(rng, vmask, wmask, 6.0, 3.0);
      const RsProjection p = solve(sc.cam, sc.timing, tw, X);
      const auto bf = exact_motion
                          ? brute_force_project(sc.cam, sc.timing, ScrewMotion(tw), X, win.t_begin, win.t_end)
                          : brute_force_project(sc.cam, sc.timing, linearised(tw), X, win.t_begin, win.t_end);
      ASSERT_EQ(p.ok(), bf.has_value()) << "point " << X.transpose() << " status " << to_string(p.status);
      if (!bf) continue;
      ++solved;
      EXPECT_NEAR((p.pixel - bf->pixel).norm(), 0.0, 1e-6) << "point " << X.transpose();
      EXPECT_NEAR(p.t_c, bf->t_c, 1e-9);
      // The solution satisfies eq. (3): its row is the row read at t_c.
      EXPECT_NEAR(p.pixel.y(), sc.timing.row_at(p.t_c), 1e-6);
    }
    EXPECT_GT(solved, trials * 9 / 10);  // the comparison is not vacuous
  }
}

}  // namespace

TEST(RsProjection, CaseA_FrontoParallelClosedFormMatchesBruteForce) {
  check_against_brute_force(project_fronto_parallel, false, {1, 1, 0}, {0, 0, 1}, 1);
}

TEST(RsProjection, CaseA_IsExactWhenWIsZero) {
  // With w = 0 the linearisation is exact, so (a) must agree with the exact screw motion.
  check_against_brute_force(project_fronto_parallel, true, {1, 1, 0}, {0, 0, 0}, 2);
}

TEST(RsProjection, CaseB_AxialQuadraticMatchesBruteForce) {
  check_against_brute_force(project_axial, false, {0, 0, 1}, {0, 0, 0}, 3);
  check_against_brute_force(project_axial, true, {0, 0, 1}, {0, 0, 0}, 4);  // exact too
}

TEST(RsProjection, CaseC_GeneralLinearisedQuadraticMatchesBruteForce) {
  check_against_brute_force(project_linearised, false, {1, 1, 1}, {1, 1, 1}, 5);
}

TEST(RsProjection, CaseD_ScrewRootFinderMatchesBruteForce) {
  check_against_brute_force(project_screw, true, {1, 1, 1}, {1, 1, 1}, 6);
}

namespace {

// project_screw against the brute-force scan for random points and twists through `sc`'s lens;
// returns how many had a solution.
int expect_screw_matches_brute_force(const Scenario& sc, unsigned seed) {
  std::mt19937 rng(seed);
  const CaptureWindow win = default_capture_window(sc.timing);
  int solved = 0;
  for (int i = 0; i < 200; ++i) {
    const Vector3d X = random_point(sc.cam, rng, 1, 10);
    const Twist tw = random_twist(rng, {1, 1, 1}, {1, 1, 1}, 4, 2);
    const auto p = project_screw(sc.cam, sc.timing, tw, X);
    const auto bf = brute_force_project(sc.cam, sc.timing, ScrewMotion(tw), X, win.t_begin, win.t_end);
    EXPECT_EQ(p.ok(), bf.has_value());
    if (!bf || !p.ok()) continue;
    ++solved;
    EXPECT_NEAR((p.pixel - bf->pixel).norm(), 0.0, 1e-6);
  }
  return solved;
}

}  // namespace

TEST(RsProjection, CaseD_HonoursLensDistortion) {
  Scenario sc = scenarios()[0];
  sc.cam.dist = {-0.25, 0.08, 0.001, -0.0005, 0.0};
  EXPECT_GT(expect_screw_matches_brute_force(sc, 7), 180);
  // The closed forms do not model distortion and must say so.
  EXPECT_EQ(project_linearised(sc.cam, sc.timing, Twist{}, Vector3d(0, 0, 1)).status,
            RsStatus::UnsupportedMotion);
}

// The same root finder through a fisheye (pinhole-equi) lens: the constraint is the lens's too,
// and the closed forms, written for an undistorted pinhole, refuse it (an equidistant lens
// without terms still bends the image).
TEST(RsProjection, CaseD_HonoursAnEquidistantLens) {
  Scenario sc = scenarios()[0];
  sc.cam.dist = Distortion::equidistant(0.0469, -0.0135, 0.0021, -0.0003);
  EXPECT_GT(expect_screw_matches_brute_force(sc, 9), 150);
  sc.cam.dist = Distortion::equidistant(0, 0, 0, 0);
  EXPECT_EQ(project_linearised(sc.cam, sc.timing, Twist{}, Vector3d(0, 0, 1)).status, RsStatus::UnsupportedMotion);
}

TEST(RsProjection, CaseE_ArbitraryTrajectoryMatchesBruteForce) {
  // A trajectory no closed form covers: oscillating translation and a growing rotation.
  auto pose = [](double t) {
    Eigen::Affine3d g = Eigen::Affine3d::Identity();
    g.linear() = exp_so3(Vector3d(0.4 * std::sin(30 * t), 2.0 * t * t, 0.3 * t));
    g.translation() = Vector3d(0.2 * std::sin(25 * t), -1.5 * t + 0.1 * std::cos(40 * t) - 0.1, 3 * t * t);
    return g;
  };
  const FunctionMotion motion(pose);
  std::mt19937 rng(8);
  for (const auto& sc : scenarios()) {
    const CaptureWindow win = default_capture_window(sc.timing);
    int solved = 0;
    for (int i = 0; i < 200; ++i) {
      const Vector3d X = random_point(sc.cam, rng, 0.5, 10);
      const auto p = project_trajectory(sc.cam, sc.timing, motion, X);
      const auto bf = brute_force_project(sc.cam, sc.timing, motion, X, win.t_begin, win.t_end);
      ASSERT_EQ(p.ok(), bf.has_value());
      if (!bf) continue;
      ++solved;
      EXPECT_NEAR((p.pixel - bf->pixel).norm(), 0.0, 1e-6);
      EXPECT_NEAR(p.t_c, bf->t_c, 1e-9);
    }
    EXPECT_GT(solved, 180);
  }
}

TEST(RsProjection, NearDegenerateDenominatorGivesNoSolution) {
  // r z - v_y - w_z x -> 0: the point's image runs down with the readout and is never caught.
  const Scenario sc = scenarios()[0];
  const double r_n = sc.timing.r() / sc.cam.fy;
  const Vector3d X(0.3, -0.2, 2.0);
  for (double eps : {0.0, 1e-15, 1e-9, 1e-6, -1e-9}) {
    Twist tw;
    tw.w.z() = 0.7;
    tw.v.y() = r_n * X.z() - tw.w.z() * X.x() + eps;
    for (Solver s : {Solver(project_fronto_parallel), Solver(project_linearised), Solver(project_screw)}) {
      const auto p = s(sc.cam, sc.timing, tw, X);
      EXPECT_EQ(p.status, RsStatus::NoSolution) << "eps " << eps;
      EXPECT_FALSE(p.pixel.allFinite());
    }
  }
  // Slightly away from degeneracy a root exists but far outside the frame: still no solution.
  Twist tw;
  tw.v.y() = r_n * X.z() * (1 - 1e-4);
  EXPECT_EQ(project_fronto_parallel(sc.cam, sc.timing, tw, X).status, RsStatus::NoSolution);
}

TEST(RsProjection, PointBehindCameraIsReported) {
  const Scenario sc = scenarios()[0];
  EXPECT_EQ(project_fronto_parallel(sc.cam, sc.timing, Twist{}, Vector3d(0, 0, -1)).status,
            RsStatus::BehindCamera);
  EXPECT_EQ(project_screw(sc.cam, sc.timing, Twist{}, Vector3d(0, 0, -1)).status, RsStatus::BehindCamera);
}

TEST(RsProjection, CasesRejectMotionOutsideTheirAssumptions) {
  const Scenario sc = scenarios()[0];
  Twist tw;
  tw.v.z() = 1;
  EXPECT_EQ(project_fronto_parallel(sc.cam, sc.timing, tw, Vector3d(0, 0, 2)).status,
            RsStatus::UnsupportedMotion);
  tw = {};
  tw.w.x() = 1;
  EXPECT_EQ(project_axial(sc.cam, sc.timing, tw, Vector3d(0, 0, 2)).status, RsStatus::UnsupportedMotion);
}

TEST(RsProjection, EveryCaseTendsToPerspectiveAsRowRateGrows) {
  // The correction shrinks like 1/r: each tenfold r cuts it tenfold, and it vanishes in the limit.
  const CameraModel cam;
  const Vector3d X(0.8, 0.5, 3.0);
  Twist fp;  fp.v = {1.5, -2.0, 0};  fp.w = {0, 0, 1.2};
  Twist ax;  ax.v = {0, 0, 3.0};
  Twist gen; gen.v = {1.0, -2.0, 1.5}; gen.w = {0.5, -0.8, 1.2};
  const auto pose = [&](double t) { return ScrewMotion(gen).at(t); };
  const FunctionMotion traj(pose);
  const std::vector<std::pair<std::string, std::function<RsProjection(const RowTiming&)>>> cases = {
      {"a", [&](const RowTiming& rt) { return project_fronto_parallel(cam, rt, fp, X); }},
      {"b", [&](const RowTiming& rt) { return project_axial(cam, rt, ax, X); }},
      {"c", [&](const RowTiming& rt) { return project_linearised(cam, rt, gen, X); }},
      {"d", [&](const RowTiming& rt) { return project_screw(cam, rt, gen, X); }},
      {"e", [&](const RowTiming& rt) { return project_trajectory(cam, rt, traj, X); }},
  };
  const Vector2d pinhole = cam.project(X).value();
  for (const auto& [name, solve] : cases) {
    double prev = -1;
    for (double r : {1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10}) {
      RowTiming rt;
      rt.line_delay_s = 1.0 / r;
      const auto p = solve(rt);
      ASSERT_TRUE(p.ok()) << name << " r " << r;
      const double corr = (p.pixel - pinhole).norm();
      if (prev > 0) {
        EXPECT_NEAR(corr / prev, 0.1, 0.01) << name << " r " << r;
      }
      prev = corr;
    }
    EXPECT_LT(prev, 1e-4) << name;
  }
}

TEST(RsProjection, ReadoutDirectionChangesTheCaptureTime) {
  // The same point near the bottom of the image is read late top-to-bottom, early bottom-to-top.
  const CameraModel cam;
  const Vector3d X(0, 0.4, 1.0);  // image row 439.5
  const RowTiming down = RowTiming::full_frame(480, 30, Readout::TopToBottom);
  const RowTiming up = RowTiming::full_frame(480, 30, Readout::BottomToTop);
  const auto a = project_screw(cam, down, Twist{}, X);
  const auto b = project_screw(cam, up, Twist{}, X);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_NEAR(a.t_c, 439.5 * down.line_delay_s, 1e-12);
  EXPECT_NEAR(b.t_c, (479 - 439.5) * up.line_delay_s, 1e-12);
}
