// Issue 38, defect 4: frames published as rectified that were black (every pixel 0,
// max_correction_px 0): a motion beyond the rolling-shutter model's reach (a pitch rate of 17 to
// 19.9 rad/s, under the velocity limit of 20) or an absurd camera left the map pointing outside
// the captured image. A frame labelled rectified is never mostly black: checked by rendering a
// white frame through every map and counting the pixels that stay lit, the independent way.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "dsp/rectify/rs_rectifier.hpp"

using namespace rsd::dsp;

namespace {

constexpr int kW = 320, kH = 240;

// The share of output pixels lit when a white frame goes through the rectifier, the camera
// turning at `w` (rad/s, its own axes) as the daemon rectifies it: rates integrated over the
// readout (nine knots), the reference at the middle row.
double lit_share(Rectifier& rect, const RowTiming& timing, const Eigen::Vector3d& w, RectifyReport& rep) {
  Image src(kW, kH, PixelFormat::Mono8), dst(kW, kH, PixelFormat::Mono8);
  src.data.assign(src.data.size(), 255);
  IntegratedMotion::Knot k[9];
  const double end = timing.row_time(kH - 1);
  for (int i = 0; i < 9; ++i) k[i].t = end * i / 8, k[i].w = w;
  rep = rect.rectify(src.view(), dst.view(), IntegratedMotion(k, 9), DepthModel::at_infinity(), end / 2);
  int lit = 0;
  for (const std::uint8_t v : dst.data) lit += v > 0;
  return static_cast<double>(lit) / static_cast<double>(dst.data.size());
}

}  // namespace

TEST(RectifierHonesty, AFrameLabelledRectifiedIsNeverMostlyBlack) {
  const CameraModel cam = CameraModel::from_hfov(kW, kH, 60 * M_PI / 180);  // the simulator's default lens
  const RowTiming timing = RowTiming::full_frame(kH, 30);                   // readout over the whole 33 ms
  Rectifier rect(cam, timing, PixelFormat::Mono8);
  int refused = 0, rectified = 0;
  for (double rate = 1; rate < 20; rate += 2) {
    for (const Eigen::Vector3d axis : {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()}) {
      RectifyReport rep;
      const double lit = lit_share(rect, timing, rate * axis, rep);
      SCOPED_TRACE("rate " + std::to_string(rate) + " rad/s about " + std::to_string(axis.x()) + " " + std::to_string(axis.y()));
      if (rep.rectified) {
        ++rectified;
        EXPECT_GE(lit, 0.45) << "labelled rectified, " << 100 * (1 - lit) << " % black";  // (the map's points vs pixels)
        EXPECT_FALSE(rep.map_outside);
      } else {
        ++refused;
        EXPECT_TRUE(rep.map_outside);  // said why
        EXPECT_EQ(lit, 1.0);           // and published as captured
        EXPECT_LT(2 * rep.points_inside, rep.points_checked);
      }
    }
  }
  EXPECT_GT(rectified, 20);  // the motions a camera makes are rectified...
  EXPECT_GT(refused, 0);     // ... and the defect's pitch rates (13 to 19.9 rad/s) were reached
}

// A camera whose principal point lies far off its image (within rsd's input limits, five image
// widths away): nothing of the captured frame lands in the output, which is said, not published black.
TEST(RectifierHonesty, AnOutputCameraThatSeesNoneOfTheFrameIsNotRectified) {
  const CameraModel cam = CameraModel::from_hfov(160, 120, 1.0);
  CameraModel away = cam;
  away.cx = 4.5 * cam.width;
  Rectifier rect(cam, RowTiming::full_frame(120, 30), away, PixelFormat::Mono8);
  Image src(160, 120, PixelFormat::Mono8), dst(160, 120, PixelFormat::Mono8);
  src.data.assign(src.data.size(), 255);
  Twist tw;
  tw.w = {0.5, 0, 0};
  const RectifyReport rep = rect.rectify(src.view(), dst.view(), tw, DepthModel::at_infinity(), 0.0);
  EXPECT_FALSE(rep.rectified);
  EXPECT_TRUE(rep.map_outside);
  EXPECT_EQ(rep.points_inside, 0);
}
