// AravisSource end to end.
//  AravisFake.*  Aravis' in-process fake camera (no network): our own images injected
//                through the fake's fill pattern arrive pixel for pixel.
//  AravisGigE.*  The real GigE Vision fake camera, arv-fake-gv-camera-0.8, on 127.0.0.1 —
//                only inside a private network namespace (tests/drivers/run_in_netns.sh; they skip
//                elsewhere): streaming by address, a camera lost mid-stream, no camera.
// Ground truth: the pixels each camera writes for a frame id (ours; the GigE fake's
// documented diagonal ramp), the in-process fake's own stamps, the GigE fake's frame period; the stamp mapping's own accuracy is
// measured against exact truth in test_aravis_timestamps.
#include <arv.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "drivers/aravis_source.hpp"
#include "tests/support/fake_camera_stamps.hpp"
#include "tests/support/fake_gv_camera.hpp"
#include "tests/support/sanitizer.hpp"

extern char** environ;

using namespace rsd::drivers;
using rsd::dsp::ImageView;
using rsd::dsp::PixelFormat;
using namespace std::chrono_literals;
using rsd::test::FakeGvCamera;
using rsd::test::only_loopback;
using rsd::test::gvcp_port_bound;

namespace {

using Pixel = std::function<int(int x, int y, int channel, uint64_t frame_id)>;

int64_t monotonic_now() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

// The camera's frame id for the driver's counter: GigE Vision ids wrap from 65535 to 1.
uint64_t camera_frame_id(uint64_t sequence) { return sequence <= 65535 ? sequence : (sequence - 1) % 65535 + 1; }

// Our injected images: every pixel a function of position, channel and frame id.
int our_pixel(int x, int y, int c, uint64_t id, PixelFormat f) {
  if (f == PixelFormat::Mono16) return static_cast<int>((x * 257 + y * 911 + id * 4099) & 0xFFFF);
  return static_cast<int>((x * 3 + y * 7 + id * 11 + c * 85) & 0xFF);
}

// The GigE fake's Mono8 diagonal ramp at 10 ms exposure and gain 0: (x + y + id) mod 255.
int gv_fake_pixel(int x, int y, int, uint64_t id) { return static_cast<int>((x + y + id) % 255); }

int read_pixel(const ImageView& v, int x, int y, int c) {
  if (v.format == PixelFormat::Mono16) {
    uint16_t p;
    std::memcpy(&p, v.row(y) + 2 * x, 2);
    return p;
  }
  return v.row(y)[x * rsd::dsp::channels(v.format) + c];
}

void write_pixel(const ImageView& v, int x, int y, int c, int value) {
  if (v.format == PixelFormat::Mono16) {
    const auto p = static_cast<uint16_t>(value);
    std::memcpy(v.row(y) + 2 * x, &p, 2);
  } else {
    v.row(y)[x * rsd::dsp::channels(v.format) + c] = static_cast<uint8_t>(value);
  }
}

void fill_ours(const ImageView& v, uint64_t id) {
  for (int y = 0; y < v.height; ++y)
    for (int x = 0; x < v.width; ++x)
      for (int c = 0; c < rsd::dsp::channels(v.format); ++c) write_pixel(v, x, y, c, our_pixel(x, y, c, id, v.format));
}

size_t count_mismatches(const ImageView& v, uint64_t id, const Pixel& expected) {
  size_t bad = 0;
  for (int y = 0; y < v.height; ++y)
    for (int x = 0; x < v.width; ++x)
      for (int c = 0; c < rsd::dsp::channels(v.format); ++c) bad += read_pixel(v, x, y, c) != expected(x, y, c, id);
  return bad;
}

struct Captured {
  std::vector<uint64_t> sequence;
  std::vector<int64_t> first_row, arrival;
  size_t bad_pixels = 0, timeouts = 0, id_skews = 0;
};

// A run's frames for a failure's message: sequence, first-row stamp (ms) and arrival (ms).
std::string describe(const Captured& run) {
  std::ostringstream o;
  for (size_t k = 0; k < run.sequence.size(); ++k)
    o << " [" << run.sequence[k] << " " << run.first_row[k] / 1e6 << " " << run.arrival[k] / 1e6 << "]";
  o << " bad " << run.bad_pixels << " timeouts " << run.timeouts << " id skews " << run.id_skews;
  return o.str();
}

Captured capture_frames(AravisSource& src, int n, const Pixel& expected) {
  rsd::dsp::Image slot(src.format().width, src.format().height, src.format().format);
  Captured run;
  while (static_cast<int>(run.sequence.size()) < n && run.timeouts < 5) {
    FrameMeta meta;
    if (src.capture(slot.view(), meta, 1000ms) != CaptureStatus::Frame) {
      ++run.timeouts;
      continue;
    }
    run.arrival.push_back(monotonic_now());
    run.sequence.push_back(meta.sequence);
    run.first_row.push_back(meta.first_row_ns);
    // Exact pixels for the frame's own id. Under heavy load Aravis' in-process fake has been
    // seen to label a frame with its neighbour's id (the pixels were intact); that is the
    // fake's bookkeeping, not ours: accept it, count it, and allow it rarely.
    const uint64_t id = camera_frame_id(meta.sequence);
    size_t bad = count_mismatches(slot.view(), id, expected);
    if (bad != 0)
      for (uint64_t other : {id - 1, id + 1})
        if (count_mismatches(slot.view(), other, expected) == 0) {
          bad = 0;
          ++run.id_skews;
          break;
        }
    run.bad_pixels += bad;
  }
  return run;
}

// Camera ids the delivered frames skip: frames lost between the camera and the caller.
uint64_t skipped_ids(const Captured& run) {
  uint64_t skipped = 0;
  for (size_t k = 1; k < run.sequence.size(); ++k)
    if (run.sequence[k] > run.sequence[k - 1] + 1) skipped += run.sequence[k] - run.sequence[k - 1] - 1;
  return skipped;
}

// On a loaded machine the fake can lose a frame (no free buffer when it came, a packet late):
// that is the machine, and not what these tests check. What they check: every frame delivered is
// exact, and every frame lost is counted by the driver (rsd.health_t says so), never silent.
void expect_losses_counted(const Captured& run, const AravisStats& s) {
  const uint64_t faults = s.incomplete + s.mismatched + s.underruns;
  std::printf("lost on the way: %llu ids skipped; counted %llu incomplete, %llu mismatched, %llu underruns\n",
              static_cast<unsigned long long>(skipped_ids(run)), static_cast<unsigned long long>(s.incomplete),
              static_cast<unsigned long long>(s.mismatched), static_cast<unsigned long long>(s.underruns));
  EXPECT_LE(skipped_ids(run), faults + run.id_skews);
  EXPECT_LT(faults, run.sequence.size() / 10);  // a stream that loses most frames is broken, not busy
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

// Frames consecutive, stamps rising, each first row at least the receipt delay and at most
// 50 ms before we had the frame.
void expect_frames_in_order(const Captured& run, double receipt_delay_s) {
  ASSERT_GE(run.sequence.size(), 2u);
  size_t gaps = 0;
  std::vector<double> lag_ms;
  for (size_t i = 1; i < run.sequence.size(); ++i) {
    gaps += run.sequence[i] != run.sequence[i - 1] + 1;
    EXPECT_GT(run.first_row[i], run.first_row[i - 1]) << "frame " << i;
  }
  for (size_t i = 0; i < run.arrival.size(); ++i) lag_ms.push_back((run.arrival[i] - run.first_row[i]) * 1e-6);
  std::printf("%zu frames: arrival - first row median %.3f ms, min %.3f, max %.3f\n", run.sequence.size(),
              median(lag_ms), *std::min_element(lag_ms.begin(), lag_ms.end()),
              *std::max_element(lag_ms.begin(), lag_ms.end()));
  EXPECT_EQ(gaps, 0u);
  EXPECT_GE(*std::min_element(lag_ms.begin(), lag_ms.end()), receipt_delay_s * 1e3 - 1e-6);
  EXPECT_LE(*std::max_element(lag_ms.begin(), lag_ms.end()), receipt_delay_s * 1e3 + 50.0 * rsd::test::kTimeScale)
      << (rsd::test::kSanitized ? rsd::test::kSanitizedNote : "");
}

// Stamps on the camera's grid of frame periods, for the GigE fake, whose own stamps the test
// cannot see (another process; these tests run alone, see CMakeLists.txt). The fake wakes at
// multiples of the period and stamps then; a late wake-up past the next multiple skips a slot
// without counting a frame, so a step can be two periods. On a busy host a late wake-up puts a
// stamp, and so two steps, off the grid by a few ms: half the steps within a quarter period,
// and the median exact to 1%. (Beside heavy load even that is the host's to break: the
// in-process fake's stamps are held to its own instead, tests/support/fake_camera_stamps.hpp.)
void expect_on_the_grid(const Captured& run, double period_s) {
  const double period_ms = period_s * 1e3;
  std::vector<double> step_ms;
  size_t on_grid = 0, skipped = 0;
  for (size_t i = 1; i < run.sequence.size(); ++i) {
    const double step = (run.first_row[i] - run.first_row[i - 1]) * 1e-6;
    const double slots = std::max(1.0, std::round(step / period_ms));
    step_ms.push_back(step);
    on_grid += std::abs(step - slots * period_ms) <= std::max(1.0, 0.25 * period_ms);
    skipped += slots > 1;
  }
  std::printf("median step %.4f ms, %zu of %zu steps within a quarter period of the grid (%zu skipped a slot)\n",
              median(step_ms), on_grid, step_ms.size(), skipped);
  EXPECT_NEAR(median(step_ms), period_ms, 0.01 * period_ms * rsd::test::kTimeScale);
  EXPECT_GE(on_grid, step_ms.size() / 2);
}

// The in-process fake's stamps: each frame's first row the fake's own stamp of it, mapped onto
// CLOCK_MONOTONIC, less the exposure (it stamps the start of exposure; the driver bounds that
// instant by the receipt less the exposure).
void expect_the_fakes_stamps(const Captured& run, rsd::test::FakeCameraStamps& camera, double exposure_s) {
  std::vector<std::pair<uint64_t, int64_t>> stamps;
  for (size_t i = 0; i < run.sequence.size(); ++i) stamps.emplace_back(camera_frame_id(run.sequence[i]), run.first_row[i]);
  camera.expect_stamps_are_the_cameras(stamps, exposure_s);
}

// `camera`, when given, records the fake's own stamp of each frame it fills.
AravisConfig fake_config(const std::string& format,
                         const std::shared_ptr<rsd::test::FakeCameraStamps>& camera = nullptr) {
  AravisConfig c;
  c.camera = "Fake_1";
  c.pixel_format = format;
  c.width = 64;
  c.height = 48;
  c.frame_rate_hz = 100;
  c.exposure_s = 100e-6;
  c.line_delay_s = 10e-6;
  c.fake_fill = [camera](const ImageView& v, uint64_t id, int64_t camera_stamp_ns) {
    if (camera) camera->record(id, camera_stamp_ns);
    fill_ours(v, id);
  };
  return c;
}

class AravisFake : public ::testing::Test {
 protected:
  // Belt and braces: the driver never uses Aravis' interfaces (no discovery), and with these
  // off nothing in this process could broadcast through them.
  void SetUp() override {
    arv_disable_interface("GigEVision");
    arv_disable_interface("USB3Vision");
  }
};

void stream_exactly(const std::string& format, int frames) {
  const auto camera = std::make_shared<rsd::test::FakeCameraStamps>();
  AravisSource src(fake_config(format, camera));
  src.open();
  const FrameFormat f = src.format();
  EXPECT_EQ(f.width, 64);
  EXPECT_EQ(f.height, 48);
  src.start();
  const PixelFormat pf = f.format;
  const Captured run = capture_frames(src, frames, [pf](int x, int y, int c, uint64_t id) { return our_pixel(x, y, c, id, pf); });
  src.stop();
  ASSERT_EQ(run.sequence.size(), static_cast<size_t>(frames));
  EXPECT_EQ(run.bad_pixels, 0u);
  EXPECT_LE(run.id_skews, 2u);
  expect_frames_in_order(run, src.timing().exposure_s);
  expect_the_fakes_stamps(run, *camera, src.timing().exposure_s);
  const AravisStats s = src.stats();
  EXPECT_EQ(s.frames, static_cast<uint64_t>(frames));
  expect_losses_counted(run, s);
}

}  // namespace

TEST_F(AravisFake, Mono8ArrivesExactlyAcrossTheFrameIdWrap) {
  const auto camera = std::make_shared<rsd::test::FakeCameraStamps>();
  AravisSource src(fake_config("Mono8", camera));
  src.open();
  const rsd::dsp::RowTiming t = src.timing();
  EXPECT_EQ(src.format().format, PixelFormat::Mono8);
  EXPECT_DOUBLE_EQ(t.frame_rate_hz, 100);
  EXPECT_NEAR(t.exposure_s, 100e-6, 1e-9);
  EXPECT_DOUBLE_EQ(t.line_delay_s, 10e-6);
  src.start();
  const Captured run = capture_frames(src, 200, [](int x, int y, int c, uint64_t id) {
    return our_pixel(x, y, c, id, PixelFormat::Mono8);
  });
  ASSERT_EQ(run.sequence.size(), 200u);
  EXPECT_EQ(run.bad_pixels, 0u);
  EXPECT_LE(run.id_skews, 2u);
  // The fake's ids start near 65400 to bring out wrap bugs: 200 frames cross 65535 -> 1.
  EXPECT_LT(run.sequence.front(), 65535u);
  EXPECT_GT(run.sequence.back(), 65535u);
  expect_frames_in_order(run, t.exposure_s);
  expect_the_fakes_stamps(run, *camera, t.exposure_s);
  const AravisStats s = src.stats();
  EXPECT_EQ(s.clock_resets, 0u);
  expect_losses_counted(run, s);
}

TEST_F(AravisFake, Mono16ArrivesExactly) { stream_exactly("Mono16", 100); }

TEST_F(AravisFake, Rgb8ArrivesExactly) { stream_exactly("RGB8", 100); }

TEST_F(AravisFake, RestartsAfterStop) {
  AravisSource src(fake_config("Mono8"));
  src.open();
  src.start();
  const Pixel ours = [](int x, int y, int c, uint64_t id) { return our_pixel(x, y, c, id, PixelFormat::Mono8); };
  const Captured first = capture_frames(src, 5, ours);
  src.stop();
  src.start();
  const Captured second = capture_frames(src, 5, ours);
  const std::string runs = "first:" + describe(first) + "\nsecond:" + describe(second) +
                           "\nclock resets " + std::to_string(src.stats().clock_resets);
  ASSERT_EQ(first.sequence.size(), 5u) << runs;
  ASSERT_EQ(second.sequence.size(), 5u) << runs;
  EXPECT_GT(second.sequence.front(), first.sequence.back()) << runs;
  // A stamp is never after its frame's arrival. It follows the earliest arrivals seen: when the
  // restarted stream's first frame reaches us more than a frame period sooner than the first
  // run's did (their first frames late on a loaded host), the mapping restarts lower and the
  // stamps may go back; without that restart they advance.
  for (const Captured* run : {&first, &second})
    for (size_t k = 0; k < run->first_row.size(); ++k) EXPECT_LE(run->first_row[k], run->arrival[k]) << runs;
  if (src.stats().clock_resets == 0) {
    EXPECT_GT(second.first_row.front(), first.first_row.back()) << runs;
  }
  EXPECT_EQ(first.bad_pixels + second.bad_pixels, 0u) << runs;
}

TEST_F(AravisFake, TimesOutWithoutHanging) {
  AravisConfig c = fake_config("Mono8");
  c.frame_rate_hz = 1;  // one frame a second, and we wait 50 ms
  AravisSource src(c);
  src.open();
  src.start();
  rsd::dsp::Image slot(64, 48, PixelFormat::Mono8);
  FrameMeta meta;
  // A capture that waited past its 50 ms for the next frame would return frames, never a
  // timeout; one that never returned is ctest's timeout. No wall clock is read: at one frame a
  // second, twenty calls see three timeouts unless the machine stalls for many seconds.
  int timeouts = 0, calls = 0;
  for (; calls < 20 && timeouts < 3; ++calls) timeouts += src.capture(slot.view(), meta, 50ms) == CaptureStatus::Timeout;
  EXPECT_EQ(timeouts, 3) << "in " << calls << " calls";
}

TEST_F(AravisFake, ConfigurationErrorsSayWhat) {
  auto message = [](const std::function<void()>& f) -> std::string {
    try {
      f();
    } catch (const CameraError& e) {
      return std::string("CameraError: ") + e.what();
    } catch (const std::exception& e) {
      return e.what();
    }
    return "no error";
  };
  AravisConfig c = fake_config("YUV422Packed");
  EXPECT_NE(message([&] { AravisSource s(c); }).find("rsd takes Mono8, Mono16 or RGB8"), std::string::npos);
  c = fake_config("Mono8");
  c.camera = "Basler-12345";
  EXPECT_NE(message([&] { AravisSource s(c); }).find("expected an IPv4 address"), std::string::npos);
  c.camera = "255.255.255.255";
  EXPECT_NE(message([&] { AravisSource s(c); }).find("not the address of one camera"), std::string::npos);
  c = fake_config("Mono8");
  c.width = 4096;  // the fake's sensor is 2048 wide
  const std::string wide = message([&] { AravisSource s(c); s.open(); });
  EXPECT_EQ(wide.find("CameraError"), std::string::npos) << wide;  // the camera is there
  EXPECT_NE(wide.find("4096"), std::string::npos) << wide;
  {
    AravisSource twice(c);  // a failed open() leaves the source as new: open() again says the same
    const std::string first = message([&] { twice.open(); }), second = message([&] { twice.open(); });
    EXPECT_EQ(first, second);
  }
  c = fake_config("Mono8");
  c.frame_rate_hz = 5000;  // the fake goes to 1000
  const std::string fast = message([&] { AravisSource s(c); s.open(); });
  EXPECT_NE(fast.find("5000"), std::string::npos) << fast;
  c = fake_config("Mono8");
  c.line_delay_s = 1e-3;  // 48 ms of readout in a 10 ms frame
  EXPECT_NE(message([&] { AravisSource s(c); s.open(); }).find("exceeds the frame period"), std::string::npos);
}

namespace {

AravisConfig gige_config() {
  AravisConfig c;
  c.camera = "127.0.0.1";
  c.pixel_format = "Mono8";
  c.width = 64;
  c.height = 48;
  c.frame_rate_hz = 100;
  c.exposure_s = 0.01;  // the fake's ramp is unscaled at 10 ms
  c.line_delay_s = 10e-6;
  c.lost_after = 1000ms;
  return c;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

class AravisGigE : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!only_loopback()) GTEST_SKIP() << "not in a private network namespace: run through tests/drivers/run_in_netns.sh";
  }
};

TEST_F(AravisGigE, StreamsByAddress) {
  std::unique_ptr<FakeGvCamera> camera;
  try {
    camera = std::make_unique<FakeGvCamera>();
  } catch (const std::exception& e) {
    FAIL() << e.what();
  }
  AravisSource src(gige_config());
  const auto t0 = std::chrono::steady_clock::now();
  src.open();
  std::printf("open took %.3f s\n", seconds_since(t0));
  EXPECT_EQ(src.format().width, 64);
  EXPECT_EQ(src.format().height, 48);
  EXPECT_EQ(src.format().format, PixelFormat::Mono8);
  EXPECT_NEAR(src.timing().exposure_s, 0.01, 1e-6);
  src.start();
  const Captured run = capture_frames(src, 200, gv_fake_pixel);
  ASSERT_EQ(run.sequence.size(), 200u);
  EXPECT_EQ(run.bad_pixels, 0u);
  EXPECT_LE(run.id_skews, 2u);
  EXPECT_LT(run.sequence.front(), 65535u);  // the GigE fake's block ids also cross the wrap
  EXPECT_GT(run.sequence.back(), 65535u);
  expect_frames_in_order(run, src.timing().exposure_s);
  expect_on_the_grid(run, 0.01);
  const AravisStats s = src.stats();
  std::printf("incomplete %llu, mismatched %llu, underruns %llu, clock resets %llu\n",
              static_cast<unsigned long long>(s.incomplete), static_cast<unsigned long long>(s.mismatched),
              static_cast<unsigned long long>(s.underruns), static_cast<unsigned long long>(s.clock_resets));
  EXPECT_EQ(s.mismatched, 0u);
}

TEST_F(AravisGigE, NoCameraIsACameraErrorNamingTheAddress) {
  ASSERT_FALSE(gvcp_port_bound()) << "something answers GVCP on 127.0.0.1 already";
  AravisSource src(gige_config());
  const auto t0 = std::chrono::steady_clock::now();
  try {
    src.open();
    FAIL() << "open() found a camera";
  } catch (const CameraError& e) {
    const double s = seconds_since(t0);
    std::printf("no camera: CameraError after %.3f s: %s\n", s, e.what());
    EXPECT_NE(std::string(e.what()).find("no GigE Vision camera answered at 127.0.0.1"), std::string::npos);
    EXPECT_LT(s, 5.0);
  }
}

TEST_F(AravisGigE, LostCameraThrowsThenANewSourceStreams) {
  std::unique_ptr<FakeGvCamera> camera;
  try {
    camera = std::make_unique<FakeGvCamera>();
  } catch (const std::exception& e) {
    FAIL() << e.what();
  }
  auto src = std::make_unique<AravisSource>(gige_config());
  src->open();
  src->start();
  ASSERT_EQ(capture_frames(*src, 10, gv_fake_pixel).sequence.size(), 10u);
  camera->kill();
  const auto t0 = std::chrono::steady_clock::now();
  rsd::dsp::Image slot(64, 48, PixelFormat::Mono8);
  FrameMeta meta;
  std::string error;
  int timeouts = 0;
  while (error.empty() && seconds_since(t0) < 30) {
    try {
      timeouts += src->capture(slot.view(), meta, 100ms) == CaptureStatus::Timeout;
    } catch (const CameraError& e) {
      error = e.what();
    }
  }
  const double lost_s = seconds_since(t0);
  std::printf("killed: CameraError after %.3f s (%d timeouts before): %s\n", lost_s, timeouts, error.c_str());
  ASSERT_FALSE(error.empty());
  EXPECT_NE(error.find("127.0.0.1"), std::string::npos);
  EXPECT_NE(error.find("lost"), std::string::npos);
  EXPECT_LT(lost_s, 10.0);  // lost_after 1 s + one register read's retries (2.5..5 s)
  // And stays lost, at once: given a minute to wait, it throws without waiting (half the
  // minute tells the two apart however slow the host; a source that waited fails the test).
  const auto t1 = std::chrono::steady_clock::now();
  EXPECT_THROW(src->capture(slot.view(), meta, 60s), CameraError);
  EXPECT_LT(seconds_since(t1), 30.0);
  const auto t2 = std::chrono::steady_clock::now();
  src.reset();  // closing a lost camera: Aravis' leave-control write times out, once
  std::printf("closing the lost source took %.3f s\n", seconds_since(t2));
  EXPECT_LT(seconds_since(t2), 10.0);

  // What the daemon's retry does: a camera is back at the address, a new source streams.
  camera.reset();
  camera = std::make_unique<FakeGvCamera>();
  AravisSource again(gige_config());
  again.open();
  again.start();
  const Captured run = capture_frames(again, 20, gv_fake_pixel);
  ASSERT_EQ(run.sequence.size(), 20u);
  EXPECT_EQ(run.bad_pixels, 0u);
  EXPECT_LE(run.id_skews, 2u);
  expect_frames_in_order(run, again.timing().exposure_s);
  expect_on_the_grid(run, 0.01);
}
