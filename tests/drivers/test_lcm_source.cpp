// The lcm source on what a network may bring (issue 16, defect 6): frames with NaN timing or
// stamps that repeat or go back were published; a frame of another size. Here a log played through LCM's own file
// provider feeds the source: every good frame comes out in order, each bad one is refused and
// counted by reason.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "drivers/lcm_source.hpp"
#include "formats/image_t_codec.hpp"
#include "formats/lcm_log.hpp"
#include "tests/support/temp_dir.hpp"

namespace rsd::drivers {
namespace {

const test::TempDir& g_tmp = test::register_temp_dir("rsd_test_lcm_source_");

constexpr int kW = 16, kH = 8;

struct Sent {
  int64_t first_row_ns;
  double line_delay_s;
  int width = kW;  // another size than the first frame's: refused
};

std::string write_log(const std::vector<Sent>& frames) {
  const std::string path = g_tmp.path("frames.lcmlog");
  formats::LcmLogWriter log(path);
  int64_t t_us = 1;
  for (size_t i = 0; i < frames.size(); ++i) {
    dsp::Image img(frames[i].width, kH, dsp::PixelFormat::Mono8);
    dsp::RowTiming timing = dsp::RowTiming::full_frame(kH, 30);
    timing.line_delay_s = frames[i].line_delay_s;
    formats::RawFrameEncoder enc({frames[i].width, kH, dsp::PixelFormat::Mono8}, timing, std::nullopt);
    FrameMeta meta;
    meta.first_row_ns = frames[i].first_row_ns;
    meta.sequence = i;
    img.data.assign(img.data.size(), static_cast<uint8_t>(i));
    const size_t n = enc.encode(img.view(), meta);
    EXPECT_GT(n, 0u);
    log.write("RSD_RAW", t_us += 1000, enc.data(), n);
  }
  return path;
}

// What the source delivers of a log played through LCM's file provider: each frame's stamp and
// first pixel (the frame's index in the log).
struct Played {
  std::vector<int64_t> stamps;
  std::vector<int> pixels;
};
Played play(LcmSource& src) {
  src.open();
  src.start();
  dsp::Image img(kW, kH, dsp::PixelFormat::Mono8);
  Played out;
  FrameMeta meta;
  while (src.capture(img.view(), meta, std::chrono::milliseconds(500)) == CaptureStatus::Frame) {
    out.stamps.push_back(meta.first_row_ns);
    out.pixels.push_back(img.data[0]);
  }
  return out;
}

LcmSourceConfig config_for(const std::string& log) {
  LcmSourceConfig cfg;
  cfg.url = "file://" + log + "?speed=0";
  return cfg;
}

TEST(LcmSource, RefusesFramesWithBadTimingOrStampsThatDoNotAdvance) {
  const double good = 1e-3 / kH;
  const std::string log = write_log({{1'000'000'000, good},
                                     {1'033'000'000, good},
                                     {1'033'000'000, good},   // repeated
                                     {500'000'000, good},     // backwards
                                     {1'050'000'000, std::numeric_limits<double>::quiet_NaN()},
                                     {1'060'000'000, good, kW / 2},  // another size
                                     {1'066'000'000, good}});
  LcmSource src(config_for(log));
  const Played got = play(src);
  EXPECT_EQ(got.stamps, (std::vector<int64_t>{1'000'000'000, 1'033'000'000, 1'066'000'000}));
  EXPECT_EQ(got.pixels, (std::vector<int>{0, 1, 6}));
  EXPECT_EQ(src.skipped(formats::LogSkip::OutOfOrder), 2u);
  EXPECT_EQ(src.skipped(formats::LogSkip::Undecodable), 2u);  // NaN timing, another size
  EXPECT_EQ(src.refused(), 4u);
}

// Issue 38, defect 2: one frame stamped far in the future (+1e15 ns, INT64_MAX) was taken as the
// newest, and every later frame was "out of order" until a reconnection. Now the wild frame
// alone is refused; and a stream whose clock really restarts is followed from its third frame.
TEST(LcmSource, AWildStampCostsThatFrameAloneAndARestartedClockIsFollowed) {
  const double good = 1e-3 / kH;
  const std::string log = write_log({{1'000'000'000, good},
                                     {1'000'000'000 + 1'000'000'000'000'000, good},  // +1e15 ns
                                     {1'033'000'000, good},
                                     {std::numeric_limits<int64_t>::max(), good},
                                     {1'066'000'000, good},
                                     {5'000'000, good},  // the sender's clock restarted
                                     {38'000'000, good},
                                     {71'000'000, good},
                                     {104'000'000, good}});
  LcmSource src(config_for(log));
  EXPECT_EQ(play(src).pixels, (std::vector<int>{0, 2, 4, 7, 8}));
  EXPECT_EQ(src.skipped(formats::LogSkip::OutOfOrder), 3u);   // the wild one, two held before the restart was sure
  EXPECT_EQ(src.skipped(formats::LogSkip::Undecodable), 1u);  // INT64_MAX: outside rsd's window for times
}

}  // namespace
}  // namespace rsd::drivers
