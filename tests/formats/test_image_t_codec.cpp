// The bot_core.image_t codec (formats/image_t_codec.hpp) at its edges: metadata that is out of
// range, non-finite or absurd is refused naming the field; lengths the generated decoder would
// trust are checked first; and the frame's intrinsics carry either lens.
#include <gtest/gtest.h>

#include <bot_core/image_t.hpp>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "formats/image_t_codec.hpp"

using namespace rsd;
using namespace rsd::formats;

namespace {

constexpr int kW = 32, kH = 24;

}  // namespace

namespace {

// A valid 4x2 mono frame with the given metadata.
bot_core::image_t frame_with(std::vector<std::pair<std::string, std::string>> meta, int64_t utime = 1700000000000000) {
  bot_core::image_t img{};
  img.utime = utime;
  img.width = 4, img.height = 4, img.row_stride = 4;  // rsd's smallest frame
  img.pixelformat = bot_core::image_t::PIXEL_FORMAT_GRAY;
  img.size = 16;
  img.data.assign(16, 0);
  for (const auto& [k, v] : meta) {
    bot_core::image_metadata_t m;
    m.key = k;
    m.value.assign(v.begin(), v.end());
    img.metadata.push_back(m);
  }
  img.nmetadata = static_cast<int32_t>(img.metadata.size());
  return img;
}

std::string refusal(const bot_core::image_t& img) {
  RecordedFrame f;
  std::string why;
  return parse_frame(img, f, why) ? "accepted" : why;
}

}  // namespace

// Issue 16, defect 6: stamps that overflow when scaled to ns and timing that is NaN or absurd
// (a NaN first row converted to int) were accepted and stamped every row wrong.
TEST(RecordedFrame, OutOfRangeStampsAndTimingAreRefusedNamingTheField) {
  EXPECT_EQ(refusal(frame_with({{"frame_utime", "123"}, {"timing", "1e-5 30 0.001 0"}})), "accepted");
  EXPECT_EQ(refusal(frame_with({{"timing", "1e-5 30 0.001 -1"}})), "accepted");  // the natural first row
  EXPECT_EQ(refusal(frame_with({}, INT64_MAX)), "utime 9223372036854775807 is out of range");
  EXPECT_EQ(refusal(frame_with({{"frame_utime", "-9223372036854775807"}})),
            "metadata frame_utime -9223372036854775807 is out of range");
  EXPECT_NE(refusal(frame_with({{"timing", "nan 30 0.001 0"}})).find("timing (line delay)"), std::string::npos);
  EXPECT_NE(refusal(frame_with({{"timing", "1e-5 -30 0.001 0"}})).find("timing (frame rate)"), std::string::npos);
  // Issue 38: a frame rate of 5e-324 was accepted, then inf published as line delay and
  // reference time; a first row time near INT64_MAX overflowed the rectifier's sums.
  EXPECT_EQ(refusal(frame_with({{"timing", "1e-5 5e-324 0.001 0"}})), "metadata timing (frame rate) 5e-324 is out of range");
  EXPECT_EQ(refusal(frame_with({{"frame_ns", "9223372036854775000"}})), "metadata frame_ns 9223372036854775000 is out of range");
  EXPECT_EQ(refusal(frame_with({{"frame_utime", "2305843009213693"}})), "accepted");  // 2^61 ns, the window's edge
  EXPECT_EQ(refusal(frame_with({{"frame_utime", "2305843009213693"}, {"intrinsics", "1e300 500 2 1 0 0 0 0 0"}})),
            "metadata intrinsics: fx 1e+300 is outside 1..1e7 pixels");
  EXPECT_NE(refusal(frame_with({{"timing", "1e-5 30 0.001 nan"}})).find("timing (first row)"), std::string::npos);
  EXPECT_NE(refusal(frame_with({{"timing", "1e-5 30 0.001 4"}})).find("timing (first row)"), std::string::npos);
  EXPECT_NE(refusal(frame_with({{"timing", "1e-5 30 0.001 -2"}})).find("timing (first row)"), std::string::npos);
  EXPECT_NE(refusal(frame_with({{"exposure_s", "inf"}})).find("exposure"), std::string::npos);
  EXPECT_NE(refusal(frame_with({{"line_delay_ns", "-5"}})).find("line_delay_ns"), std::string::npos);
  EXPECT_NE(refusal(frame_with({{"intrinsics", "500 500 2 1 inf 0 0 0 0"}})).find("not finite"), std::string::npos);
  EXPECT_NE(refusal(frame_with({{"intrinsics", "0 500 2 1 0 0 0 0 0"}})).find("not positive"), std::string::npos);
  // Without frame_utime the first row's time is the utime (rsd-sim and older logs).
  RecordedFrame f;
  std::string why;
  ASSERT_TRUE(parse_frame(frame_with({}, 42), f, why)) << why;
  EXPECT_EQ(f.meta.first_row_ns, 42000);
}

// Found by fuzzing (tests/fuzz/corpus/lcm_message/crash-health-negative-string-length):
// lcm-gen's decoders check a string's length against the payload's end but not its sign, and
// std::string::assign threw std::length_error through decode_checked. Every length of every
// type is now checked generically (test_lcm_layout_check); this is the case as found.
TEST(RecordedFrame, AStringWithANegativeLengthIsRefusedNotAnException) {
  rsd::health_t h{};
  h.source = "sim";
  h.source_state = "streaming";
  std::vector<uint8_t> b(static_cast<size_t>(h.getEncodedSize()));
  ASSERT_EQ(h.encode(b.data(), 0, static_cast<int>(b.size())), static_cast<int>(b.size()));
  std::string why;
  rsd::health_t back;
  ASSERT_EQ(decode_checked(b.data(), b.size(), back, why), DecodeStatus::Ok);
  EXPECT_EQ(back.source_state, "streaming");
  for (const uint32_t len : {0xfffffff0u, 0u}) {
    const size_t at = 8 + 8;  // fingerprint, utime, then the source's length
    for (int i = 0; i < 4; ++i) b[at + i] = static_cast<uint8_t>(len >> (24 - 8 * i));
    EXPECT_EQ(decode_checked(b.data(), b.size(), back, why), DecodeStatus::AbsurdSize) << len;
    EXPECT_EQ(why.rfind("rsd.health_t.source has a string length of ", 0), 0u) << why;
  }
}

// The frame's intrinsics carry the lens: "fx fy cx cy k1 k2 p1 p2 k3" for pinhole-radtan, and
// k4 with the lens's name for pinhole-equi; written by the encoder, read back exactly.
TEST(RecordedFrame, AnEquidistantLensTravelsWithItsName) {
  dsp::CameraModel cam = dsp::CameraModel::from_hfov(kW, kH, 2.0);
  cam.dist = dsp::Distortion::equidistant(0.0469, -0.0135, 0.0021, -1.0 / 3000);
  RawFrameEncoder enc({kW, kH, dsp::PixelFormat::Mono8}, dsp::RowTiming::full_frame(kH, 30), cam);
  dsp::Image img(kW, kH, dsp::PixelFormat::Mono8);
  FrameMeta meta;
  meta.first_row_ns = 1000;
  const size_t n = enc.encode(img.view(), meta);
  bot_core::image_t decoded;
  RecordedFrame f;
  std::string why;
  ASSERT_EQ(decode_frame(enc.data(), n, decoded, f, why), DecodeStatus::Ok) << why;
  ASSERT_TRUE(f.camera);
  EXPECT_EQ(f.camera->dist, cam.dist);
  EXPECT_EQ(f.camera->fx, cam.fx);
  // Written by hand: the name decides; an unknown one is no intrinsics, a tangential term refused.
  RecordedFrame g;
  ASSERT_TRUE(parse_frame(frame_with({{"intrinsics", "500 500 2 1 0.1 0.2 0 0 0.3 0.4 pinhole-equi"}}), g, why)) << why;
  ASSERT_TRUE(g.camera);
  EXPECT_EQ(g.camera->dist, dsp::Distortion::equidistant(0.1, 0.2, 0.3, 0.4));
  RecordedFrame h;
  ASSERT_TRUE(parse_frame(frame_with({{"intrinsics", "500 500 2 1 0.1 0.2 0 0 0.3 0.4 fisheye"}}), h, why));
  EXPECT_FALSE(h.camera);
  EXPECT_EQ(refusal(frame_with({{"intrinsics", "500 500 2 1 0.1 0.2 0.01 0 0.3 0.4 pinhole-equi"}})),
            "metadata intrinsics: the pinhole-equi lens has no tangential terms (p1, p2)");
}
