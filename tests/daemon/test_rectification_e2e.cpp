// The daemon's promise, end to end: a moving simulated rolling-shutter camera's frames come
// out of the rectifier where a global-shutter camera at the reference time would have seen
// the scene. Features are tracked (OpenCV, pyramidal Lucas-Kanade) from the global-shutter
// render into the raw and into the rectified frame: the raw frame is off by pixels, the
// rectified one agrees to a few hundredths of a pixel RMS.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <cmath>

#include "daemon/frame_rectifier.hpp"
#include "drivers/sim_source.hpp"
#include "tests/support/sanitizer.hpp"

using namespace rsd;

namespace {

cv::Mat as_mat(dsp::Image& img) { return cv::Mat(img.height, img.width, CV_8UC1, img.data.data()); }

// RMS displacement of features found in `ref` when tracked into `img`, over those that track.
double rms_shift(const cv::Mat& ref, const cv::Mat& img, int& tracked) {
  std::vector<cv::Point2f> p0, p1;
  cv::goodFeaturesToTrack(ref, p0, 300, 0.01, 8, cv::noArray(), 7);
  cv::Mat mask(ref.size(), CV_8UC1, cv::Scalar(0));
  std::vector<uchar> ok;
  std::vector<float> err;
  cv::calcOpticalFlowPyrLK(ref, img, p0, p1, ok, err, cv::Size(21, 21), 3);
  double sum = 0;
  tracked = 0;
  for (size_t i = 0; i < p0.size(); ++i) {
    // Keep features well inside: near the border the rectified image has no data.
    if (!ok[i] || p0[i].x < 40 || p0[i].y < 40 || p0[i].x > ref.cols - 40 || p0[i].y > ref.rows - 40) continue;
    const double dx = p1[i].x - p0[i].x, dy = p1[i].y - p0[i].y;
    sum += dx * dx + dy * dy;
    ++tracked;
  }
  return tracked ? std::sqrt(sum / tracked) : INFINITY;
}

// A brisk pan and roll of the simulated camera `cam`, rotation only (infinite depth is exact);
// frames 2..5 rectified with `rc` and compared with the global-shutter render through the output
// camera at the reference time.
void expect_like_the_global_shutter(const dsp::CameraModel& cam, const daemon::RectifyConfig& rc, double limit_rms,
                                    double min_raw_rms = 3.0) {
  drivers::SimSourceConfig c;
  c.camera = cam;
  c.realtime = false;
  c.angular_rate = Eigen::Vector3d(0.2, 0.9, 0.6);
  c.velocity = Eigen::Vector3d::Zero();
  c.exposure_s = 0;
  c.noise_grey = 0;
  c.supersample = 2;
  drivers::SimSource sim(c);
  daemon::VelocityBuffer velocity;
  sim.set_velocity_sink([&](const drivers::VelocitySample& s) { velocity.push(s); });
  sim.open();
  sim.start();
  daemon::FrameRectifier rect(rc, c.camera, sim.timing(), sim.format());

  dsp::Image raw(cam.width, cam.height, dsp::PixelFormat::Mono8), out = raw, gs = raw;
  dsp::RowTiming global = sim.timing();
  global.line_delay_s = 1e-12;  // every row at the same instant: a global shutter
  dsp::RenderOptions ro;
  ro.supersample = 2;
  dsp::RsRenderer gs_renderer(daemon::output_camera(rc, cam), global, ro);
  int checked = 0;
  for (int k = 0; k < 6; ++k) {
    drivers::FrameMeta meta;
    ASSERT_EQ(sim.capture(raw.view(), meta, std::chrono::milliseconds(100)), drivers::CaptureStatus::Frame);
    const daemon::RectifyResult r = rect.process(raw.view(), out.view(), meta, velocity);
    if (k < 2) continue;  // the first frames may precede the first velocity samples
    ASSERT_TRUE(r.rectified) << r.reason;
    gs_renderer.render(sim.scene(), sim.truth(), k / c.fps + r.reference_time_s, gs.view());
    int n_raw = 0, n_rect = 0;
    const double raw_rms = rms_shift(as_mat(gs), as_mat(raw), n_raw);
    const double rect_rms = rms_shift(as_mat(gs), as_mat(out), n_rect);
    EXPECT_GT(n_rect, 50);
    if (rc.output == daemon::RectifyOutput::SameLens) {
      EXPECT_GT(raw_rms, min_raw_rms) << "frame " << k;  // the rolling shutter moved features by pixels
    }
    EXPECT_LT(rect_rms, limit_rms) << "frame " << k;
    ::testing::Test::RecordProperty("frame" + std::to_string(k) + "_raw_rms_px", std::to_string(raw_rms));
    ::testing::Test::RecordProperty("frame" + std::to_string(k) + "_rectified_rms_px", std::to_string(rect_rms));
    ++checked;
  }
  EXPECT_EQ(checked, 4);
}

// A wide-angle lens of an action camera's kind: 640x480 with a 150-degree horizontal field.
dsp::CameraModel fisheye() {
  dsp::CameraModel cam = dsp::CameraModel::from_hfov(640, 480, 1.0);
  cam.fx = cam.fy = 250;
  cam.dist = dsp::Distortion::equidistant(0.0469, -0.0135, 0.0021, -0.0003);
  return cam;
}

}  // namespace

// Rectification puts the features back: every row's orientation integrated from the gyro (one
// rate held for the frame left 0.065-0.091 px on these frames, 5-8 times more).
TEST(RectificationEndToEnd, RectifiedFeaturesMatchTheGlobalShutterRender) {
  // 27 s under AddressSanitizer, where the same maps, warps and renders run in the fisheye's
  // test to a pinhole output.
  RSD_SKIP_LONG_IN_SLOW_BUILD("RectificationEndToEnd.AFisheyeFrameIsRectifiedToAPinhole");
  expect_like_the_global_shutter(dsp::CameraModel::from_hfov(640, 480, 60.0 * M_PI / 180.0), {}, 0.04);
}

// Through a fisheye (pinhole-equi) lens: the rolling shutter removed, the lens kept (the default).
// (A wide lens sees the same motion as fewer pixels: 2.8-3.0 px raw here.)
TEST(RectificationEndToEnd, AFisheyeFrameIsRectifiedInItsOwnLens) {
  // 25 s under AddressSanitizer, where the fisheye's maps and warps run in the test below.
  RSD_SKIP_LONG_IN_SLOW_BUILD("RectificationEndToEnd.AFisheyeFrameIsRectifiedToAPinhole");
  expect_like_the_global_shutter(fisheye(), {}, 0.05, 2.0);
}

// And with rectification.output: pinhole, the lens undone too: a 100-degree pinhole.
TEST(RectificationEndToEnd, AFisheyeFrameIsRectifiedToAPinhole) {
  daemon::RectifyConfig rc;
  rc.output = daemon::RectifyOutput::Pinhole;
  rc.output_hfov_deg = 100;
  expect_like_the_global_shutter(fisheye(), rc, 0.05);
}
