// The V4L2 source driven through a fake device (tests/support/fake_v4l2_device.hpp): format
// negotiation, capture with padded rows and converted stamps, sequence gaps, buffer
// bookkeeping, lost cameras and bad input; and the real device as far as this machine allows.
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
#include "tests/support/fake_v4l2_device.hpp"

namespace rsd::drivers {
namespace {

using v4l2::Layout;
using namespace rsd::drivers::test;

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
  EXPECT_EQ(src->format().format, dsp::PixelFormat::Yuyv);  // passed through natively
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
    EXPECT_EQ(std::string(e.what()), "/dev/video0 offers none of " + v4l2::pixel_format_names() + " (it offers MJPG, H264)");
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
  dev->sizes = {discrete(4, 4)};  // rsd's smallest frame (dsp/core/input_limits.hpp)
  dev->row_padding = 4;  // bytesperline 4 * 2 + 4 = 12
  cfg.width = 4;
  cfg.height = 4;
  cfg.line_delay_s = 30e-6;
  dev->exposure_100us = 50;
  FakeFrame f;
  f.bytes = yuyv_frame(4, 4, 12);
  f.flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_EOF;
  f.stamp = {100, 0};
  f.sequence = 7;
  dev->frames.push_back(f);
  auto src = make();
  src->open();
  src->start();
  EXPECT_EQ(src->format().format, dsp::PixelFormat::Yuyv);  // passed through, chroma and all
  dsp::Image img(4, 4, dsp::PixelFormat::Yuyv);
  FrameMeta meta;
  ASSERT_EQ(src->capture(img.view(), meta, std::chrono::milliseconds(100)), CaptureStatus::Frame);
  std::vector<std::uint8_t> want;  // the rows without their padding
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) want.insert(want.end(), {static_cast<std::uint8_t>(10 * y + x), 0x80});
  EXPECT_EQ(img.data, want);
  // 4 rows: 100 s - (3 * 30 us + 5 ms) = 99.99491 s.
  EXPECT_EQ(meta.first_row_ns, 99'994'910'000);
  EXPECT_EQ(meta.sequence, 7u);
  EXPECT_DOUBLE_EQ(meta.exposure_s, 5e-3);
  EXPECT_EQ(dev->queued.size(), 4u);  // the buffer went straight back to the driver
}

TEST_F(V4l2SourceFake, CountsSequenceGapsAndSkipsErrorAndShortFrames) {
  cfg.width = 4;
  cfg.height = 4;
  dev->sizes = {discrete(4, 4)};
  auto frame = [](std::uint32_t seq, std::uint8_t v) {
    FakeFrame f;
    f.bytes.assign(16, v);
    f.sequence = seq;
    f.stamp = {1, static_cast<long>(seq)};
    return f;
  };
  dev->frames = {frame(0, 10), frame(1, 11), frame(2, 12), frame(3, 13), frame(6, 16)};
  dev->frames[2].flags |= V4L2_BUF_FLAG_ERROR;  // seq 2: corrupted
  dev->frames[3].bytesused = 15;                // seq 3: truncated
  auto src = make();
  src->open();
  src->start();
  dsp::Image img(4, 4, dsp::PixelFormat::Mono8);
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
  EXPECT_EQ(src->refused(), 2u);  // both counted where rsd.health_t reads them
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
