// The renderer images every row at its own read time. Checked against analytic edge
// positions: a vertical board edge x = X0 seen in row y is where the camera pose at that
// row's time t(y) puts it, which for translation and for roll has a closed form.
#include <gtest/gtest.h>

#include <cmath>

#include "dsp/sim/rs_renderer.hpp"
#include "tests/support/sanitizer.hpp"

using namespace rsd::dsp;

namespace {

constexpr double kZ = 1.0, kSquare = 0.05;

// Sub-pixel column of the first black -> white or white -> black step in row y, searched in
// [x_lo, x_hi]: with area-sampled pixels the step position is the summed coverage.
double edge_column(const Image& img, int y, int x_lo, int x_hi) {
  const std::uint8_t* row = img.data.data() + y * img.stride();
  int x = x_lo;
  while (x < x_hi && std::abs(int(row[x + 1]) - int(row[x])) < 8) ++x;  // first step
  const int a = std::max(x_lo, x - 2), b = std::min(x_hi, x + 3);
  if (std::abs(int(row[b]) - int(row[a])) < 250) return std::nan("");  // row on a corner
  const bool rising = row[b] > row[a];
  double sum = 0;
  for (int k = a; k <= b; ++k) sum += row[k] / 255.0;
  return rising ? b + 0.5 - sum : a - 0.5 + sum;
}

// A board with one square column boundary at x = 0: squares are 5 cm, board centred.
Scene board_scene() {
  Scene s;
  s.planes.push_back(fronto_parallel_checkerboard(kZ, 8, 8, kSquare));
  return s;
}

Image render(const CameraMotion& motion, const RowTiming& timing, const CameraModel& cam) {
  RenderOptions opt;
  opt.supersample = 16;
  RsRenderer r(cam, timing, opt);
  Image img(cam.width, cam.height, PixelFormat::Mono8);
  r.render(board_scene(), motion, 0.0, img.view());
  return img;
}

}  // namespace

TEST(RsRenderer, TranslationShearsEdgesByTheRowTime) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("RsRenderer.RollBendsEdgesAsThePoseAtEachRowSays (the same renderer, a pose per row)");
  CameraModel cam;
  cam.width = 320, cam.height = 240, cam.fx = cam.fy = 250, cam.cx = 159.5, cam.cy = 119.5;
  const RowTiming timing = RowTiming::full_frame(240, 30);
  Twist tw;
  tw.v = {0.9, 0.4, 0.0};  // camera-frame point velocity; X_c = X + v t
  const ScrewMotion motion(tw);
  const Image img = render(motion, timing, cam);
  double worst = 0, shear = 0;
  int measured = 0;
  for (int y = 80; y < 160; y += 3) {  // rows the board covers {
    const double t = timing.row_time(y);
    // The board's column boundary at x = 0 in row y, analytic: u = fx (0 + vx t) / z + cx.
    const double expected = cam.fx * (0.0 + tw.v.x() * t) / kZ + cam.cx;
    const double got = edge_column(img, y, int(expected) - 8, int(expected) + 8);
    if (std::isnan(got)) continue;
    ++measured;
    worst = std::max(worst, std::abs(got - expected));
    shear = std::max(shear, std::abs(expected - cam.cx));
  }
  EXPECT_GT(measured, 20);
  EXPECT_LT(worst, 0.04);  // 16 sub-columns quantise a vertical edge's coverage to 1/32 px
  EXPECT_GT(shear, 4.0);  // the rolling shutter moved the edge by pixels, not hundredths
}

TEST(RsRenderer, RollBendsEdgesAsThePoseAtEachRowSays) {
  // The paper's Figure 1 set-up: rotation about the optical axis at 1/2 revolution per second.
  CameraModel cam = CameraModel::from_hfov(320, 240, 40.0 * M_PI / 180.0);
  const RowTiming timing = RowTiming::full_frame(240, 30, Readout::BottomToTop);
  Twist tw;
  tw.w = {0, 0, M_PI};
  const ScrewMotion motion(tw);
  const Image img = render(motion, timing, cam);
  const double X0 = kSquare;  // the boundary one square right of centre
  double worst = 0;
  int measured = 0;
  for (int y = 60; y < 180; y += 5) {  // rows the board covers {
    const double th = tw.w.z() * timing.row_time(y);
    // X_c = Rz(th) (X0, Y, z): pick Y so that the point lands on row y, read its column.
    const double Y = ((y - cam.cy) * kZ / cam.fy - std::sin(th) * X0) / std::cos(th);
    const double expected = cam.fx * (std::cos(th) * X0 - std::sin(th) * Y) / kZ + cam.cx;
    const double got = edge_column(img, y, int(expected) - 6, int(expected) + 6);
    if (std::isnan(got)) continue;
    ++measured;
    worst = std::max(worst, std::abs(got - expected));
  }
  EXPECT_GT(measured, 15);
  EXPECT_LT(worst, 0.03);
}

TEST(RsRenderer, NoiseHasTheRequestedSigma) {
  CameraModel cam;
  cam.width = 200, cam.height = 100;
  RenderOptions opt;
  opt.supersample = 1;
  opt.noise_sigma = 4.0;
  RsRenderer r(cam, RowTiming::full_frame(100, 30), opt);
  Scene flat;
  flat.background = {0.5f, 0.5f, 0.5f};
  Image img(cam.width, cam.height, PixelFormat::Mono8);
  r.render(flat, ScrewMotion(Twist{}), 0.0, img.view());
  double sum = 0, sum2 = 0;
  for (auto p : img.data) sum += p, sum2 += double(p) * p;
  const double n = img.data.size(), mean = sum / n;
  EXPECT_NEAR(mean, 127.5, 0.2);
  EXPECT_NEAR(std::sqrt(sum2 / n - mean * mean), std::sqrt(16.0 + 1.0 / 12), 0.1);  // + rounding
}
