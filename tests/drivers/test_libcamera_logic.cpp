// The libcamera source's device-independent logic: pixel-format mapping (libcamera's DRM
// naming), stream roles, timestamp selection and clock resolution, dmabuf page arithmetic and
// request bookkeeping across threads; and the live source, as far as a machine without a
// camera allows: "no camera found", cleanly. Expected numbers are worked out in the comments.
#include <gtest/gtest.h>

#include <libcamera/formats.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "drivers/libcamera_logic.hpp"
#include "drivers/libcamera_source.hpp"

namespace rsd::drivers {
namespace {

namespace formats = libcamera::formats;
using namespace std::chrono_literals;

// ---- Pixel formats -------------------------------------------------------------------------

TEST(LibcameraFormat, NamesFollowDrmSoRgb888IsBgrInMemory) {
  // DRM fourcc 'R' 'G' '2' '4' = RGB888, "[23:0] R:G:B little endian": byte 0 is blue.
  EXPECT_EQ(formats::RGB888.fourcc(), 0x34324752u);
  const lc::FormatInfo* rgb888 = lc::format_info(formats::RGB888);
  ASSERT_NE(rgb888, nullptr);
  const std::vector<std::uint8_t> memory{10, 20, 30};  // B, G, R of one pixel
  dsp::Image px(1, 1, dsp::PixelFormat::Rgb8);
  ASSERT_TRUE(v4l2::copy_frame(memory.data(), 3, 3, rgb888->layout, px.view()));
  EXPECT_EQ(px.data, (std::vector<std::uint8_t>{30, 20, 10}));
  // BGR888 ('B' 'G' '2' '4') is R, G, B in memory: copied as is.
  const lc::FormatInfo* bgr888 = lc::format_info(formats::BGR888);
  ASSERT_NE(bgr888, nullptr);
  ASSERT_TRUE(v4l2::copy_frame(memory.data(), 3, 3, bgr888->layout, px.view()));
  EXPECT_EQ(px.data, memory);
  EXPECT_EQ(lc::format_info(formats::R8)->layout, v4l2::Layout::Grey8);
  EXPECT_EQ(lc::format_info(formats::YUYV)->layout, v4l2::native(dsp::PixelFormat::Yuyv));
  EXPECT_EQ(lc::format_info(formats::NV12)->layout, v4l2::native(dsp::PixelFormat::Nv12));
  EXPECT_EQ(lc::format_info(formats::SBGGR16)->layout, v4l2::native(dsp::PixelFormat::BayerBggr16));
  EXPECT_EQ(lc::format_info(formats::SRGGB10_CSI2P), nullptr);  // packed 10-bit: not read
}

TEST(LibcameraFormat, ChoosesTheBestOfferedFormatForTheSlot) {
  using dsp::PixelFormat;
  EXPECT_EQ(lc::choose_format(PixelFormat::Mono8, {formats::YUYV, formats::R8})->format, formats::R8);
  EXPECT_EQ(lc::choose_format(PixelFormat::Mono8, {formats::NV12, formats::YUYV})->format, formats::YUYV);
  EXPECT_EQ(lc::choose_format(PixelFormat::Nv12, {formats::YUYV, formats::NV12})->format, formats::NV12);
  EXPECT_EQ(lc::choose_format(PixelFormat::BayerRggb8, {formats::R8, formats::SRGGB8})->format, formats::SRGGB8);
  EXPECT_EQ(lc::choose_format(PixelFormat::Rgb8, {formats::RGB888, formats::BGR888})->format, formats::BGR888);
  EXPECT_EQ(lc::choose_format(PixelFormat::Rgb8, {formats::NV12, formats::RGB888})->format, formats::RGB888);
  EXPECT_EQ(lc::choose_format(PixelFormat::Mono16, {formats::R8})->format, formats::R8);  // no 16-bit grey
  EXPECT_EQ(lc::choose_format(PixelFormat::Rgb8, {formats::NV12, formats::YUYV})->format, formats::YUYV);  // natively
  EXPECT_FALSE(lc::choose_format(PixelFormat::Mono8, {formats::SRGGB10_CSI2P}).has_value());
}

TEST(LibcameraRole, ParsesTheThreeNamesAndMapsAutoToViewfinder) {
  lc::Role r = lc::Role::Raw;
  ASSERT_TRUE(lc::parse_role("auto", r));
  EXPECT_EQ(lc::stream_role(r), libcamera::StreamRole::Viewfinder);
  ASSERT_TRUE(lc::parse_role("raw", r));
  EXPECT_EQ(lc::stream_role(r), libcamera::StreamRole::Raw);
  ASSERT_TRUE(lc::parse_role("viewfinder", r));
  EXPECT_EQ(lc::stream_role(r), libcamera::StreamRole::Viewfinder);
  EXPECT_FALSE(lc::parse_role("Raw", r));
  EXPECT_FALSE(lc::parse_role("", r));
}

TEST(LibcameraErrors, NoCameraMessagesCountWhatWasListed) {
  EXPECT_EQ(lc::no_camera_message("", {}), "no libcamera camera found (0 cameras listed)");
  EXPECT_EQ(lc::no_camera_message("imx477", {"/base/a"}),
            "no libcamera camera found with id 'imx477' (1 camera listed: /base/a)");
  EXPECT_EQ(lc::no_camera_message("x", {"a", "b"}), "no libcamera camera found with id 'x' (2 cameras listed: a, b)");
}

// ---- Timestamps ----------------------------------------------------------------------------

TEST(LibcameraClock, AStampOnTheMonotonicClockIsKeptAndSettlesIt) {
  // The machine slept 60 s: BOOTTIME = MONOTONIC + 60 s. A stamp 20 ms before monotonic "now"
  // is 60.02 s before boottime "now": only the monotonic clock fits.
  lc::ClockResolver r;
  EXPECT_EQ(r.to_monotonic(99'980'000'000, 100'000'000'000, 160'000'000'000), 99'980'000'000);
  ASSERT_TRUE(r.settled().has_value());
  EXPECT_EQ(*r.settled(), lc::Clock::Monotonic);
}

TEST(LibcameraClock, AStampOnTheBoottimeClockIsShiftedBackByTheSuspendTime) {
  // 159.97 s is 30 ms before boottime "now" and in monotonic's future: boottime, minus 60 s.
  lc::ClockResolver r;
  EXPECT_EQ(r.to_monotonic(159'970'000'000, 100'000'000'000, 160'000'000'000), 99'970'000'000);
  EXPECT_EQ(*r.settled(), lc::Clock::Boottime);
  // Settled: the next stamp is converted the same way without a test.
  EXPECT_EQ(r.to_monotonic(160'003'000'000, 100'040'000'000, 160'040'000'000), 100'003'000'000);
}

TEST(LibcameraClock, ClocksThatAgreeCannotBeToldApartAndNeedNoConversion) {
  lc::ClockResolver r;
  EXPECT_EQ(r.to_monotonic(4'990'000'000, 5'000'000'000, 5'000'000'000), 4'990'000'000);
  EXPECT_FALSE(r.settled().has_value());
}

lc::Completion completed_at(std::int64_t mono_ns) {
  lc::Completion c;
  c.mono_now_ns = mono_ns;
  c.boot_now_ns = mono_ns;
  return c;
}

TEST(LibcameraTimestamp, SensorTimestampFirstThenBufferThenCompletionAsEndOfFrame) {
  lc::ClockResolver clocks;
  lc::Completion c = completed_at(10'000'000'000);
  c.sensor_timestamp_ns = 9'950'000'000;
  c.buffer_timestamp_ns = 9'960'000'000;
  auto t = lc::first_row_stamp(c, clocks, 1000, 30e-6, 5e-3);
  EXPECT_EQ(t.ns, 9'950'000'000);
  EXPECT_EQ(t.origin, lc::StampOrigin::SensorTimestamp);

  c.sensor_timestamp_ns.reset();
  t = lc::first_row_stamp(c, clocks, 1000, 30e-6, 5e-3);
  EXPECT_EQ(t.ns, 9'960'000'000);
  EXPECT_EQ(t.origin, lc::StampOrigin::BufferTimestamp);

  // Neither: completed at 10 s, so the first row began 999 * 30 us + 5 ms = 34.97 ms earlier.
  c.buffer_timestamp_ns = 0;
  t = lc::first_row_stamp(c, clocks, 1000, 30e-6, 5e-3);
  EXPECT_EQ(t.ns, 9'965'030'000);
  EXPECT_EQ(t.origin, lc::StampOrigin::CompletionTime);
}

TEST(LibcameraTimestamp, StampsBeyondTheWindowAreNotUsed) {
  // A buffer stamp above INT64_MAX (negative once signed) or a sensor stamp beyond 2^61 ns
  // (dsp::Stamp's window) falls through to the next source instead of being converted.
  lc::ClockResolver clocks;
  lc::Completion c = completed_at(10'000'000'000);
  c.sensor_timestamp_ns = INT64_MAX;
  c.buffer_timestamp_ns = UINT64_MAX;
  auto t = lc::first_row_stamp(c, clocks, 1000, 30e-6, 5e-3);
  EXPECT_EQ(t.origin, lc::StampOrigin::CompletionTime);
  EXPECT_EQ(t.ns, 9'965'030'000);
  c.buffer_timestamp_ns = (std::uint64_t{1} << 61) + 1;
  EXPECT_EQ(lc::first_row_stamp(c, clocks, 1000, 30e-6, 5e-3).origin, lc::StampOrigin::CompletionTime);
  c.buffer_timestamp_ns = 9'960'000'000;
  EXPECT_EQ(lc::first_row_stamp(c, clocks, 1000, 30e-6, 5e-3).origin, lc::StampOrigin::BufferTimestamp);
}

TEST(LibcameraTimestamp, ExposureFromMetadataInMicrosecondsElseTheFallback) {
  EXPECT_DOUBLE_EQ(lc::exposure_seconds(10000, 0.5), 0.01);
  EXPECT_DOUBLE_EQ(lc::exposure_seconds(std::nullopt, 0.5), 0.5);
  EXPECT_DOUBLE_EQ(lc::exposure_seconds(0, 0.5), 0.5);
}

// ---- Mapping and bookkeeping ---------------------------------------------------------------

TEST(LibcameraMapping, PlanesAreMappedFromThePageTheyStartIn) {
  // Offset 5000 in 4096-byte pages: map from 4096, the plane starts 904 bytes in, 1004 long.
  lc::MapSpan s = lc::page_span(5000, 100, 4096);
  EXPECT_EQ(s.map_offset, 4096u);
  EXPECT_EQ(s.data_offset, 904u);
  EXPECT_EQ(s.map_length, 1004u);
  s = lc::page_span(8192, 10, 4096);
  EXPECT_EQ(s.map_offset, 8192u);
  EXPECT_EQ(s.data_offset, 0u);
  EXPECT_EQ(s.map_length, 10u);
}

TEST(LibcameraRequests, CancelledRetiresFailedSkipsGoodDelivers) {
  lc::Completion c;
  EXPECT_EQ(lc::dispose(c), lc::Disposition::Deliver);
  c.frame_ok = false;
  EXPECT_EQ(lc::dispose(c), lc::Disposition::Skip);
  c.cancelled = true;
  EXPECT_EQ(lc::dispose(c), lc::Disposition::Retire);
}

TEST(LibcameraRequests, CompletionsCrossThreadsAndTimeOut) {
  lc::CompletionQueue q;
  for (int i = 0; i < 3; ++i) q.queued();
  EXPECT_EQ(q.in_flight(), 3u);
  lc::Completion out;
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(q.pop(30ms, out), lc::WaitResult::Timeout);
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 30ms);

  std::thread camera([&q] {
    std::this_thread::sleep_for(20ms);
    lc::Completion c;
    c.cookie = 7;
    q.push(c);
  });
  const auto t1 = std::chrono::steady_clock::now();
  ASSERT_EQ(q.pop(5000ms, out), lc::WaitResult::Ready);
  EXPECT_LT(std::chrono::steady_clock::now() - t1, 2000ms);  // woken, not timed out
  camera.join();
  EXPECT_EQ(out.cookie, 7u);
  EXPECT_EQ(q.in_flight(), 2u);
}

TEST(LibcameraRequests, ALostCameraStillDeliversWhatCompletedBefore) {
  lc::CompletionQueue q;
  q.queued();
  lc::Completion c;
  c.cookie = 3;
  q.push(c);
  q.lose();
  lc::Completion out;
  ASSERT_EQ(q.pop(0ms, out), lc::WaitResult::Ready);
  EXPECT_EQ(out.cookie, 3u);
  EXPECT_EQ(q.pop(1000ms, out), lc::WaitResult::Lost);
  q.reset();
  EXPECT_EQ(q.pop(0ms, out), lc::WaitResult::Timeout);
  EXPECT_EQ(q.in_flight(), 0u);
}

// ---- The live source -----------------------------------------------------------------------

TEST(LibcameraLive, AnUnknownCameraIdIsNoCamera) {
  LibcameraConfig cfg;
  cfg.camera_id = "rsd-test-no-such-camera";
  LibcameraSource src(cfg);
  try {
    src.open();
    FAIL() << "no exception";
  } catch (const CameraError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("no libcamera camera found with id 'rsd-test-no-such-camera' (", 0), 0u)
        << e.what();
  }
}

bool machine_has_media_devices() {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator("/dev", ec))
    if (e.path().filename().string().rfind("media", 0) == 0) return true;
  return false;
}

TEST(LibcameraLive, NoCameraOnTheMachineIsACameraErrorNotAHangOrCrash) {
  if (machine_has_media_devices()) GTEST_SKIP() << "this machine has /dev/media* nodes: a camera may be listed";
  // Again and again, from two sources: each failed open must stop the camera manager it
  // started, since libcamera aborts a process that creates a second one while one lives.
  LibcameraSource a{LibcameraConfig{}}, b{LibcameraConfig{}};
  for (LibcameraSource* src : {&a, &b, &a}) {
    try {
      src->open();
      FAIL() << "no exception";
    } catch (const CameraError& e) {
      EXPECT_STREQ(e.what(), "no libcamera camera found (0 cameras listed)");
    }
  }
  dsp::Image img(640, 480, dsp::PixelFormat::Mono8);
  FrameMeta meta;
  EXPECT_THROW(a.capture(img.view(), meta, 10ms), std::logic_error);  // never opened: a clear error
  EXPECT_THROW(a.start(), std::logic_error);
}

TEST(LibcameraLive, BadConfigurationIsAClearError) {
  LibcameraConfig cfg;
  cfg.role = "still";
  try {
    LibcameraSource src(cfg);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("role"), std::string::npos);
  }
  cfg.role = "auto";
  cfg.width = 0;
  EXPECT_THROW(LibcameraSource{cfg}, std::invalid_argument);
}

}  // namespace
}  // namespace rsd::drivers
