// The V4L2 source's device-independent logic, driven through a fake V4l2Device: format
// choice, timestamp conversion, sequence gaps, buffer bookkeeping, error mapping and row
// copies that honour bytesperline. Expected numbers are worked out by hand in the comments.
#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "drivers/v4l2_logic.hpp"
#include "drivers/v4l2_source.hpp"

namespace rsd::drivers {
namespace {

using v4l2::Layout;

// ---- A fake device -------------------------------------------------------------------------

struct FakeFrame {
  std::vector<std::uint8_t> bytes;
  std::uint32_t flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE;
  timeval stamp{};
  std::uint32_t sequence = 0;
  long bytesused = -1;  // -1: bytes.size()
};

// What the fake driver offers and what the test can observe, shared with the device object
// (which the source owns).
struct FakeState {
  std::uint32_t caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  int querycap_error = 0;
  std::vector<std::uint32_t> formats{V4L2_PIX_FMT_GREY};
  std::vector<v4l2_frmsizeenum> sizes;      // empty: ENUM_FRAMESIZES unsupported
  std::uint32_t row_padding = 0;            // bytesperline = packed row + this
  bool can_set_rate = true;
  std::vector<double> rates{30.0};          // the driver snaps to the nearest
  int exposure_100us = 0;                   // 0: no exposure control
  unsigned grant = 0;                       // 0: grant what is asked
  std::map<std::string, int> fail;          // call name -> errno
  std::deque<FakeFrame> frames;
  // Observed.
  std::vector<std::vector<std::uint8_t>> memory;
  std::deque<std::uint32_t> queued;
  bool streaming = false;
  int maps = 0, unmaps = 0, reqbufs_zero = 0;
  v4l2_format format{};
  double rate = 30.0;
};

v4l2_frmsizeenum discrete(std::uint32_t w, std::uint32_t h) {
  v4l2_frmsizeenum s{};
  s.type = V4L2_FRMSIZE_TYPE_DISCRETE;
  s.discrete = {w, h};
  return s;
}

class FakeDevice final : public V4l2Device {
 public:
  explicit FakeDevice(std::shared_ptr<FakeState> s) : s_(std::move(s)) {}
  int query_cap(v4l2_capability& c) override {
    std::strcpy(reinterpret_cast<char*>(c.card), "Fake Cam");
    std::strcpy(reinterpret_cast<char*>(c.driver), "fake");
    c.capabilities = s_->caps;
    return s_->querycap_error;
  }
  int enum_format(v4l2_fmtdesc& d) override {
    if (d.index >= s_->formats.size()) return EINVAL;
    d.pixelformat = s_->formats[d.index];
    return 0;
  }
  int enum_frame_size(v4l2_frmsizeenum& e) override {
    if (s_->sizes.empty()) return ENOTTY;
    if (e.index >= s_->sizes.size()) return EINVAL;
    const std::uint32_t i = e.index, f = e.pixel_format;
    e = s_->sizes[i];
    e.index = i;
    e.pixel_format = f;
    return 0;
  }
  int set_format(v4l2_format& f) override {
    if (int e = failure("S_FMT")) return e;
    auto& p = f.fmt.pix;
    const auto* info = v4l2::pixel_info(p.pixelformat);
    p.bytesperline = p.width * (info ? v4l2::source_bytes_per_pixel(info->layout) : 1) + s_->row_padding;
    p.sizeimage = p.bytesperline * p.height;
    p.field = V4L2_FIELD_NONE;
    s_->format = f;
    return 0;
  }
  int get_parm(v4l2_streamparm& p) override {
    p.parm.capture.capability = s_->can_set_rate ? V4L2_CAP_TIMEPERFRAME : 0;
    p.parm.capture.timeperframe = {1000, static_cast<std::uint32_t>(s_->rate * 1000)};
    return 0;
  }
  int set_parm(v4l2_streamparm& p) override {
    const double want = double(p.parm.capture.timeperframe.denominator) / p.parm.capture.timeperframe.numerator;
    double best = s_->rates.front();
    for (double r : s_->rates)
      if (std::abs(r - want) < std::abs(best - want)) best = r;
    s_->rate = best;
    return get_parm(p);
  }
  int get_control(v4l2_control& c) override {
    if (c.id != V4L2_CID_EXPOSURE_ABSOLUTE || s_->exposure_100us == 0) return EINVAL;
    c.value = s_->exposure_100us;
    return 0;
  }
  int request_buffers(v4l2_requestbuffers& r) override {
    if (r.count == 0) {
      ++s_->reqbufs_zero;
      s_->memory.clear();
      return 0;
    }
    if (s_->grant) r.count = s_->grant;
    s_->memory.assign(r.count, std::vector<std::uint8_t>(s_->format.fmt.pix.sizeimage));
    return 0;
  }
  int query_buffer(v4l2_buffer& b) override {
    b.length = static_cast<std::uint32_t>(s_->memory.at(b.index).size());
    b.m.offset = b.index * 4096;
    return 0;
  }
  int queue_buffer(v4l2_buffer& b) override {
    if (int e = failure("QBUF")) return e;
    s_->queued.push_back(b.index);
    return 0;
  }
  int dequeue_buffer(v4l2_buffer& b) override;
  int stream_on() override {
    if (int e = failure("STREAMON")) return e;
    s_->streaming = true;
    return 0;
  }
  int stream_off() override {
    s_->streaming = false;
    s_->queued.clear();
    return 0;
  }
  int wait_readable(int, bool& ready) override {
    if (int e = failure("poll")) return e;
    ready = s_->streaming && !s_->queued.empty() && (!s_->frames.empty() || s_->fail.count("DQBUF"));
    return 0;
  }
  int map(std::size_t, std::uint32_t offset, void*& addr) override {
    addr = s_->memory.at(offset / 4096).data();
    ++s_->maps;
    return 0;
  }
  void unmap(void*, std::size_t) override { ++s_->unmaps; }

 private:
  int failure(const std::string& call) const {
    const auto it = s_->fail.find(call);
    return it == s_->fail.end() ? 0 : it->second;
  }
  std::shared_ptr<FakeState> s_;
};

int FakeDevice::dequeue_buffer(v4l2_buffer& b) {
  if (int e = failure("DQBUF")) return e;
  if (s_->frames.empty() || s_->queued.empty()) return EAGAIN;
  const FakeFrame f = s_->frames.front();
  s_->frames.pop_front();
  b.index = s_->queued.front();
  s_->queued.pop_front();
  auto& mem = s_->memory[b.index];
  std::copy(f.bytes.begin(), f.bytes.begin() + std::min(f.bytes.size(), mem.size()), mem.begin());
  b.bytesused = static_cast<std::uint32_t>(f.bytesused < 0 ? f.bytes.size() : f.bytesused);
  b.flags = f.flags;
  b.timestamp = f.stamp;
  b.sequence = f.sequence;
  return 0;
}

V4l2Opener fake_opener(const std::shared_ptr<FakeState>& s) {
  return [s](const std::string&) { return std::make_unique<FakeDevice>(s); };
}

// A width x height YUYV frame, rows `stride` bytes apart, luma = 10 * y + x, chroma 0x80,
// padding bytes 0xEE.
std::vector<std::uint8_t> yuyv_frame(int width, int height, std::size_t stride) {
  std::vector<std::uint8_t> b(stride * height, 0xEE);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      b[y * stride + 2 * x] = static_cast<std::uint8_t>(10 * y + x);
      b[y * stride + 2 * x + 1] = 0x80;
    }
  return b;
}

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

TEST(V4l2Copy, YuyvKeepsTheLumaOfEveryPixel) {
  const auto src = yuyv_frame(3, 2, 8);  // 3 pixels = 6 bytes, bytesperline 8
  dsp::Image img(3, 2, dsp::PixelFormat::Mono8);
  ASSERT_TRUE(v4l2::copy_frame(src.data(), src.size(), 8, Layout::YuyvLuma, img.view()));
  EXPECT_EQ(img.data, (std::vector<std::uint8_t>{0, 1, 2, 10, 11, 12}));
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

// ---- The source through the fake device ----------------------------------------------------

struct V4l2SourceFake : ::testing::Test {
  std::shared_ptr<FakeState> dev = std::make_shared<FakeState>();
  V4l2Config cfg;
  std::int64_t now_ns = 50'000'000'000;
  std::unique_ptr<V4l2Source> make() {
    return std::make_unique<V4l2Source>(cfg, fake_opener(dev), [this] { return now_ns; });
  }
};

TEST_F(V4l2SourceFake, NegotiatesTheClosestFormatAndReportsTheDifferences) {
  dev->formats = {V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_YUYV};
  dev->sizes = {discrete(320, 240), discrete(640, 480)};
  dev->rates = {25.0, 15.0};
  cfg.width = 600;
  cfg.height = 470;
  auto src = make();
  src->open();
  EXPECT_EQ(src->format().width, 640);
  EXPECT_EQ(src->format().height, 480);
  EXPECT_EQ(src->format().format, dsp::PixelFormat::Mono8);  // YUYV delivers its luma
  EXPECT_EQ(dev->format.fmt.pix.pixelformat, V4L2_PIX_FMT_YUYV);
  ASSERT_FALSE(src->notes().empty());
  EXPECT_EQ(src->notes().front(), "requested 600x470 GREY at 30 fps, driver gives 640x480 YUYV at 25 fps");
  // The readout fills the negotiated period: 1 / (480 rows * 25 fps).
  EXPECT_DOUBLE_EQ(src->timing().line_delay_s, 1.0 / 12000);
  EXPECT_EQ(src->timing().height, 480);
  EXPECT_DOUBLE_EQ(src->timing().frame_rate_hz, 25.0);
}

TEST_F(V4l2SourceFake, AnExactMatchHasNoNotesAndTakesTheExposureFromTheDriver) {
  dev->exposure_100us = 50;  // 5 ms
  auto src = make();
  src->open();
  EXPECT_TRUE(src->notes().empty());
  EXPECT_DOUBLE_EQ(src->timing().exposure_s, 5e-3);
}

TEST_F(V4l2SourceFake, NothingReadableOfferedIsAClearError) {
  dev->formats = {V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_H264};
  auto src = make();
  try {
    src->open();
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "/dev/video0 offers none of GREY, Y16, YUYV, RGB24 (it offers MJPG, H264)");
  }
}

TEST_F(V4l2SourceFake, ANodeThatIsNotV4l2OrCannotStreamIsRefused) {
  dev->querycap_error = ENOTTY;
  EXPECT_THROW(make()->open(), std::runtime_error);
  dev->querycap_error = 0;
  dev->caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_READWRITE;
  EXPECT_THROW(make()->open(), std::runtime_error);
  dev->querycap_error = ENODEV;  // vanished between open and QUERYCAP
  EXPECT_THROW(make()->open(), CameraError);
}

TEST_F(V4l2SourceFake, CapturesYuyvWithPaddedRowsAndConvertsAnEndOfFrameStamp) {
  dev->formats = {V4L2_PIX_FMT_YUYV};
  dev->sizes = {discrete(4, 3)};
  dev->row_padding = 4;  // bytesperline 4 * 2 + 4 = 12
  cfg.width = 4;
  cfg.height = 3;
  cfg.line_delay_s = 30e-6;
  dev->exposure_100us = 50;
  FakeFrame f;
  f.bytes = yuyv_frame(4, 3, 12);
  f.flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_EOF;
  f.stamp = {100, 0};
  f.sequence = 7;
  dev->frames.push_back(f);
  auto src = make();
  src->open();
  src->start();
  dsp::Image img(4, 3, dsp::PixelFormat::Mono8);
  FrameMeta meta;
  ASSERT_EQ(src->capture(img.view(), meta, std::chrono::milliseconds(100)), CaptureStatus::Frame);
  EXPECT_EQ(img.data, (std::vector<std::uint8_t>{0, 1, 2, 3, 10, 11, 12, 13, 20, 21, 22, 23}));
  // 3 rows: 100 s - (2 * 30 us + 5 ms) = 99.99494 s.
  EXPECT_EQ(meta.first_row_ns, 99'994'940'000);
  EXPECT_EQ(meta.sequence, 7u);
  EXPECT_DOUBLE_EQ(meta.exposure_s, 5e-3);
  EXPECT_EQ(dev->queued.size(), 4u);  // the buffer went straight back to the driver
}

TEST_F(V4l2SourceFake, CountsSequenceGapsAndSkipsErrorAndShortFrames) {
  cfg.width = 2;
  cfg.height = 2;
  dev->sizes = {discrete(2, 2)};
  auto frame = [](std::uint32_t seq, std::uint8_t v) {
    FakeFrame f;
    f.bytes.assign(4, v);
    f.sequence = seq;
    f.stamp = {1, static_cast<long>(seq)};
    return f;
  };
  dev->frames = {frame(0, 10), frame(1, 11), frame(2, 12), frame(3, 13), frame(6, 16)};
  dev->frames[2].flags |= V4L2_BUF_FLAG_ERROR;  // seq 2: corrupted
  dev->frames[3].bytesused = 3;                 // seq 3: truncated
  auto src = make();
  src->open();
  src->start();
  dsp::Image img(2, 2, dsp::PixelFormat::Mono8);
  FrameMeta meta;
  std::vector<std::uint64_t> seqs;
  while (src->capture(img.view(), meta, std::chrono::milliseconds(0)) == CaptureStatus::Frame) {
    seqs.push_back(meta.sequence);
    EXPECT_EQ(img.data[0], 10 + meta.sequence);
    EXPECT_EQ(meta.first_row_ns, 1'000'000'000 + 1000 * static_cast<std::int64_t>(meta.sequence));
  }
  EXPECT_EQ(seqs, (std::vector<std::uint64_t>{0, 1, 6}));
  EXPECT_EQ(src->stats().frames, 3u);
  EXPECT_EQ(src->stats().dropped, 2u);  // 4 and 5 never came
  EXPECT_EQ(src->stats().error_frames, 1u);
  EXPECT_EQ(src->stats().short_frames, 1u);
  EXPECT_EQ(src->stats().estimated_stamps, 0u);
}

TEST_F(V4l2SourceFake, BufferBookkeepingFollowsWhatTheDriverGrants) {
  dev->grant = 3;  // asked for 4
  auto src = make();
  src->open();
  src->start();
  EXPECT_EQ(dev->maps, 3);
  EXPECT_EQ(dev->queued.size(), 3u);
  EXPECT_TRUE(dev->streaming);
  src->stop();
  EXPECT_FALSE(dev->streaming);
  EXPECT_EQ(dev->unmaps, 3);
  EXPECT_EQ(dev->reqbufs_zero, 1);
  src->start();  // and again after a stop
  EXPECT_EQ(dev->maps, 6);
  EXPECT_EQ(dev->queued.size(), 3u);
}

TEST_F(V4l2SourceFake, NoFrameIsATimeout) {
  auto src = make();
  src->open();
  src->start();
  dsp::Image img(640, 480, dsp::PixelFormat::Mono8);
  FrameMeta meta;
  EXPECT_EQ(src->capture(img.view(), meta, std::chrono::milliseconds(5)), CaptureStatus::Timeout);
}

TEST_F(V4l2SourceFake, ACameraLostDuringCaptureIsACameraError) {
  for (int err : {ENODEV, EIO}) {
    dev->fail = {{"DQBUF", err}};
    auto src = make();
    src->open();
    src->start();
    dsp::Image img(640, 480, dsp::PixelFormat::Mono8);
    FrameMeta meta;
    try {
      src->capture(img.view(), meta, std::chrono::milliseconds(10));
      FAIL() << "no exception for errno " << err;
    } catch (const CameraError& e) {
      EXPECT_NE(std::string(e.what()).find("camera at /dev/video0 lost during VIDIOC_DQBUF"), std::string::npos);
    }
    src->stop();  // must not throw on a lost camera
  }
  dev->fail = {{"DQBUF", EINVAL}};
  auto src = make();
  src->open();
  src->start();
  dsp::Image img(640, 480, dsp::PixelFormat::Mono8);
  FrameMeta meta;
  try {
    src->capture(img.view(), meta, std::chrono::milliseconds(10));
    FAIL() << "no exception";
  } catch (const CameraError&) {
    FAIL() << "EINVAL is not a lost camera";
  } catch (const std::runtime_error&) {
  }
}

TEST_F(V4l2SourceFake, BadInputIsAClearErrorNotACrash) {
  auto src = make();
  src->open();
  FrameMeta meta;
  dsp::Image img(640, 480, dsp::PixelFormat::Mono8);
  EXPECT_THROW(src->capture(img.view(), meta, std::chrono::milliseconds(1)), std::logic_error);  // not started
  src->start();
  dsp::Image wrong(320, 240, dsp::PixelFormat::Mono8);
  EXPECT_THROW(src->capture(wrong.view(), meta, std::chrono::milliseconds(1)), std::invalid_argument);
  cfg.pixel_format = "MJPG";
  try {
    make();
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pixel_format"), std::string::npos);
  }
  cfg.pixel_format = "GREY";
  cfg.fps = 0;
  EXPECT_THROW(make(), std::invalid_argument);
}

// ---- The real device, as far as this machine allows ----------------------------------------

TEST(V4l2Live, ANonexistentDeviceIsNoCamera) {
  V4l2Config cfg;
  cfg.device = "/dev/rsd-test-no-such-video-node";
  V4l2Source src(cfg);
  try {
    src.open();
    FAIL() << "no exception";
  } catch (const CameraError& e) {
    EXPECT_STREQ(e.what(),
                 "no camera at /dev/rsd-test-no-such-video-node (no such device): is the camera plugged in and "
                 "the uvcvideo/driver module loaded?");
  }
}

TEST(V4l2Live, ANodeThatIsNotAVideoDeviceIsRefusedByQuerycap) {
  V4l2Config cfg;
  cfg.device = "/dev/null";  // opens, but answers VIDIOC_QUERYCAP with ENOTTY
  V4l2Source src(cfg);
  try {
    src.open();
    FAIL() << "no exception";
  } catch (const CameraError&) {
    FAIL() << "a wrong node is a configuration error, not a missing camera";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/null is not a V4L2 device"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rsd::drivers
