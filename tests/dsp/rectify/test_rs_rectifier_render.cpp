// The rectifier's images against the renderer's global-shutter frame at t_ref (RsRenderer with
// a line delay of 1e-12 s), from the rendered rolling-shutter frame of the same scene and motion.
// Apart from test_rs_rectifier.cpp because it needs the simulator (OpenCV), which the arm64
// cross build (tests/cross) does without.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "dsp/rectify/rs_rectifier.hpp"
#include "dsp/sim/rs_renderer.hpp"

using namespace rsd::dsp;
using Eigen::Vector3d;

namespace test_rs_rectifier_render {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

CameraModel camera(int w, int h, double hfov_deg) { return CameraModel::from_hfov(w, h, hfov_deg * M_PI / 180); }

Twist twist(Vector3d v, Vector3d w) {
  Twist t;
  t.v = v, t.w = w;
  return t;
}

}  // namespace

namespace {

// Root-mean-square grey-level difference over rows [y0, y1) less a margin on either side.
double rms_difference(const Image& a, const Image& b, int margin, int y0, int y1) {
  const int C = channels(a.format);
  double sum = 0;
  long n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = margin; x < a.width - margin; ++x)
      for (int ch = 0; ch < C; ++ch) {
        const size_t k = (static_cast<size_t>(y) * a.width + x) * C + ch;
        const double d = double(a.data[k]) - double(b.data[k]);
        sum += d * d, ++n;
      }
  return std::sqrt(sum / n);
}

struct RenderCheck {
  double rectified_rms, unrectified_rms;
};

// Renders the rolling-shutter frame and the global-shutter frame at t_ref of the same scene
// and motion (world = camera at the frame start), rectifies the first, compares with the second
// over rows [y0, y1) (margins: rectification leaves black where the rolling shutter saw nothing).
RenderCheck render_and_rectify(const Scene& scene, const Twist& tw, const DepthModel& depth, PixelFormat f,
                               int y0 = 30, int y1 = 210) {
  const CameraModel cam = camera(320, 240, 60);
  const RowTiming timing = RowTiming::full_frame(240, 30);
  const double t_ref = reference_time(timing, ReferenceRow::Middle);
  RenderOptions opt;
  opt.supersample = 4;
  RowTiming global = timing;
  global.line_delay_s = 1e-12;
  Image rs(cam.width, cam.height, f), gs(cam.width, cam.height, f), out(cam.width, cam.height, f);
  const ScrewMotion motion(tw);
  RsRenderer(cam, timing, opt).render(scene, motion, 0.0, rs.view());
  RsRenderer(cam, global, opt).render(scene, motion, t_ref, gs.view());
  Rectifier rect(cam, timing, f);
  const RectifyReport rep = rect.rectify(rs.view(), out.view(), tw, depth, t_ref);
  EXPECT_TRUE(rep.within_tolerance());
  return {rms_difference(out, gs, 30, y0, y1), rms_difference(rs, gs, 30, y0, y1)};
}

Plane textured_plane(Vector3d origin, Vector3d s, Vector3d t, double cell_m) {
  Plane p;
  p.origin = origin, p.axis_s = s, p.axis_t = t;
  p.texture = std::make_shared<NoiseTexture>(3, cell_m);
  return p;
}

}  // namespace

TEST(RsRectifier, RectifiedFrameIsTheGlobalShutterFrame) {
  // A textured wall 2 m ahead; the camera pans, rolls and slides.
  Scene scene;
  scene.planes.push_back(textured_plane({-5, -5, 2}, Vector3d::UnitX(), Vector3d::UnitY(), 0.08));
  const Twist tw = twist({0.8, 0.3, 0.4}, {0.3, 1.5, 0.8});
  for (PixelFormat f : {PixelFormat::Mono8, PixelFormat::Rgb8}) {
    const RenderCheck r = render_and_rectify(scene, tw, DepthModel::fronto_parallel(2.0), f);
    std::printf("[ image ] wall, format %d: RMS rectified %.2f, unrectified %.2f grey levels\n",
                static_cast<int>(f), r.rectified_rms, r.unrectified_rms);
    EXPECT_LT(r.rectified_rms, 2.5);
    EXPECT_GT(r.unrectified_rms, 6 * r.rectified_rms);
  }
}

TEST(RsRectifier, RectifiedGroundIsTheGlobalShutterGround) {
  // Driving at 12 m/s with the camera 1.2 m above a textured road, yawing; uniform sky. Compared
  // from 50 rows below the horizon (row 119.5) down: nearer the horizon the foreshortened
  // texture is finer than the pixels, and the two renders alias it differently.
  Scene scene;
  scene.planes.push_back(textured_plane({0, 1.2, 0}, Vector3d::UnitX(), Vector3d::UnitZ(), 1.0));
  scene.background = {0.6f, 0.7f, 0.9f};
  const Twist tw = twist({0, 0, 12}, {0.02, 0.6, 0.05});
  const RenderCheck r = render_and_rectify(scene, tw, ground_plane(1.2), PixelFormat::Mono8, 170, 230);
  std::printf("[ image ] ground: RMS rectified %.2f, unrectified %.2f grey levels\n", r.rectified_rms,
              r.unrectified_rms);
  EXPECT_LT(r.rectified_rms, 2.5);
  EXPECT_GT(r.unrectified_rms, 4 * r.rectified_rms);
}

}  // namespace test_rs_rectifier_render
