// The pinhole model's domain of applicability: the paper's limit line against hand-computed
// numbers, and the general (exact, grid-maximised) bound against the closed form of
// eq. (4) maximised over the image by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "dsp/analysis/applicability.hpp"
#include "tests/support/sanitizer.hpp"

using namespace rsd::dsp;
using Eigen::Vector3d;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

CameraModel vga(double f = 500) {
  CameraModel c;  // 640 x 480, principal point centred
  c.fx = c.fy = f;
  return c;
}

Twist translation(double vx, double vy, double vz) {
  Twist t;
  t.v = Vector3d(vx, vy, vz);
  return t;
}

// Closed form of the largest correction for v = (0, v_y, 0), w = 0 (eq. (4)
// with K): a point on row v_p (perspective, t = 0) is captured at
//     t_c = ((v_p + v0) / fy) / (r_n - v_y / z),   r_n = r / fy,
// and moves by fy t_c v_y / z = (v_p + v0) v_y / (r_n z - v_y) pixels, straight down.
// |v_p + v0| is the number of rows between p and the first row read; it is largest
// (H - 1) on the row read last. Returns the magnitude there.
double closed_form_max_vy(const CameraModel& cam, const RowTiming& timing, double vy, double z) {
  const double r_n = timing.r() / cam.fy;
  const double rows_from_first = cam.height - 1;  // natural first row: top or bottom
  return std::abs(rows_from_first * vy / (r_n * z - vy));
}

}  // namespace

// (a) The paper's limit line z_min = |v_y| / (s_alpha r_n) = |v_y| fy^2 / |r|.
TEST(PaperBound, HandComputedValues) {
  const CameraModel cam = vga(500);
  const RowTiming t15 = RowTiming::full_frame(480, 15);
  ASSERT_DOUBLE_EQ(t15.r(), 7200.0);  // 480 rows * 15 fps
  EXPECT_NEAR(paper_min_depth(cam, t15, 1.0), 250000.0 / 7200.0, 1e-12);  // 34.722 m
  EXPECT_NEAR(paper_min_depth(cam, t15, -1.0), 250000.0 / 7200.0, 1e-12);
  EXPECT_NEAR(paper_min_depth(cam, t15, 2.5), 2.5 * 250000.0 / 7200.0, 1e-12);
  // Threshold of N pixels divides by N.
  EXPECT_NEAR(paper_min_depth(cam, t15, 1.0, 2.0), 125000.0 / 7200.0, 1e-12);
  // Direction of readout does not matter; half the frame rate doubles the depth.
  EXPECT_NEAR(paper_min_depth(cam, RowTiming::full_frame(480, 15, Readout::BottomToTop), 1.0),
              250000.0 / 7200.0, 1e-12);
  EXPECT_NEAR(paper_min_depth(cam, RowTiming::full_frame(480, 7.5), 1.0), 250000.0 / 3600.0,
              1e-12);
  // The paper's Figure 1 camera: hfov 40 deg, fy = 320 / tan(20 deg) = 879.19 px.
  const CameraModel fig1 = CameraModel::from_hfov(640, 480, 40 * M_PI / 180);
  const double fy = 320 / std::tan(20 * M_PI / 180);
  EXPECT_NEAR(paper_min_depth(fig1, RowTiming::full_frame(480, 3.75), 1.0), fy * fy / 1800, 1e-9);
  EXPECT_EQ(paper_min_depth(cam, t15, 0.0), 0.0);
  EXPECT_TRUE(std::isnan(paper_min_depth(cam, t15, 1.0, 0.0)));
}

TEST(Grid, ProportionalRowsIncludeCorners) {
  const ApplicabilityOptions o = grid_for(vga(), 33);
  EXPECT_EQ(o.grid_cols, 33);
  EXPECT_EQ(o.grid_rows, 25);
  const ApplicabilityOptions o2 = grid_for(vga(), 65);
  EXPECT_EQ(o2.grid_rows, 49);
}

// (b) For v = (0, v_y, 0), w = 0 the grid maximum equals the closed form on the last row
// read (the grid includes both borders).
TEST(GeneralBound, PureVyMatchesClosedFormMaximum) {
  CameraModel hd;
  hd.width = 1920, hd.height = 1080, hd.fx = 1329.75, hd.fy = 1340.0, hd.cx = 959.5, hd.cy = 539.5;
  RowTiming hd_t = RowTiming::full_frame(1080, 30);
  hd_t.line_delay_s = 0.8 / (1080 * 30);  // readout shorter than the frame
  struct Case {
    CameraModel cam;
    RowTiming timing;
    double vy, z;
  };
  const Case cases[] = {
      {vga(500), RowTiming::full_frame(480, 15), 1.0, 10.0},
      {vga(500), RowTiming::full_frame(480, 15), -1.0, 10.0},
      {vga(500), RowTiming::full_frame(480, 3.75), 2.0, 3.0},
      {vga(500), RowTiming::full_frame(480, 30, Readout::BottomToTop), 1.5, 4.0},
      {vga(500), RowTiming::full_frame(480, 30, Readout::BottomToTop), -1.5, 4.0},
      {CameraModel::from_hfov(640, 480, 40 * M_PI / 180), RowTiming::full_frame(480, 15), 0.7, 25.0},
      {hd, hd_t, 3.0, 8.0},
  };
  for (const auto& c : cases) {
    const ApplicabilityResult res = correction_bound(c.cam, c.timing, translation(0, c.vy, 0), c.z);
    const double expect = closed_form_max_vy(c.cam, c.timing, c.vy, c.z);
    SCOPED_TRACE(testing::Message() << "vy=" << c.vy << " z=" << c.z << " r=" << c.timing.r());
    EXPECT_EQ(res.no_solution, 0);
    EXPECT_NEAR(res.max_correction_px, expect, 1e-6);
    // Worst on the row read last, and the correction is vertical with the sign of v_y.
    const double last_row = c.timing.readout == Readout::TopToBottom ? c.cam.height - 1 : 0;
    EXPECT_DOUBLE_EQ(res.worst_pixel.y(), last_row);
    EXPECT_NEAR(res.worst_correction.x(), 0, 1e-9);
    EXPECT_GT(res.worst_correction.y() * c.vy, 0);
    EXPECT_EQ(res.pinhole_sufficient, expect < 1.0);
  }
  // One number by hand: fy = 500, 15 fps, v_y = 1 m/s, z = 10 m:
  // r_n = 14.4 /s, correction = 479 * 1 / (144 - 1) = 3.34965 px.
  const ApplicabilityResult res =
      correction_bound(vga(500), RowTiming::full_frame(480, 15), translation(0, 1, 0), 10.0);
  EXPECT_NEAR(res.max_correction_px, 479.0 / 143.0, 1e-6);
  EXPECT_FALSE(res.pinhole_sufficient);
  // The mean over a uniform grid of rows 0, 479/24, ..., 479: the correction is linear in
  // the row, so the mean is half the maximum.
  EXPECT_NEAR(res.mean_correction_px, 0.5 * 479.0 / 143.0, 1e-6);
}

// The middle-row reference: correction fy v_y (t_c - t_ref) / z, largest on the first or
// the last row; t_ref is the middle row's time.
TEST(GeneralBound, MiddleRowReference) {
  const CameraModel cam = vga(500);
  const RowTiming t = RowTiming::full_frame(480, 15);
  const double vy = 1.0, z = 10.0, r_n = t.r() / cam.fy;
  ApplicabilityOptions o;
  o.reference = CorrectionReference::MiddleRow;
  const double t_ref = 239.5 / 7200.0;
  const double t_last = (479.0 / 500.0) / (r_n - vy / z);
  const double expect = std::max(cam.fy * vy * t_ref / z, cam.fy * vy * (t_last - t_ref) / z);
  const ApplicabilityResult res = correction_bound(cam, t, translation(0, vy, 0), z, o);
  EXPECT_NEAR(res.max_correction_px, expect, 1e-6);
  EXPECT_DOUBLE_EQ(res.worst_pixel.y(), 479.0);
  // About half the frame-start bound.
  const double fs = correction_bound(cam, t, translation(0, vy, 0), z).max_correction_px;
  EXPECT_NEAR(res.max_correction_px / fs, 0.5, 0.01);
}

// The general bound's min depth for pure v_y in closed form: the correction on the last
// row, (H - 1) v_y / (r_n z - v_y) = N, gives z = v_y (H - 1 + N) / (N r_n).
TEST(GeneralBound, MinDepthPureVyClosedForm) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("GeneralBound.PureVyMatchesClosedFormMaximum (the same bound)");
  const CameraModel cam = vga(500);
  const RowTiming t = RowTiming::full_frame(480, 15);
  for (double N : {0.5, 1.0, 3.0}) {
    ApplicabilityOptions o;
    o.threshold_px = N;
    const double z = min_depth_for(cam, t, translation(0, 1.0, 0), o);
    EXPECT_NEAR(z, (479 + N) / (N * 14.4), 1e-6 * z) << "N=" << N;  // 33.333 m for N = 1
  }
  // Linear in v_y (the correction depends on v_y / z only).
  const double z1 = min_depth_for(cam, t, translation(0, 1.0, 0));
  EXPECT_NEAR(min_depth_for(cam, t, translation(0, 3.0, 0)), 3 * z1, 1e-6 * z1);
}

// (c) ~1/z at large depth, ~linear in v; decreasing in depth.
TEST(GeneralBound, ScalesInverselyWithDepthAndLinearlyWithVelocity) {
  const CameraModel cam = CameraModel::from_hfov(640, 480, 60 * M_PI / 180);
  const RowTiming t = RowTiming::full_frame(480, 30);
  const Twist tw = translation(0.4, 1.0, 0.6);
  const double b1 = correction_bound(cam, t, tw, 1e3).max_correction_px;
  const double b2 = correction_bound(cam, t, tw, 2e3).max_correction_px;
  const double b4 = correction_bound(cam, t, tw, 4e3).max_correction_px;
  EXPECT_NEAR(b1 / b2, 2.0, 2e-3);
  EXPECT_NEAR(b2 / b4, 2.0, 1e-3);
  const double c2 = correction_bound(cam, t, translation(0.8, 2.0, 1.2), 1e3).max_correction_px;
  EXPECT_NEAR(c2 / b1, 2.0, 2e-3);
  double prev = kInf;
  for (double z : {0.5, 1.0, 2.0, 5.0, 10.0, 50.0}) {
    const double b = correction_bound(cam, t, tw, z).max_correction_px;
    EXPECT_LT(b, prev) << "z=" << z;
    prev = b;
  }
}

// (d) Rotation only: depth-independent floor; no depth suffices when it exceeds the threshold.
TEST(GeneralBound, RotationGivesDepthIndependentFloor) {
  const CameraModel cam = vga(500);
  const RowTiming t = RowTiming::full_frame(480, 15);
  Twist rot;
  rot.w = Vector3d(0.2, 0.5, 0.1);
  const ApplicabilityResult a = correction_bound(cam, t, rot, 0.5);
  for (double z : {2.0, 20.0, 2000.0}) {
    const ApplicabilityResult b = correction_bound(cam, t, rot, z);
    EXPECT_NEAR(b.max_correction_px, a.max_correction_px, 1e-7 * a.max_correction_px);
    EXPECT_NEAR(b.mean_correction_px, a.mean_correction_px, 1e-7 * a.mean_correction_px);
  }
  // Pan w_y = 0.5 rad/s moves the image about fx w_y = 250 px/s: ~17 px over the readout.
  EXPECT_GT(a.max_correction_px, 10);
  EXPECT_FALSE(a.pinhole_sufficient);
  EXPECT_EQ(min_depth_for(cam, t, rot), kInf);
  Twist both = rot;
  both.v = Vector3d(0, 1, 0);
  EXPECT_EQ(min_depth_for(cam, t, both), kInf);

  // A slow rotation leaves room: finite depth, larger than for translation alone, and the
  // verdict flips there.
  Twist slow;
  slow.w = Vector3d(0, 0.01, 0);  // ~0.33 px floor
  EXPECT_EQ(min_depth_for(cam, t, slow), 0.0);  // no translation: every depth is fine
  slow.v = Vector3d(0, 1, 0);
  const double z = min_depth_for(cam, t, slow);
  ASSERT_TRUE(std::isfinite(z));
  EXPECT_GT(z, min_depth_for(cam, t, translation(0, 1, 0)));
  EXPECT_TRUE(correction_bound(cam, t, slow, z * 1.001).pinhole_sufficient);
  EXPECT_FALSE(correction_bound(cam, t, slow, z * 0.999).pinhole_sufficient);
}

// (e) With fy = H (normalised image height 1) the paper's limit and the exact one agree:
// exact z = v_y (H - 1 + N) fy / (N r) vs paper v_y fy^2 / (N r), identical for N = 1.
TEST(PaperBound, AgreesWithExactWhenNormalisedHeightIsOne) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("PaperBound.*, GeneralBound.* (the same bounds)");
  const CameraModel cam = vga(480);  // fy = H = 480
  for (double fps : {3.75, 7.5, 15.0}) {
    const RowTiming t = RowTiming::full_frame(480, fps);
    for (double vy : {0.5, 1.0, 3.0}) {
      for (double N : {1.0, 2.0}) {
        ApplicabilityOptions o;
        o.threshold_px = N;
        const double zp = paper_min_depth(cam, t, vy, N);
        const double ze = min_depth_for(cam, t, translation(0, vy, 0), o);
        SCOPED_TRACE(testing::Message() << "fps=" << fps << " vy=" << vy << " N=" << N);
        EXPECT_NEAR(ze / zp, 1.0, 0.01);
        // The verdict flips at the paper's limit.
        EXPECT_FALSE(correction_bound(cam, t, translation(0, vy, 0), 0.98 * zp, o).pinhole_sufficient);
        EXPECT_TRUE(correction_bound(cam, t, translation(0, vy, 0), 1.02 * zp, o).pinhole_sufficient);
      }
    }
  }
  // For N = 1 the two coincide exactly: 480^2 / 7200 = 32 m at 15 fps and v_y = 1 m/s.
  const double ze = min_depth_for(cam, RowTiming::full_frame(480, 15), translation(0, 1, 0));
  EXPECT_NEAR(ze, 32.0, 1e-6);
  EXPECT_NEAR(paper_min_depth(cam, RowTiming::full_frame(480, 15), 1.0), 32.0, 1e-12);
  // The Figure 1 camera (fy = 879 > H) makes the paper's line conservative by fy / H ~ 1.83.
  const CameraModel fig1 = CameraModel::from_hfov(640, 480, 40 * M_PI / 180);
  const RowTiming t15 = RowTiming::full_frame(480, 15);
  EXPECT_NEAR(paper_min_depth(fig1, t15, 1.0) / min_depth_for(fig1, t15, translation(0, 1, 0)),
              fig1.fy / 480, 1e-6);
}

// Points the readout never catches (image faster than the readout) count as failures.
TEST(GeneralBound, UncapturedPointsAreReported) {
  const CameraModel cam = vga(500);
  const RowTiming t = RowTiming::full_frame(480, 15);  // r_n = 14.4 /s
  const ApplicabilityResult res = correction_bound(cam, t, translation(0, 10, 0), 0.5);
  EXPECT_GT(res.no_solution, 0);
  EXPECT_LT(res.no_solution, res.grid_points);
  EXPECT_FALSE(res.pinhole_sufficient);
  const ApplicabilityResult bad = correction_bound(cam, t, translation(0, 1, 0), -1.0);
  EXPECT_EQ(bad.no_solution, bad.grid_points);
  EXPECT_EQ(bad.max_correction_px, kInf);
  EXPECT_FALSE(bad.pinhole_sufficient);
  // A static camera: no correction at all.
  const ApplicabilityResult still = correction_bound(cam, t, Twist{}, 3.0);
  EXPECT_NEAR(still.max_correction_px, 0, 1e-9);
  EXPECT_TRUE(still.pinhole_sufficient);
  EXPECT_EQ(min_depth_for(cam, t, Twist{}), 0.0);
}
