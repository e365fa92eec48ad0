// The V4L2 source's device-independent logic: format choice, row copies that honour
// bytesperline, timestamp conversion, sequence gaps and error mapping. Expected numbers are
// worked out by hand in the comments.
#include <gtest/gtest.h>

#include <climits>

#include <cerrno>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "drivers/v4l2_logic.hpp"
#include "drivers/v4l2_source.hpp"
#include "tests/support/fake_v4l2_device.hpp"

namespace rsd::drivers {
namespace {

using v4l2::Layout;
using namespace rsd::drivers::test;

// ---- Pixel formats and format choice -------------------------------------------------------

TEST(V4l2PixelFormat, ParsesTheFourConfigNamesToKernelFourccs) {
  std::uint32_t f = 0;
  ASSERT_TRUE(v4l2::parse_pixel_format("GREY", f));
  EXPECT_EQ(f, 0x59455247u);  // 'G' 'R' 'E' 'Y', least significant byte first
  ASSERT_TRUE(v4l2::parse_pixel_format("Y16", f));
  EXPECT_EQ(f, 0x20363159u);  // 'Y' '1' '6' ' '
  ASSERT_TRUE(v4l2::parse_pixel_format("YUYV", f));
  EXPECT_EQ(f, 0x56595559u);
  ASSERT_TRUE(v4l2::parse_pixel_format("RGB24", f));
  EXPECT_EQ(f, 0x33424752u);  // 'R' 'G' 'B' '3'
  EXPECT_FALSE(v4l2::parse_pixel_format("MJPG", f));
  EXPECT_FALSE(v4l2::parse_pixel_format("grey", f));
  EXPECT_EQ(v4l2::fourcc_name(V4L2_PIX_FMT_MJPEG), "MJPG");
  EXPECT_EQ(v4l2::fourcc_name(0x00000001u), "????");
}

TEST(V4l2FormatChoice, PrefersTheRequestThenTheClosestReadableFormat) {
  EXPECT_EQ(v4l2::choose_pixel_format(V4L2_PIX_FMT_GREY, {V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_GREY}), V4L2_PIX_FMT_GREY);
  // Grey wanted, a colour webcam: its YUYV luma is the same 8 bits, before 16-bit or RGB.
  EXPECT_EQ(v4l2::choose_pixel_format(V4L2_PIX_FMT_GREY, {V4L2_PIX_FMT_RGB24, V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_YUYV}),
            V4L2_PIX_FMT_YUYV);
  EXPECT_EQ(v4l2::choose_pixel_format(V4L2_PIX_FMT_Y16, {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_GREY}), V4L2_PIX_FMT_GREY);
  EXPECT_EQ(v4l2::choose_pixel_format(V4L2_PIX_FMT_RGB24, {V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_YUYV}), V4L2_PIX_FMT_YUYV);
  EXPECT_EQ(v4l2::choose_pixel_format(V4L2_PIX_FMT_GREY, {V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_H264}), 0u);
  EXPECT_EQ(v4l2::choose_pixel_format(V4L2_PIX_FMT_GREY, {}), 0u);
}

TEST(V4l2FormatChoice, DiscreteSizeNearestInWidthPlusHeight) {
  const std::vector<v4l2_frmsizeenum> sizes{discrete(320, 240), discrete(800, 600), discrete(640, 480),
                                            discrete(1280, 720)};
  // 700x500: |700-640| + |500-480| = 80 beats |700-800| + |500-600| = 200.
  const v4l2::Size s = v4l2::choose_frame_size({700, 500}, sizes);
  EXPECT_EQ(s.width, 640);
  EXPECT_EQ(s.height, 480);
  // 720x540 is 100 from both 640x480 and 800x600: the larger wins.
  const v4l2::Size t = v4l2::choose_frame_size({720, 540}, sizes);
  EXPECT_EQ(t.width, 800);
  EXPECT_EQ(t.height, 600);
  const v4l2::Size u = v4l2::choose_frame_size({1280, 720}, sizes);
  EXPECT_EQ(u.width, 1280);
}

TEST(V4l2FormatChoice, StepwiseSizeClampedAndRoundedToTheStep) {
  v4l2_frmsizeenum e{};
  e.type = V4L2_FRMSIZE_TYPE_STEPWISE;
  e.stepwise = {160, 1280, 16, 120, 960, 8};
  // 1003: (1003 - 160) / 16 = 52.7 -> 53 steps -> 1008; 701: (701 - 120) / 8 = 72.6 -> 73 -> 704.
  v4l2::Size s = v4l2::choose_frame_size({1003, 701}, {e});
  EXPECT_EQ(s.width, 1008);
  EXPECT_EQ(s.height, 704);
  s = v4l2::choose_frame_size({4000, 10}, {e});  // clamped to the range
  EXPECT_EQ(s.width, 1280);
  EXPECT_EQ(s.height, 120);
  s = v4l2::choose_frame_size({333, 222}, {});  // cannot enumerate: the request stands
  EXPECT_EQ(s.width, 333);
  EXPECT_EQ(s.height, 222);
}

// ---- Row copies ----------------------------------------------------------------------------

TEST(V4l2Copy, GreyRowsSkipThePaddingBetweenThem) {
  // 3x2 grey, bytesperline 5: two padding bytes (0xEE) after each row.
  const std::vector<std::uint8_t> src{1, 2, 3, 0xEE, 0xEE, 4, 5, 6, 0xEE, 0xEE};
  dsp::Image img(3, 2, dsp::PixelFormat::Mono8);
  ASSERT_TRUE(v4l2::copy_frame(src.data(), src.size(), 5, Layout::Grey8, img.view()));
  EXPECT_EQ(img.data, (std::vector<std::uint8_t>{1, 2, 3, 4, 5, 6}));
  // The last row's padding may be absent: 5 + 3 = 8 bytes suffice, 7 do not.
  dsp::Image again(3, 2, dsp::PixelFormat::Mono8);
  EXPECT_TRUE(v4l2::copy_frame(src.data(), 8, 5, Layout::Grey8, again.view()));
  dsp::Image untouched(3, 2, dsp::PixelFormat::Mono8);
  EXPECT_FALSE(v4l2::copy_frame(src.data(), 7, 5, Layout::Grey8, untouched.view()));
  EXPECT_EQ(untouched.data, std::vector<std::uint8_t>(6, 0));
}

TEST(V4l2Copy, YuvAndMosaicsPassThroughWithTheirPlanes) {
  const auto src = yuyv_frame(4, 2, 10);  // 4 pixels = 8 bytes, bytesperline 10
  dsp::Image img(4, 2, dsp::PixelFormat::Yuyv);
  ASSERT_TRUE(v4l2::copy_frame(src.data(), src.size(), 10, v4l2::native(dsp::PixelFormat::Yuyv), img.view()));
  EXPECT_EQ(std::vector<std::uint8_t>(img.data.begin(), img.data.begin() + 8), std::vector<std::uint8_t>(src.begin(), src.begin() + 8));
  EXPECT_EQ(std::vector<std::uint8_t>(img.data.begin() + 8, img.data.end()), std::vector<std::uint8_t>(src.begin() + 10, src.begin() + 18));
  // NV12 4x2 at bytesperline 6: two luma rows, then one row of U V pairs at the same stride.
  std::vector<std::uint8_t> nv12(18);
  for (std::size_t i = 0; i < nv12.size(); ++i) nv12[i] = static_cast<std::uint8_t>(i);
  dsp::Image n(4, 2, dsp::PixelFormat::Nv12);
  ASSERT_TRUE(v4l2::copy_frame(nv12.data(), 16, 6, v4l2::native(dsp::PixelFormat::Nv12), n.view()));
  EXPECT_EQ(n.data, (std::vector<std::uint8_t>{0, 1, 2, 3, 6, 7, 8, 9, 12, 13, 14, 15}));
  EXPECT_FALSE(v4l2::copy_frame(nv12.data(), 15, 6, v4l2::native(dsp::PixelFormat::Nv12), n.view())) << "chroma cut short";
  // I420 4x2 at bytesperline 6: U and V rows at stride 3.
  dsp::Image i420(4, 2, dsp::PixelFormat::I420);
  ASSERT_TRUE(v4l2::copy_frame(nv12.data(), 17, 6, v4l2::native(dsp::PixelFormat::I420), i420.view()));
  EXPECT_EQ(i420.data, (std::vector<std::uint8_t>{0, 1, 2, 3, 6, 7, 8, 9, 12, 13, 15, 16}));
  EXPECT_FALSE(v4l2::copy_frame(nv12.data(), 18, 5, v4l2::native(dsp::PixelFormat::I420), i420.view())) << "odd stride";
  EXPECT_EQ(v4l2::pixel_info(V4L2_PIX_FMT_SGRBG16)->layout, v4l2::native(dsp::PixelFormat::BayerGrbg16));
  EXPECT_EQ(v4l2::pixel_info(V4L2_PIX_FMT_YUV420)->layout, v4l2::native(dsp::PixelFormat::I420));
  EXPECT_EQ(v4l2::choose_pixel_format(V4L2_PIX_FMT_NV12, {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_NV12}), V4L2_PIX_FMT_NV12);
  EXPECT_EQ(v4l2::choose_pixel_format(V4L2_PIX_FMT_GREY, {V4L2_PIX_FMT_SRGGB8}), V4L2_PIX_FMT_SRGGB8);
}

TEST(V4l2Copy, SixteenBitIsLittleEndianAndBgrIsSwappedToRgb) {
  const std::vector<std::uint8_t> y16{0x34, 0x12, 0xcd, 0xab, 0, 0};  // 2x1, bytesperline 6
  dsp::Image grey(2, 1, dsp::PixelFormat::Mono16);
  ASSERT_TRUE(v4l2::copy_frame(y16.data(), y16.size(), 6, Layout::Grey16, grey.view()));
  std::uint16_t px[2];
  std::memcpy(px, grey.data.data(), 4);
  EXPECT_EQ(px[0], 0x1234);
  EXPECT_EQ(px[1], 0xabcd);

  const std::vector<std::uint8_t> bgr{10, 20, 30, 40, 50, 60};  // two pixels: B G R
  dsp::Image rgb(2, 1, dsp::PixelFormat::Rgb8);
  ASSERT_TRUE(v4l2::copy_frame(bgr.data(), bgr.size(), 6, Layout::Bgr24, rgb.view()));
  EXPECT_EQ(rgb.data, (std::vector<std::uint8_t>{30, 20, 10, 60, 50, 40}));
  ASSERT_TRUE(v4l2::copy_frame(bgr.data(), bgr.size(), 6, Layout::Rgb24, rgb.view()));
  EXPECT_EQ(rgb.data, bgr);
}

TEST(V4l2Copy, AWrongDestinationIsAClearError) {
  const std::vector<std::uint8_t> src(16, 1);
  dsp::Image rgb(2, 2, dsp::PixelFormat::Rgb8);
  EXPECT_THROW(v4l2::copy_frame(src.data(), src.size(), 2, Layout::Grey8, rgb.view()), std::invalid_argument);
  dsp::ImageView empty;
  EXPECT_THROW(v4l2::copy_frame(src.data(), src.size(), 2, Layout::Grey8, empty), std::invalid_argument);
}

// ---- Timestamps ----------------------------------------------------------------------------

v4l2_buffer stamped(std::uint32_t flags, long sec, long usec) {
  v4l2_buffer b{};
  b.flags = flags;
  b.timestamp.tv_sec = sec;
  b.timestamp.tv_usec = usec;
  return b;
}

TEST(V4l2Timestamp, EndOfFrameStepsBackOverTheReadoutAndTheExposure) {
  // 1000 rows, 30 us line delay, 5 ms exposure: 999 * 30 us + 5 ms = 34.97 ms before the stamp.
  // 12.345678 s - 0.03497 s = 12.310708 s.
  EXPECT_EQ(v4l2::first_row_from_end_of_frame(12'345'678'000, 1000, 30e-6, 5e-3), 12'310'708'000);
  // One row: only the exposure lies between its start and its read-out.
  EXPECT_EQ(v4l2::first_row_from_end_of_frame(1'000'000'000, 1, 30e-6, 2e-3), 998'000'000);
  const auto b = stamped(V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_EOF, 12, 345678);
  const auto t = v4l2::first_row_start(b, 1000, 30e-6, 5e-3, 99'000'000'000);
  EXPECT_EQ(t.ns, 12'310'708'000);
  EXPECT_TRUE(t.from_driver_clock);
}

TEST(V4l2Timestamp, StartOfExposureIsTheFirstRowAlready) {
  const auto b = stamped(V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE, 12, 345678);
  const auto t = v4l2::first_row_start(b, 1000, 30e-6, 5e-3, 99'000'000'000);
  EXPECT_EQ(t.ns, 12'345'678'000);
  EXPECT_TRUE(t.from_driver_clock);
}

TEST(V4l2Timestamp, UnknownOrCopiedClocksFallBackToTheDequeueTimeAsEndOfFrame) {
  // Dequeued at 20 s: 20 s - 34.97 ms = 19.96503 s, flagged as estimated.
  for (std::uint32_t clock : {V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN, V4L2_BUF_FLAG_TIMESTAMP_COPY}) {
    const auto b = stamped(clock | V4L2_BUF_FLAG_TSTAMP_SRC_SOE, 12, 345678);
    const auto t = v4l2::first_row_start(b, 1000, 30e-6, 5e-3, 20'000'000'000);
    EXPECT_EQ(t.ns, 19'965'030'000);
    EXPECT_FALSE(t.from_driver_clock);
  }
}

TEST(V4l2Timestamp, AnAbsurdDriverStampFallsBackToTheDequeueTime) {
  // Seconds beyond rsd's window (2^61 ns, dsp::Stamp) or microseconds out of 0..999999: never
  // multiplied into an overflow, the dequeue time stands in (as for an unknown clock).
  struct Case { long sec; long usec; } cases[] = {{LONG_MAX, 0}, {LONG_MIN, 0}, {3'000'000'000, 0}, {12, -1}, {12, 1'000'000}};
  for (const Case& k : cases) {
    const auto b = stamped(V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE, k.sec, k.usec);
    const auto t = v4l2::first_row_start(b, 1000, 30e-6, 5e-3, 20'000'000'000);
    EXPECT_EQ(t.ns, 19'965'030'000) << k.sec << " s " << k.usec << " us";
    EXPECT_FALSE(t.from_driver_clock);
  }
}

// ---- Sequence numbers ----------------------------------------------------------------------

TEST(V4l2Sequence, CountsTheFramesMissingBetweenNumbers) {
  v4l2::SequenceTracker s;
  EXPECT_EQ(s.update(5), 5u);
  EXPECT_EQ(s.update(6), 6u);
  EXPECT_EQ(s.update(10), 10u);  // 7, 8, 9 missing
  EXPECT_EQ(s.dropped(), 3u);
  EXPECT_EQ(s.restarts(), 0u);
}

TEST(V4l2Sequence, UnwrapsThe32BitCounter) {
  v4l2::SequenceTracker s;
  s.update(0xFFFFFFFEu);
  s.update(0xFFFFFFFFu);
  // 0 is missing; 1 is the 2^32 + 1 = 4294967297th number.
  EXPECT_EQ(s.update(1), 4294967297ull);
  EXPECT_EQ(s.dropped(), 1u);
}

TEST(V4l2Sequence, ACounterGoingBackIsARestartNotADrop) {
  v4l2::SequenceTracker s;
  s.update(100);
  EXPECT_EQ(s.update(0), 101u);
  EXPECT_EQ(s.update(1), 102u);
  EXPECT_EQ(s.update(1), 103u);  // a repeat
  EXPECT_EQ(s.dropped(), 0u);
  EXPECT_EQ(s.restarts(), 2u);
}

// ---- Error mapping -------------------------------------------------------------------------

TEST(V4l2Errors, AMissingNodeSaysNoCameraAndWhatToCheck) {
  const CameraError e = v4l2::open_error(ENOENT, "/dev/video0");
  EXPECT_STREQ(e.what(),
               "no camera at /dev/video0 (no such device): is the camera plugged in and the uvcvideo/driver "
               "module loaded?");
  EXPECT_NE(std::string(v4l2::open_error(EACCES, "/dev/video0").what()).find("'video' group"), std::string::npos);
}

TEST(V4l2Errors, LostCameraErrnosBecomeCameraErrorOthersRuntimeError) {
  for (int err : {ENODEV, EIO, ENXIO}) {
    EXPECT_TRUE(v4l2::camera_lost(err));
    EXPECT_THROW(v4l2::throw_errno(err, "VIDIOC_DQBUF", "/dev/video3"), CameraError) << err;
  }
  EXPECT_FALSE(v4l2::camera_lost(EINVAL));
  try {
    v4l2::throw_errno(EINVAL, "VIDIOC_S_FMT", "/dev/video3");
    FAIL() << "no exception";
  } catch (const CameraError&) {
    FAIL() << "EINVAL is a bug, not a missing camera";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "/dev/video3: VIDIOC_S_FMT failed: Invalid argument");
  }
}

TEST(V4l2Errors, CapabilitiesWithoutCaptureOrStreamingAreRefused) {
  v4l2_capability cap{};
  cap.capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  EXPECT_NO_THROW(v4l2::check_capabilities(cap, "/dev/video0"));
  // The node's own caps count, not the device's: a UVC metadata node.
  cap.capabilities |= V4L2_CAP_DEVICE_CAPS;
  cap.device_caps = V4L2_CAP_META_CAPTURE | V4L2_CAP_STREAMING;
  EXPECT_THROW(v4l2::check_capabilities(cap, "/dev/video1"), std::runtime_error);
  cap.device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_READWRITE;
  EXPECT_THROW(v4l2::check_capabilities(cap, "/dev/video1"), std::runtime_error);
}

}  // namespace
}  // namespace rsd::drivers
