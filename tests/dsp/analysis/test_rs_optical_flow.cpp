// Rolling-shutter optical flow, eq. (6), against independent ground truth:
// finite differences of the exact model in the frame start t0. Shifting the frame start by h
// is the same as moving the static point to X' = ScrewMotion(tw).at(h) * X and projecting it
// with project_screw (the screw motion is a one-parameter group), so
//     qdot ~ (q(+h) - q(-h)) / (2h),
// here Richardson-extrapolated from h and 2h (h = 1e-5 s): the truncation error drops to
// O(h^4) and the rounding error (~1e-13 px / h) stays near 1e-8 px/s. Measured agreement
// ~1e-10 relative; the figures are in docs/optical-flow.md.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "dsp/analysis/rs_optical_flow.hpp"
#include "dsp/geometry/rs_projection.hpp"
#include "tests/support/random_twist.hpp"

using namespace rsd::dsp;
using Eigen::Vector2d;
using Eigen::Vector3d;
using rsd::test::random_twist;

namespace {

constexpr double kH = 1e-5;  // finite-difference step in the frame start, seconds
// Absolute noise floor of the finite differences, px/s. ScrewMotion::at evaluates
// (1 - cos th)/th^2 in closed form from th = 1e-5 rad up, where cancellation costs ~eps/th^2
// (~1e-6) relative: ~1e-13 m on the translation, ~1e-10 px on q(t0), ~1e-5 px/s after
// dividing by 2h. Measured worst 2.7e-6 px/s (a fronto-parallel case with wz t_c ~ 1e-5).
constexpr double kFdFloor = 2e-5;

struct Case {
  std::string name;
  CameraModel cam;
  RowTiming timing;
  CaptureWindow win;
};

Case make_case(std::string name, const CameraModel& cam, const RowTiming& rt) {
  return {std::move(name), cam, rt, default_capture_window(rt)};
}

// Both readout directions, fx != fy, a readout shorter than the frame, a sensor whose first
// row is mid-image (v0 != 0, != -(H-1)).
std::vector<Case> cases() {
  std::vector<Case> c;
  CameraModel vga;  // 640x480, f = 500
  c.push_back(make_case("vga-ttb-30", vga, RowTiming::full_frame(480, 30)));
  c.push_back(make_case("vga-btt-15", vga, RowTiming::full_frame(480, 15, Readout::BottomToTop)));
  CameraModel hd;
  hd.width = 1920, hd.height = 1080, hd.fx = 1329.75, hd.fy = 1340.0, hd.cx = 959.5, hd.cy = 539.5;
  RowTiming hd_t = RowTiming::full_frame(1080, 30);
  hd_t.line_delay_s = 0.8 / (1080 * 30);
  c.push_back(make_case("hd-ttb-blanking", hd, hd_t));
  CameraModel aniso = vga;
  aniso.fx = 610, aniso.fy = 480, aniso.cx = 300.25, aniso.cy = 250.75;
  RowTiming mid = RowTiming::full_frame(480, 25, Readout::BottomToTop);
  mid.first_row = 300;
  c.push_back(make_case("aniso-btt-first-row-300", aniso, mid));
  return c;
}

// A point a static camera would see inside the image, at depth z.
Vector3d random_point(const CameraModel& cam, std::mt19937& rng, double zmin, double zmax) {
  std::uniform_real_distribution<double> u(0, cam.width - 1), v(0, cam.height - 1), z(zmin, zmax);
  const double zz = z(rng);
  return zz * Vector3d((u(rng) - cam.cx) / cam.fx, (v(rng) - cam.cy) / cam.fy, 1.0);
}

// d/dt0 of the rolling-shutter image q(t0) (an RsProjection for frame start t0): central
// differences with steps h and 2h, Richardson-extrapolated, (4 D(h) - D(2h)) / 3, which cancels
// the h^2 term. nullopt unless all four projections exist and follow the same root.
template <class Q>
std::optional<Vector2d> derivative(const Q& q, double h) {
  auto central = [&](double step) -> std::optional<Vector2d> {
    const RsProjection a = q(step), b = q(-step);
    if (!a.ok() || !b.ok() || std::abs(a.t_c - b.t_c) > 1e-3) return std::nullopt;
    return Vector2d((a.pixel - b.pixel) / (2 * step));
  };
  const auto d1 = central(h), d2 = central(2 * h);
  if (!d1 || !d2) return std::nullopt;
  return Vector2d((4 * *d1 - *d2) / 3);
}

// Ground truth for the exact model: frame start t0 <=> static point moved to at(t0) * X.
std::optional<Vector2d> fd_flow(const Case& c, const Twist& tw, const Vector3d& X, double h = kH) {
  const ScrewMotion m(tw);
  return derivative([&](double t0) { return project_screw(c.cam, c.timing, tw, m.at(t0) * X, c.win); }, h);
}

// What the analytic formula is given: the rolling-shutter pixel and the depth at capture.
struct Seen {
  Vector2d pixel;
  double depth;
};
std::optional<Seen> seen(const Case& c, const Twist& tw, const Vector3d& X) {
  const RsProjection p = project_screw(c.cam, c.timing, tw, X, c.win);
  if (!p.ok()) return std::nullopt;
  return Seen{p.pixel, (ScrewMotion(tw).at(p.t_c) * X).z()};
}

// A static point (camera frame at t0 = 0) that the exact model captures at `px` with depth `z`
// at capture: the row fixes t_c, undo the motion up to t_c. nullopt if an earlier root exists.
std::optional<Vector3d> point_seen_at(const Case& c, const Twist& tw, const Vector2d& px, double z) {
  const auto ray = c.cam.ray(px);
  if (!ray) return std::nullopt;
  const Vector3d X = ScrewMotion(tw).at(c.timing.row_time(px.y())).inverse() * (z * *ray);
  const RsProjection p = project_screw(c.cam, c.timing, tw, X, c.win);
  if (!p.ok() || (p.pixel - px).norm() > 1e-7) return std::nullopt;
  return X;
}

Vector2d to_normalised(const CameraModel& cam, const Vector2d& px) {
  return {(px.x() - cam.cx) / cam.fx, (px.y() - cam.cy) / cam.fy};
}
Vector2d from_normalised(const CameraModel& cam, const Vector2d& xn) {
  return {cam.fx * xn.x() + cam.cx, cam.fy * xn.y() + cam.cy};
}
Vector2d to_pixels_per_s(const CameraModel& cam, const Vector2d& f) {
  return {cam.fx * f.x(), cam.fy * f.y()};
}

// The exact flow against finite differences over random points and twists; returns the
// worst mismatches seen. Tolerance: 1e-8 relative + kFdFloor.
struct Worst {
  double rel = 0, abs = 0;
};
Worst check_exact_flow(const std::vector<Case>& cs, const Vector3d& vmask, const Vector3d& wmask,
                        unsigned seed) {
  std::mt19937 rng(seed);
  Worst worst;
  for (const Case& c : cs) {
    int checked = 0;
    const int trials = 300;
    for (int i = 0; i < trials; ++i) {
      const Vector3d X = random_point(c.cam, rng, 1.0, 20.0);
      const Twist tw = random_twist(rng, vmask, wmask, 6.0, 3.0);
      const auto s = seen(c, tw, X);
      const auto fd = fd_flow(c, tw, X);
      if (!s || !fd) continue;
      const auto flow = rs_optical_flow(c.cam, c.timing, tw, s->pixel, s->depth);
      if (!flow) {
        ADD_FAILURE() << c.name << ": no flow at a captured point";
        continue;
      }
      const double err = (*flow - *fd).norm();
      EXPECT_LE(err, 1e-8 * flow->norm() + kFdFloor)
          << c.name << " flow " << flow->transpose() << " fd " << fd->transpose();
      worst.rel = std::max(worst.rel, err / flow->norm());
      worst.abs = std::max(worst.abs, err);
      ++checked;
    }
    EXPECT_GT(checked, trials * 9 / 10) << c.name;  // not vacuous
  }
  return worst;
}

// The paper's setting with K: readout starts at the principal point's row (v0_n = 0).
Case paper_case(Readout dir, double fx, double fy) {
  CameraModel cam;
  cam.fx = fx, cam.fy = fy, cam.cx = 320, cam.cy = 240;
  RowTiming rt = RowTiming::full_frame(480, 30, dir);
  rt.first_row = 240;  // v0 = -240 = -cy: v0_n = (v0 + cy) / fy = 0
  return make_case("paper-K", cam, rt);
}

}  // namespace

TEST(RsOpticalFlow, PerspectiveFlowIsTheDerivativeOfThePinholeProjection) {
  std::mt19937 rng(11);
  const Case c = cases()[2];  // fx != fy
  for (int i = 0; i < 200; ++i) {
    const Vector3d X = random_point(c.cam, rng, 0.5, 20.0);
    const Twist tw = random_twist(rng, {1, 1, 1}, {1, 1, 1}, 6.0, 3.0);
    const ScrewMotion m(tw);
    const double h = 1e-6;
    const Vector2d fd = (c.cam.project(m.at(h) * X).value() - c.cam.project(m.at(-h) * X).value()) / (2 * h);
    const Vector2d f = perspective_flow(c.cam, tw, c.cam.project(X).value(), X.z());
    EXPECT_LE((f - fd).norm(), 1e-7 * f.norm() + 1e-5);
  }
  // The paper's fronto-parallel special case, K = I: (vx/z - wz v, vy/z + wz u).
  CameraModel unit;
  unit.fx = unit.fy = 1, unit.cx = unit.cy = 0;
  Twist fp;
  fp.v = {0.7, -0.4, 0};
  fp.w = {0, 0, 1.3};
  const Vector2d f = perspective_flow(unit, fp, Vector2d(0.2, -0.1), 2.0);
  EXPECT_NEAR(f.x(), 0.35 + 0.13, 1e-15);
  EXPECT_NEAR(f.y(), -0.2 + 0.26, 1e-15);
}

TEST(RsOpticalFlow, ExactFlowMatchesFiniteDifferencesForGeneralMotion) {
  const Worst worst = check_exact_flow(cases(), {1, 1, 1}, {1, 1, 1}, 1);
  std::printf("  general twist: worst |flow - FD| = %.2e relative, %.2e px/s\n", worst.rel, worst.abs);
}

TEST(RsOpticalFlow, ExactFlowMatchesFiniteDifferencesForFrontoParallelMotion) {
  const Worst worst = check_exact_flow(cases(), {1, 1, 0}, {0, 0, 1}, 2);
  std::printf("  fronto-parallel: worst |flow - FD| = %.2e relative, %.2e px/s\n", worst.rel, worst.abs);
}

TEST(RsOpticalFlow, ExactFlowHonoursLensDistortion) {
  // The constraint is on the recorded (distorted) row, and so is the flow.
  std::vector<Case> cs = cases();
  cs.resize(2);
  for (Case& c : cs) c.cam.dist = {-0.25, 0.08, 0.001, -0.0005, 0.0};
  const Worst worst = check_exact_flow(cs, {1, 1, 1}, {1, 1, 1}, 3);
  std::printf("  with distortion: worst |flow - FD| = %.2e relative, %.2e px/s\n", worst.rel, worst.abs);
  // With distortion the pinhole motion field is not the recorded pixel's velocity.
  const Case& c = cs[0];
  Twist tw;
  tw.w = {0.3, 0.5, 0.0};
  const Vector2d px(40, 400);
  const Vector2d pinhole = perspective_flow(c.cam, tw, px, 3.0);
  const Vector2d rs = rs_optical_flow(c.cam, c.timing, tw, px, 3.0).value();
  EXPECT_GT((rs - pinhole).norm(), 0.05 * pinhole.norm());
}

TEST(RsOpticalFlow, PaperFormulaIsExactWithoutRotationAboutTheOpticalAxis) {
  // wz = 0, v = (vx, vy, 0): the printed eq. (6) reduces to r/(r - vdot_p) qdot_p.
  // In the paper's own units (K = I, normalised coordinates, r_n = 28.8 /s) ...
  CameraModel unit;
  unit.width = unit.height = 1;
  unit.fx = unit.fy = 1, unit.cx = unit.cy = 0;
  RowTiming rt = RowTiming::full_frame(1, 28.8);  // r = 28.8 "rows" (normalised units) per second
  ASSERT_DOUBLE_EQ(rt.v0(), 0.0);
  std::vector<Case> cs = {{"K=I", unit, rt, {-0.05, 0.05}}};
  // ... and converted from pixels (fx != fy), both readout directions.
  cs.push_back(paper_case(Readout::TopToBottom, 520, 500));
  cs.push_back(paper_case(Readout::BottomToTop, 520, 500));
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> un(-0.4, 0.4), zd(1, 20);
  double worst = 0;
  for (const Case& c : cs) {
    const double r_n = c.timing.r() / c.cam.fy;
    int checked = 0;
    for (int i = 0; i < 200; ++i) {
      const Twist tw = random_twist(rng, {1, 1, 0}, {0, 0, 0}, 6.0, 0.0);
      const Vector2d px = from_normalised(c.cam, Vector2d(un(rng), un(rng)));
      const double z = zd(rng);
      const auto X = point_seen_at(c, tw, px, z);
      const auto fd = X ? fd_flow(c, tw, *X) : std::nullopt;
      if (!fd) continue;
      const Vector2d paper = to_pixels_per_s(c.cam, rs_optical_flow_paper(to_normalised(c.cam, px), z, tw, r_n));
      const Vector2d ours = rs_optical_flow(c.cam, c.timing, tw, px, z).value();
      EXPECT_LE((paper - *fd).norm(), 1e-8 * fd->norm() + kFdFloor) << c.name;
      EXPECT_LE((paper - ours).norm(), 1e-12 * ours.norm()) << c.name;
      worst = std::max(worst, (paper - *fd).norm() / fd->norm());
      ++checked;
    }
    EXPECT_GT(checked, 180) << c.name;
  }
  std::printf("  wz = 0: worst relative |printed - FD| / |FD| = %.2e\n", worst);
}

TEST(RsOpticalFlow, PaperFormulaIsWrongWithRotationAboutTheOpticalAxis) {
  // Documented case (docs/optical-flow.md): VGA, f = 500, principal point (320, 240), readout
  // top to bottom starting at row 240 (v0_n = 0), r = 14400 rows/s, r_n = 28.8 /s. The point
  // is seen at the rolling-shutter pixel (420, 390), i.e. (u, v) = (0.2, 0.3), at depth z = 2 m,
  // the camera moving with v = (2, 0, 0) m/s, w = (0, 0, 1) rad/s. By hand:
  //   (udot_p, vdot_p) = (vx/z - wz v, vy/z + wz u) = (0.7, 0.2) /s
  //   exact:   r/(r - vdot_p) (udot_p, vdot_p) = (28.8/28.6)(0.7, 0.2)        -> x500 px
  //   printed: r z / (v vx wz + r z (r - vdot_p)) = 57.6 / 1647.96,
  //            (r udot_p + wz v vdot_p, r vdot_p + wz v udot_p) = (20.22, 5.97) -> x500 px
  const Case c = paper_case(Readout::TopToBottom, 500, 500);
  ASSERT_DOUBLE_EQ(c.timing.r() / c.cam.fy, 28.8);
  Twist tw;
  tw.v = {2, 0, 0};
  tw.w = {0, 0, 1};
  const Vector2d px(420, 390);
  const double z = 2.0;
  const auto X = point_seen_at(c, tw, px, z);
  ASSERT_TRUE(X);
  const Vector2d fd = fd_flow(c, tw, *X).value();
  const Vector2d fd2 = fd_flow(c, tw, *X, 2 * kH).value();
  const double fd_err = (fd - fd2).norm();  // estimate of the FD error, independent of any formula

  const Vector2d exact_hand = 500.0 * (28.8 / 28.6) * Vector2d(0.7, 0.2);  // (352.4476, 100.6993)
  const Vector2d printed_hand = 500.0 * (57.6 / 1647.96) * Vector2d(20.22, 5.97);  // (353.3678, 104.3326)
  EXPECT_NEAR(exact_hand.x(), 352.44755244755, 1e-9);
  EXPECT_NEAR(exact_hand.y(), 100.69930069930, 1e-9);
  EXPECT_NEAR(printed_hand.x(), 353.36780018933, 1e-9);
  EXPECT_NEAR(printed_hand.y(), 104.33262943275, 1e-9);

  const Vector2d ours = rs_optical_flow(c.cam, c.timing, tw, px, z).value();
  const Vector2d printed = to_pixels_per_s(c.cam, rs_optical_flow_paper(to_normalised(c.cam, px), z, tw, 28.8));
  EXPECT_LE((ours - exact_hand).norm(), 1e-10);
  EXPECT_LE((printed - printed_hand).norm(), 1e-10);

  // Ground truth sides with the corrected formula ...
  EXPECT_LE((fd - exact_hand).norm(), 1e-5);
  EXPECT_LT(fd_err, 1e-5);
  // ... and the printed one is off by (0.920, 3.633) px/s, 3.6 % of the vertical flow (and
  // larger than the whole rolling-shutter correction, ours - perspective = (2.448, 0.699) px/s).
  const Vector2d miss = printed - fd;
  EXPECT_NEAR(miss.x(), 0.92024774, 1e-5);
  EXPECT_NEAR(miss.y(), 3.63332873, 1e-5);
  EXPECT_GT(miss.norm(), 1e5 * std::max(fd_err, (fd - ours).norm()));
  const Vector2d persp = perspective_flow(c.cam, tw, px, z);
  EXPECT_GT(miss.norm(), (ours - persp).norm());
  std::printf("  printed - FD = (%.6f, %.6f) px/s; FD error estimate %.1e px/s; FD - ours %.1e px/s\n",
              miss.x(), miss.y(), fd_err, (fd - ours).norm());
}

TEST(RsOpticalFlow, PaperFormulaErrorIsFirstOrderInWz) {
  // A consistent first-order approximation would leave an O(wz^2) error; the printed formula
  // leaves O(wz): (printed - exact) / wz tends to a non-zero limit, which to first order is
  //   rho (v / r) [ (vdot_p, udot_p) - (udot_p, vdot_p) vx / (z (r - vdot_p)) ],
  // rho = r / (r - vdot_p), evaluated at wz = 0 (t_c = v / r is the capture time).
  const Case c = paper_case(Readout::TopToBottom, 500, 500);
  const double r = 28.8, z = 3.0;
  const Vector2d uv(-0.25, 0.4);
  const Vector2d px = from_normalised(c.cam, uv);
  Twist tw;
  tw.v = {1.5, 2.0, 0};
  const double ud = tw.v.x() / z, vd = tw.v.y() / z, rho = r / (r - vd);
  const Vector2d limit =
      rho * (uv.y() / r) * (Vector2d(vd, ud) - Vector2d(ud, vd) * tw.v.x() / (z * (r - vd)));
  ASSERT_GT(limit.norm(), 1e-3);
  for (double wz : {1e-2, 1e-3, 1e-4}) {
    tw.w = {0, 0, wz};
    const Vector2d printed = rs_optical_flow_paper(uv, z, tw, r);
    const Vector2d exact = rs_optical_flow(c.cam, c.timing, tw, px, z).value() / 500.0;
    EXPECT_LE(((printed - exact) / wz - limit).norm(), 20 * wz * limit.norm()) << "wz " << wz;
    // One finite-difference spot check that the exact side is the model's flow.
    const auto X = point_seen_at(c, tw, px, z);
    ASSERT_TRUE(X);
    EXPECT_LE((fd_flow(c, tw, *X).value() - 500.0 * exact).norm(), kFdFloor);
  }
}

TEST(RsOpticalFlow, PaperProcedureOnTheLinearisedModelGivesTheSignCorrectedFormula) {
  // The paper differentiates its linearised fronto-parallel model (Table 1 case a). Doing that
  // by finite differences -- the frame start shifted by h in P(t0 + t) = [(I + (t0 + t)[w]x) | v (t0 + t)]
  // -- reproduces the printed formula except for the sign of wz v udot_p in its second row.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> un(-0.45, 0.45), zd(1, 20);
  double worst_lin = 0, worst_printed = 0;
  for (Readout dir : {Readout::TopToBottom, Readout::BottomToTop}) {
    const Case c = paper_case(dir, 520, 500);
    const double r_n = c.timing.r() / c.cam.fy;
    int checked = 0;
    for (int i = 0; i < 200; ++i) {
      const Twist tw = random_twist(rng, {1, 1, 0}, {0, 0, 1}, 6.0, 3.0);
      const Vector3d X = zd(rng) * Vector3d(un(rng), un(rng), 1.0);
      const RsProjection p = project_fronto_parallel(c.cam, c.timing, tw, X, c.win);
      auto shifted = [&](double t0) {
        return FunctionMotion([tw, t0](double t) { return LinearisedMotion(tw).at(t0 + t); });
      };
      const auto fd_or = derivative(
          [&](double t0) { return project_trajectory(c.cam, c.timing, shifted(t0), X, c.win); }, kH);
      if (!p.ok() || !fd_or) continue;
      const Vector2d fd = *fd_or;
      const Vector2d uv = to_normalised(c.cam, p.pixel);  // depth stays X.z() in case a
      const Vector2d lin = to_pixels_per_s(c.cam, rs_optical_flow_linearised(uv, X.z(), tw, r_n));
      const Vector2d printed = to_pixels_per_s(c.cam, rs_optical_flow_paper(uv, X.z(), tw, r_n));
      EXPECT_LE((lin - fd).norm(), 1e-8 * fd.norm() + kFdFloor);
      EXPECT_NEAR(lin.x(), printed.x(), 1e-12 * fd.norm());  // the first row is as printed
      worst_lin = std::max(worst_lin, (lin - fd).norm() / fd.norm());
      worst_printed = std::max(worst_printed, (printed - fd).norm() / fd.norm());
      ++checked;
    }
    EXPECT_GT(checked, 180);
  }
  EXPECT_GT(worst_printed, 1e-2);
  std::printf("  linearised model: worst relative |corrected - FD| %.2e, |printed - FD| %.2e\n",
              worst_lin, worst_printed);
}

TEST(RsOpticalFlow, TendsToPerspectiveFlowAsRowRateGrows) {
  // rs - perspective = perspective * vdot_p / (r - vdot_p): tenfold r, tenfold smaller.
  const CameraModel cam;
  Twist tw;
  tw.v = {1.0, -2.0, 1.5};
  tw.w = {0.5, -0.8, 1.2};
  const Vector2d px(400, 300);
  const double z = 3.0;
  const Vector2d persp = perspective_flow(cam, tw, px, z);
  double prev = -1;
  for (double r : {1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10}) {
    RowTiming rt;
    rt.line_delay_s = 1.0 / r;
    const double diff = (rs_optical_flow(cam, rt, tw, px, z).value() - persp).norm();
    if (prev > 0) {
      EXPECT_NEAR(diff / prev, 0.1, 0.01) << "r " << r;
    }
    prev = diff;
  }
  EXPECT_LT(prev, 1e-6 * persp.norm());
  // The ground truth agrees: finite differences of the exact model approach the pinhole flow.
  const Vector3d X = z * cam.ray(px).value();
  for (double r : {1e6, 1e8}) {
    RowTiming rt;
    rt.line_delay_s = 1.0 / r;
    const Case c = make_case("fast", cam, rt);
    const auto s = seen(c, tw, X);
    ASSERT_TRUE(s);
    const Vector2d fd = fd_flow(c, tw, X).value();
    EXPECT_LE((fd - rs_optical_flow(cam, rt, tw, s->pixel, s->depth).value()).norm(), 1e-6 * fd.norm());
    EXPECT_LE((fd - perspective_flow(cam, tw, cam.project(X).value(), z)).norm(), 3e3 / r * fd.norm());
  }
}

TEST(RsOpticalFlow, DegenerateWhenTheImageRunsWithTheReadout) {
  // vdot_p = r: the image moves down exactly as fast as the readout; ds/dt0 is undefined.
  const CameraModel cam;
  const RowTiming rt = RowTiming::full_frame(480, 30);
  const Vector2d px(300, 200);
  const double z = 2.0;
  Twist tw;
  tw.v.y() = rt.r() * z / cam.fy;  // vdot_p = fy vy / z = r
  EXPECT_FALSE(rs_optical_flow(cam, rt, tw, px, z).has_value());
  tw.v.y() *= 1 + 1e-12;
  EXPECT_FALSE(rs_optical_flow(cam, rt, tw, px, z).has_value());
  tw.v.y() = rt.r() * z / cam.fy * (1 - 1e-6);  // near but not at: finite and huge (rho ~ 1e6)
  const auto near = rs_optical_flow(cam, rt, tw, px, z);
  ASSERT_TRUE(near);
  EXPECT_NEAR(near->y() / rt.r(), 1e6, 2.0);
  // Bottom-to-top: degenerate at vdot_p = r < 0.
  const RowTiming up = RowTiming::full_frame(480, 30, Readout::BottomToTop);
  tw = {};
  tw.v.y() = up.r() * z / cam.fy;
  EXPECT_FALSE(rs_optical_flow(cam, up, tw, px, z).has_value());
  // No flow for points not in front of the camera.
  EXPECT_FALSE(rs_optical_flow(cam, rt, Twist{}, px, 0.0).has_value());
  EXPECT_FALSE(rs_optical_flow(cam, rt, Twist{}, px, -1.0).has_value());
  // The printed formula has no guard: its denominator r z (r - vdot_p) + v vx wz vanishes.
  Twist t2;
  t2.v.y() = 28.8 * z;
  EXPECT_FALSE(rs_optical_flow_paper(Vector2d(0.1, 0.2), z, t2, 28.8).allFinite());
}
