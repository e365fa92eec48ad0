// The daemon's hot path behind a real Aravis camera: stream, stamp, rectify, publish.
//
//   AravisPipeline.*      Aravis' in-process fake camera (Fake_1), rolling-shutter frames
//                         rendered by rsd's simulator injected as its images.
//   AravisPipelineGigE.*  the GigE Vision fake camera (arv-fake-gv-camera-0.8) on 127.0.0.1,
//                         only inside a private network namespace (tests/drivers/run_in_netns.sh).
#include <gtest/gtest.h>

#include <rsd/frame_info_t.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <thread>
#include <vector>

#include "daemon/frame_rectifier.hpp"
#include "daemon/pipeline.hpp"
#include "drivers/aravis_source.hpp"
#include "drivers/monotonic_clock.hpp"
#include "dsp/sim/rs_renderer.hpp"
#include "tests/support/fake_gv_camera.hpp"
#include "tests/support/sanitizer.hpp"

using namespace rsd;

namespace {

constexpr int kW = 160, kH = 120;

// The camera turns at this constant rate; the velocity buffer is told so.
const Eigen::Vector3d kRate(0.0, 0.6, 0.4);

struct Received {
  std::vector<rsd::frame_info_t> infos;
  int images = 0;
};
void on_image(const lcm_recv_buf_t*, const char*, void* u) { ++static_cast<Received*>(u)->images; }
void on_info(const lcm_recv_buf_t* rbuf, const char*, void* u) {
  rsd::frame_info_t m;
  if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) > 0) static_cast<Received*>(u)->infos.push_back(m);
}

// The velocity input: the constant rate, kept two seconds ahead of CLOCK_MONOTONIC (the frames'
// stamps) by a thread of its own until the run ends, so that every frame finds its rate however
// long a loaded or instrumented machine takes to deliver it.
class RateFeeder {
 public:
  explicit RateFeeder(daemon::VelocityBuffer& v) : velocity_(v), next_ns_(drivers::monotonic_ns() - 500000000LL) {
    feed();
    thread_ = std::thread([this] {
      while (!stop_.load()) {
        feed();
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    });
  }
  ~RateFeeder() {
    stop_ = true;
    thread_.join();
  }

 private:
  static constexpr int64_t kStepNs = 5000000, kLeadNs = 2000000000;
  void feed() {
    for (const int64_t until = drivers::monotonic_ns() + kLeadNs; next_ns_ <= until; next_ns_ += kStepNs) {
      drivers::VelocitySample s;
      s.t_ns = next_ns_;
      for (int k = 0; k < 3; ++k) s.w[k] = kRate[k];
      velocity_.push(s);
    }
  }
  daemon::VelocityBuffer& velocity_;
  int64_t next_ns_;  // the feeder's thread only (after the constructor)
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Runs `source` through the pipeline until `frames` are published; returns what LCM carried.
// Waits for the frames, not for a time: the limit only ends a run that hangs.
Received run_pipeline(drivers::CameraSource& source, int frames) {
  source.open();
  daemon::VelocityBuffer velocity;
  RateFeeder feeder(velocity);
  daemon::LcmPublisher pub("memq://", {}, source.format());
  Received rx;
  lcm_subscribe(pub.handle(), "RSD_RECT", on_image, &rx);
  lcm_subscribe(pub.handle(), "RSD_FRAME_INFO", on_info, &rx);
  const dsp::CameraModel cam = dsp::CameraModel::from_hfov(source.format().width, source.format().height, 1.0);
  daemon::FrameRectifier rect({}, cam, source.timing(), source.format());
  daemon::PipelineConfig pc;
  daemon::Pipeline pipeline(pc, source, rect, pub, velocity);
  source.start();
  pipeline.start();
  const auto hang = std::chrono::steady_clock::now() + std::chrono::seconds(static_cast<int>(60 * test::kTimeScale));
  while (pipeline.stats().frames_out.load() < static_cast<uint64_t>(frames) && std::chrono::steady_clock::now() < hang)
    lcm_handle_timeout(pub.handle(), 10);
  pipeline.stop();
  source.stop();
  while (lcm_handle_timeout(pub.handle(), 0) > 0) {}
  return rx;
}

// The stamps against the camera's grid of frame periods. A fake camera whose frames take longer
// to fill than a period (the simulator's renderer at sanitizer speed) skips slots of its grid and
// counts only the frames it delivers, and the pipeline drops frames it cannot keep up with (newest
// wins); so each frame's slot is found from its step, rounded to whole periods, and the period is
// the least-squares slope of the stamps against those slots: a late software stamp moves it by its
// lateness over the run's length, not by a whole step.
struct StampGrid {
  std::vector<double> slot, t_s;  // per frame
  std::vector<int> slot_steps;     // per step
  double period_s = 0, t0_s = 0;   // the fit
};
StampGrid fit_grid(const std::vector<rsd::frame_info_t>& infos, double period_s) {
  StampGrid g;
  for (const auto& m : infos) {
    const double t = (m.utime - infos.front().utime) * 1e-6;
    if (!g.t_s.empty()) g.slot_steps.push_back(std::max(1, static_cast<int>(std::lround((t - g.t_s.back()) / period_s))));
    g.slot.push_back(g.slot.empty() ? 0.0 : g.slot.back() + g.slot_steps.back());
    g.t_s.push_back(t);
  }
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(g.slot.size());
  for (size_t i = 0; i < g.slot.size(); ++i) sx += g.slot[i], sy += g.t_s[i], sxx += g.slot[i] * g.slot[i], sxy += g.slot[i] * g.t_s[i];
  g.period_s = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  g.t0_s = (sy - g.period_s * sx) / n;
  return g;
}

void expect_streamed_stamped_rectified(const Received& rx, int frames, double period_s) {
  ASSERT_GE(static_cast<int>(rx.infos.size()), frames);
  EXPECT_EQ(rx.images, static_cast<int>(rx.infos.size()));
  int rectified = 0;
  for (size_t i = 1; i < rx.infos.size(); ++i) {
    const auto& a = rx.infos[i - 1];
    const auto& b = rx.infos[i];
    EXPECT_GT(b.utime, a.utime) << "frame " << i;
    EXPECT_GT(b.source_sequence, a.source_sequence) << "frame " << i;
    rectified += b.rectified;
    if (b.rectified) {
      EXPECT_NEAR(b.angular_velocity[1], kRate[1], 1e-9);
    }
  }
  const StampGrid g = fit_grid(rx.infos, period_s);
  EXPECT_NEAR(g.period_s / period_s, 1.0, 0.02);
  // The fakes stamp in software when they wake, so on a busy host a late wake-up puts a stamp
  // off the grid: most stamps (not all) must lie within a quarter period of the fit.
  int on_grid = 0;
  for (size_t i = 0; i < g.slot.size(); ++i) on_grid += std::abs(g.t_s[i] - g.t0_s - g.period_s * g.slot[i]) < 0.25 * period_s;
  EXPECT_GE(on_grid, static_cast<int>(g.slot.size()) / 2);  // see test_aravis_fake.cpp: software stamps
  // At full speed the camera fills every slot and the pipeline keeps up: most steps are one period.
  if (!test::kSanitized) {
    std::vector<int> steps = g.slot_steps;
    std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
    EXPECT_EQ(steps[steps.size() / 2], 1);
  }
  EXPECT_GE(rectified, frames - 2);
}

}  // namespace

TEST(AravisPipeline, FakeCameraStreamsStampsRectifiesPublishes) {
  drivers::AravisConfig c;
  c.camera = "Fake_1";
  c.pixel_format = "Mono8";
  c.width = kW, c.height = kH;
  c.frame_rate_hz = 50;
  c.exposure_s = 1e-3;
  c.line_delay_s = 1.0 / (kH * 50.0);
  // Frames rendered by the simulator's rolling-shutter renderer, turning at kRate.
  dsp::RowTiming timing = dsp::RowTiming::full_frame(kH, 50);
  auto renderer = std::make_shared<dsp::RsRenderer>(dsp::CameraModel::from_hfov(kW, kH, 1.0), timing, dsp::RenderOptions{});
  auto scene = std::make_shared<dsp::Scene>();
  scene->planes = {dsp::fronto_parallel(Eigen::Vector3d(0, 0, 3), std::make_shared<dsp::CheckerboardTexture>(40, 40, 0.1))};
  c.fake_fill = [renderer, scene](const dsp::ImageView& v, uint64_t id) {
    dsp::Twist tw;
    tw.w = -kRate;
    renderer->render(*scene, dsp::ScrewMotion(tw), id / 50.0, v);
  };
  drivers::AravisSource source(c);
  const Received rx = run_pipeline(source, 30);
  expect_streamed_stamped_rectified(rx, 30, 1.0 / 50);
}

class AravisPipelineGigE : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!test::only_loopback()) GTEST_SKIP() << "not in a private network namespace: run through tests/drivers/run_in_netns.sh";
  }
};

TEST_F(AravisPipelineGigE, FakeGigECameraStreamsStampsRectifiesPublishes) {
  test::FakeGvCamera camera;  // arv-fake-gv-camera-0.8 -i 127.0.0.1
  drivers::AravisConfig c;
  c.camera = "127.0.0.1";
  c.pixel_format = "Mono8";
  c.width = 64, c.height = 48;
  c.frame_rate_hz = 50;
  c.exposure_s = 0.01;
  c.line_delay_s = 1.0 / (48 * 50.0);
  drivers::AravisSource source(c);
  const Received rx = run_pipeline(source, 30);
  expect_streamed_stamped_rectified(rx, 30, 1.0 / 50);
}
