// A replay's output depends on the log alone, not on thread timing (PipelineConfig::
// samples_until_next_frame). The source reads on while a frame waits for the rectifier, so
// without that rule a frame saw whatever samples the reader had reached by then: a CI machine
// under load published other bytes than the developer's (daemon_reference_replay_digest).
//
// A log-like source whose IMU lags the camera by 15 ms: the samples that come before frame
// k + 1 stop short of frame k's last rows. Played twice: once in lock step (the samples of frame
// k + 2 wait until frame k has been rectified) and once with the rectifier held up until the
// reader is three frames ahead. Both must publish the same frame infos, and those must say what
// the log gives each frame: its motion held past the newest sample before the next frame, by the
// exact amount.
#include <gtest/gtest.h>

#include <rsd/frame_info_t.hpp>

#include <condition_variable>
#include <mutex>
#include <vector>

#include "daemon/frame_rectifier.hpp"
#include "daemon/pipeline.hpp"

using namespace rsd;

namespace test_pipeline_replay_samples {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

constexpr int kW = 48, kH = 36, kFrames = 10;
constexpr double kFps = 30, kLineDelay = 0.8e-3;  // readout 28.8 ms of the 33.3 ms period
constexpr int64_t kPeriodNs = 33'333'333, kSampleNs = 1'000'000, kImuLagNs = 15'000'000;
constexpr int64_t kStartNs = 1'000'000'000;

int64_t frame_ns(int k) { return kStartNs + k * kPeriodNs; }

// A turn whose rate changes with time, so that holding a rate and interpolating differ.
drivers::VelocitySample sample_at(int64_t t_ns) {
  drivers::VelocitySample s;
  s.t_ns = t_ns;
  const double t = static_cast<double>(t_ns - kStartNs) * 1e-9;
  s.w[0] = 0.2 + 3.0 * t, s.w[1] = -0.1 + 2.0 * t, s.w[2] = 0.5;
  return s;
}

// Events in log order: before frame k, every sample up to its start minus the IMU's lag.
class LaggingLogSource : public drivers::CameraSource {
 public:
  // before_frame(k): called before frame k's samples go out (the test's gate).
  explicit LaggingLogSource(std::function<void(int)> before_frame) : before_frame_(std::move(before_frame)) {}
  std::string name() const override { return "lagging log"; }
  void open() override {}
  drivers::FrameFormat format() const override { return {kW, kH, dsp::PixelFormat::Mono8}; }
  dsp::RowTiming timing() const override {
    dsp::RowTiming t;
    t.height = kH, t.line_delay_s = kLineDelay, t.frame_rate_hz = kFps;
    return t;
  }
  void start() override {}
  void stop() override {}
  void set_velocity_sink(drivers::VelocitySink s) override { sink_ = std::move(s); }
  drivers::CaptureStatus capture(const dsp::ImageView& dst, drivers::FrameMeta& meta, std::chrono::milliseconds) override {
    if (next_ == kFrames) return drivers::CaptureStatus::EndOfStream;
    before_frame_(next_);
    for (; next_sample_ns_ <= frame_ns(next_) - kImuLagNs; next_sample_ns_ += kSampleNs) sink_(sample_at(next_sample_ns_));
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) dst.row(y)[x] = static_cast<uint8_t>((x * 7 + y * 13 + next_ * 5) & 0xff);
    meta = {};
    meta.first_row_ns = frame_ns(next_);
    meta.sequence = static_cast<uint64_t>(next_++);
    return drivers::CaptureStatus::Frame;
  }
  // The newest sample delivered before frame k (the last one it may use, frame k being held
  // until frame k + 1 comes).
  static int64_t newest_before(int k) { return (frame_ns(k) - kImuLagNs) / kSampleNs * kSampleNs; }

 private:
  std::function<void(int)> before_frame_;
  drivers::VelocitySink sink_;
  int next_ = 0;
  int64_t next_sample_ns_ = kStartNs - 100'000'000;
};

// Which frames the rectifier has finished, and the reader's progress: each side waits on the other.
struct Progress : daemon::FrameTap {
  std::mutex m;
  std::condition_variable cv;
  int rectified = -1;   // the newest frame rectified
  int reader_at = -1;   // the newest frame whose samples went out
  int hold_until_reader_at = -1;  // the tap holds the rectifier after frame 0 until the reader is here
  void offer(const dsp::ImageView&, const drivers::FrameMeta& meta) override {
    std::unique_lock<std::mutex> lock(m);
    rectified = static_cast<int>(meta.sequence);
    cv.notify_all();
    if (meta.sequence == 0) cv.wait(lock, [&] { return reader_at >= hold_until_reader_at; });
  }
  void reader_reached(int k, bool lock_step) {
    std::unique_lock<std::mutex> lock(m);
    if (lock_step) cv.wait(lock, [&] { return rectified >= k - 2; });
    reader_at = k;
    cv.notify_all();
  }
};

void on_info(const lcm_recv_buf_t* rbuf, const char*, void* user) {
  rsd::frame_info_t m;
  if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) > 0) static_cast<std::vector<rsd::frame_info_t>*>(user)->push_back(m);
}

std::vector<rsd::frame_info_t> play(bool lock_step) {
  Progress progress;
  progress.hold_until_reader_at = lock_step ? -1 : 3;
  LaggingLogSource source([&](int k) { progress.reader_reached(k, lock_step); });
  daemon::VelocityBuffer velocity;
  source.set_velocity_sink([&](const drivers::VelocitySample& s) { velocity.push(s); });
  daemon::LcmPublisher pub("memq://", {}, source.format());
  std::vector<rsd::frame_info_t> infos;
  lcm_subscribe(pub.handle(), "RSD_FRAME_INFO", on_info, &infos);
  daemon::RectifyConfig rc;
  rc.imu_wait_ms = 0;  // as the service sets it for a replay
  daemon::FrameRectifier rect(rc, dsp::CameraModel::from_hfov(kW, kH, 1.0), source.timing(), source.format());
  daemon::PipelineConfig pc;
  pc.lossless = true, pc.samples_until_next_frame = true;
  daemon::Pipeline pipeline(pc, source, rect, pub, velocity);
  pipeline.set_frame_tap(&progress);
  pipeline.start();
  while (!pipeline.finished()) lcm_handle_timeout(pub.handle(), 100);  // ends with the log
  pipeline.stop();
  while (lcm_handle_timeout(pub.handle(), 0) > 0) {}
  return infos;
}

}  // namespace

TEST(PipelineReplay, AFrameSeesTheSamplesBeforeTheNextFrameWhateverTheThreadsTiming) {
  const std::vector<rsd::frame_info_t> lock_step = play(true), ahead = play(false);
  ASSERT_EQ(lock_step.size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(ahead.size(), static_cast<size_t>(kFrames));
  const dsp::RowTiming t = LaggingLogSource(nullptr).timing();
  const double end_s = t.row_time(kH - 1);  // the last row's start (exposure 0)
  for (int k = 0; k < kFrames; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const rsd::frame_info_t &a = lock_step[k], &b = ahead[k];
    ASSERT_TRUE(a.rectified);
    // What the log gives frame k: the samples before frame k + 1 (all of them for the last).
    const int64_t newest = k + 1 < kFrames ? LaggingLogSource::newest_before(k + 1) : LaggingLogSource::newest_before(kFrames - 1);
    const double beyond_s = static_cast<double>(frame_ns(k) - newest) * 1e-9 + end_s;
    EXPECT_EQ(a.extrapolated, beyond_s > 0);
    EXPECT_NEAR(a.extrapolated_s, std::max(0.0, beyond_s), 2e-9);  // stamps in whole ns
    // The same bytes of information either way.
    EXPECT_EQ(b.extrapolated, a.extrapolated);
    EXPECT_EQ(b.extrapolated_s, a.extrapolated_s);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(b.angular_velocity[i], a.angular_velocity[i]);
    EXPECT_EQ(b.max_correction_px, a.max_correction_px);
    EXPECT_EQ(b.velocity_age_s, a.velocity_age_s);
  }
}

}  // namespace test_pipeline_replay_samples
