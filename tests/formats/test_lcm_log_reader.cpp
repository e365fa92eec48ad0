// The robust LCM log reader and writer (formats/lcm_log.hpp), the recorded-frame convention
// (formats/image_t_codec.hpp) and the replay source on damaged logs: a log written by our
// writer reads back with LCM's own reader; each kind of damage (broken sync word, absurd
// sizes, truncation, unknown channel, wrong fingerprint, corrupt image size) skips exactly the
// damaged event with a count and a message naming the file and byte offset, and the rest
// replays.
#include <gtest/gtest.h>

#include <bot_core/image_t.hpp>
#include <bot_core/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <rsd/frame_info_t.hpp>
#include <rsd/health_t.hpp>
#include <rsd/velocity_t.hpp>

#include <filesystem>
#include <fstream>
#include <random>

#include "formats/lcm_log.hpp"
#include "formats/motion_log.hpp"
#include "tests/support/temp_dir.hpp"
#include "formats/image_t_codec.hpp"
#include "drivers/replay_source.hpp"

using namespace rsd;
using namespace rsd::drivers;
using namespace rsd::formats;

namespace test_lcm_log_reader {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

constexpr int kFrames = 10, kW = 32, kH = 24;

// The logs this process wrote go when it ends.
const test::TempDir& g_tmp = test::register_temp_dir("rsd_test_lcm_log_");
std::string tmp(const std::string& name) { return g_tmp.path(name); }

std::vector<uint8_t> velocity_bytes(int64_t utime, double wz) {
  rsd::velocity_t m{};
  m.utime = utime;
  m.frame = rsd::velocity_t::FRAME_CAMERA;
  m.angular_velocity[2] = wz;
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

struct Written {
  std::string path;
  std::vector<uint64_t> frame_offsets, velocity_offsets;  // sync word of each event
  std::vector<uint8_t> bytes;
};

// kFrames frames (pixel value = frame index) each preceded by one velocity message.
Written write_good_log(const std::string& name) {
  Written w;
  w.path = tmp(name);
  {
    LcmLogWriter log(w.path);
    dsp::Image img(kW, kH, dsp::PixelFormat::Mono8);
    dsp::RowTiming t = dsp::RowTiming::full_frame(kH, 30);
    dsp::CameraModel cam = dsp::CameraModel::from_hfov(kW, kH, 1.0);
    RawFrameEncoder enc({kW, kH, dsp::PixelFormat::Mono8}, t, cam);
    uint64_t pos = 0;
    for (int k = 0; k < kFrames; ++k) {
      const int64_t t_us = k * 33333;
      const auto v = velocity_bytes(t_us, 0.1 * k);
      w.velocity_offsets.push_back(pos);
      log.write("RSD_VELOCITY", t_us, v.data(), v.size());
      pos += 28 + 12 + v.size();
      std::fill(img.data.begin(), img.data.end(), static_cast<uint8_t>(k));
      FrameMeta meta;
      meta.first_row_ns = t_us * 1000 + 7;  // ns precision survives (frame_ns)
      meta.sequence = static_cast<uint64_t>(k);
      meta.exposure_s = 0.001;
      const size_t n = enc.encode(img.view(), meta);
      w.frame_offsets.push_back(pos);
      log.write("RSD_RAW", t_us + 33000, enc.data(), n);
      pos += 28 + 7 + n;
    }
  }
  std::ifstream in(w.path, std::ios::binary);
  w.bytes.assign(std::istreambuf_iterator<char>(in), {});
  return w;
}

std::string save(const std::string& name, const std::vector<uint8_t>& bytes) {
  const std::string p = tmp(name);
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  return p;
}

void put32(std::vector<uint8_t>& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + static_cast<size_t>(i)] = static_cast<uint8_t>(v >> (24 - 8 * i));
}

struct Read {
  int frames = 0, velocity = 0;
  std::vector<std::string> messages;
};

Read read_all(LcmLogReader& r) {
  Read out;
  r.set_message_handler([&](const std::string& m) { out.messages.push_back(m); });
  LogEvent ev;
  while (r.next(ev)) (ev.channel == "RSD_RAW" ? out.frames : out.velocity)++;
  return out;
}

struct Replayed {
  std::vector<int> pixels;  // first pixel of each frame delivered
  std::vector<std::string> messages;
  std::unique_ptr<ReplaySource> src;
};

Replayed replay_all(const std::string& path, double speed = 0) {
  Replayed out;
  ReplayConfig c;
  c.file = path;
  c.speed = speed;
  out.src = std::make_unique<ReplaySource>(c);
  out.src->open();
  const_cast<LcmLogReader*>(out.src->reader())->set_message_handler([&](const std::string& m) { out.messages.push_back(m); });
  out.src->start();
  dsp::Image img(kW, kH, dsp::PixelFormat::Mono8);
  FrameMeta meta;
  for (int guard = 0; guard < 1000; ++guard) {
    const CaptureStatus st = out.src->capture(img.view(), meta, std::chrono::milliseconds(100));
    if (st == CaptureStatus::EndOfStream) break;
    if (st == CaptureStatus::Frame) out.pixels.push_back(img.data[0]);
  }
  return out;
}

bool any_contains(const std::vector<std::string>& v, const std::string& s) {
  for (const auto& m : v)
    if (m.find(s) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST(LcmLog, WriterOutputReadsBackWithLcmsOwnReaderAndOurs) {
  const Written w = write_good_log("good.lcmlog");
  lcm::LogFile lf(w.path, "r");
  ASSERT_TRUE(lf.good());
  int n = 0;
  while (const lcm::LogEvent* ev = lf.readNextEvent()) {
    EXPECT_EQ(ev->eventnum, n);
    EXPECT_EQ(ev->channel, n % 2 ? "RSD_RAW" : "RSD_VELOCITY");
    ++n;
  }
  EXPECT_EQ(n, 2 * kFrames);
  LcmLogReader r(w.path);
  const Read got = read_all(r);
  EXPECT_EQ(got.frames, kFrames);
  EXPECT_EQ(got.velocity, kFrames);
  EXPECT_EQ(r.skipped_total(), 0u);
  EXPECT_TRUE(got.messages.empty());
  EXPECT_TRUE(looks_like_lcm_log(w.path));
}

// rsd-extract's first pass says how far into a long log it is: after each frame, the bytes up to
// the end of that frame's event (where the writer put the next event), and the end once.
TEST(MotionLog, ProgressFollowsEveryFrameAndSaysTheEndOnce) {
  const Written w = write_good_log("progress.lcmlog");
  std::vector<std::pair<uint64_t, uint64_t>> calls;
  const MotionLog s = read_motion_log(w.path, {}, [&](uint64_t read, uint64_t size) { calls.emplace_back(read, size); });
  ASSERT_EQ(s.frames.size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(calls.size(), static_cast<size_t>(kFrames + 1));
  for (int k = 0; k + 1 < kFrames; ++k) EXPECT_EQ(calls[k].first, w.velocity_offsets[k + 1]) << "frame " << k;
  for (int k = kFrames - 1; k <= kFrames; ++k) EXPECT_EQ(calls[k].first, w.bytes.size()) << "call " << k;
  for (const auto& c : calls) EXPECT_EQ(c.second, w.bytes.size());
}

TEST(LcmLog, RecordedFrameKeepsExactTimingAndIntrinsics) {
  const Written w = write_good_log("exact.lcmlog");
  ReplayConfig c;
  c.file = w.path;
  ReplaySource src(c);
  src.open();
  const dsp::RowTiming t = dsp::RowTiming::full_frame(kH, 30);
  EXPECT_EQ(src.timing().line_delay_s, t.line_delay_s);  // bit-exact through "%.17g"
  EXPECT_EQ(src.timing().frame_rate_hz, 30.0);
  EXPECT_EQ(src.timing().exposure_s, 0.001);
  const dsp::CameraModel cam = dsp::CameraModel::from_hfov(kW, kH, 1.0);
  ASSERT_TRUE(src.recorded_camera());
  EXPECT_EQ(src.recorded_camera()->fx, cam.fx);
  EXPECT_EQ(src.recorded_camera()->cx, cam.cx);
  src.start();
  dsp::Image img(kW, kH, dsp::PixelFormat::Mono8);
  FrameMeta meta;
  std::vector<int64_t> velocity_us;
  src.set_velocity_message_sink([&](const rsd::velocity_t& m) { velocity_us.push_back(m.utime); });
  ASSERT_EQ(src.capture(img.view(), meta, std::chrono::milliseconds(100)), CaptureStatus::Frame);
  ASSERT_EQ(src.capture(img.view(), meta, std::chrono::milliseconds(100)), CaptureStatus::Frame);
  EXPECT_EQ(meta.first_row_ns, 33333000 + 7);
  EXPECT_EQ(meta.sequence, 1u);
  EXPECT_EQ(img.data[5], 1);
  EXPECT_EQ(velocity_us, (std::vector<int64_t>{0, 33333}));  // each before its frame
}

TEST(LcmLog, BrokenSyncWordSkipsThatEventAndResynchronises) {
  Written w = write_good_log("sync.lcmlog");
  w.bytes[w.frame_offsets[3]] ^= 0xff;
  const std::string p = save("sync-bad.lcmlog", w.bytes);
  LcmLogReader r(p);
  const Read got = read_all(r);
  EXPECT_EQ(got.frames, kFrames - 1);
  EXPECT_EQ(got.velocity, kFrames);
  EXPECT_EQ(r.skipped(LogSkip::BadSync), 1u);
  EXPECT_EQ(r.skipped_total(), 1u);
  ASSERT_EQ(got.messages.size(), 1u);
  EXPECT_NE(got.messages[0].find(p + ": event at byte " + std::to_string(w.frame_offsets[3]) + ": broken sync word"),
            std::string::npos) << got.messages[0];
}

TEST(LcmLog, TruncatedLastEventIsCountedAndTheRestReads) {
  Written w = write_good_log("trunc.lcmlog");
  w.bytes.resize(w.frame_offsets[kFrames - 1] + 100);  // inside the last frame's data
  const std::string p = save("trunc-bad.lcmlog", w.bytes);
  LcmLogReader r(p);
  const Read got = read_all(r);
  EXPECT_EQ(got.frames, kFrames - 1);
  EXPECT_EQ(r.skipped(LogSkip::Truncated), 1u);
  EXPECT_TRUE(any_contains(got.messages, "byte " + std::to_string(w.frame_offsets[kFrames - 1]) + ": truncated"));
  // Cut inside a header, too.
  w.bytes.resize(w.frame_offsets[kFrames - 1] + 10);
  LcmLogReader r2(save("trunc-header.lcmlog", w.bytes));
  EXPECT_EQ(read_all(r2).frames, kFrames - 1);
  EXPECT_EQ(r2.skipped(LogSkip::Truncated), 1u);
}

TEST(LcmLog, AbsurdLengthsAreSkippedWithoutAllocatingThem) {
  Written w = write_good_log("absurd.lcmlog");
  put32(w.bytes, w.frame_offsets[2] + 24, 0x7ffffff0u);  // data length: 2 GiB
  put32(w.bytes, w.frame_offsets[5] + 20, 5000);         // channel length beyond LCM's 63
  put32(w.bytes, w.frame_offsets[7] + 24, 1u << 20);     // within limits, but past the end of the file
  LcmLogReader r(save("absurd-bad.lcmlog", w.bytes));
  const Read got = read_all(r);
  EXPECT_EQ(got.frames, kFrames - 3);
  EXPECT_EQ(got.velocity, kFrames);
  EXPECT_EQ(r.skipped(LogSkip::AbsurdSize), 3u);
  EXPECT_TRUE(any_contains(got.messages, "data length 2147483632"));
}

TEST(LcmLog, GarbageAndEmptyFilesEndQuickly) {
  std::vector<uint8_t> junk(100000);
  std::mt19937 rng(3);
  for (auto& b : junk) b = static_cast<uint8_t>(rng());
  const std::string p = save("junk.lcmlog", junk);
  LcmLogReader r(p);
  r.set_message_handler({});
  LogEvent ev;
  EXPECT_FALSE(r.next(ev));
  EXPECT_EQ(r.skipped(LogSkip::BadSync), 1u);
  ReplayConfig c;
  c.file = p;
  ReplaySource src(c);
  try {
    src.open();
    FAIL() << "a log without frames must not open";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(p + ": no usable raw frame"), std::string::npos) << e.what();
  }
  c.file = save("empty.lcmlog", {});
  ReplaySource empty(c);
  EXPECT_THROW(empty.open(), std::runtime_error);
  c.file = tmp("does-not-exist.lcmlog");
  ReplaySource missing(c);
  EXPECT_THROW(missing.open(), std::runtime_error);
}

TEST(LcmLog, ImageWithCorruptSizeFieldIsRefusedBeforeDecoding) {
  Written w = write_good_log("imgsize.lcmlog");
  // The image_t `size` field: after sync+header (28), channel (7), hash, utime, 4 x int32.
  put32(w.bytes, w.frame_offsets[4] + 28 + 7 + 8 + 8 + 16, 0x7fffffffu);
  std::string why;
  const size_t payload = w.frame_offsets[5] - w.frame_offsets[4] - 35 - (28 + 12 + velocity_bytes(0, 0).size());
  EXPECT_EQ(check_image_t(w.bytes.data() + w.frame_offsets[4] + 35, payload, why), DecodeStatus::AbsurdSize);
  EXPECT_NE(why.find("bot_core.image_t.data has more elements than the payload has bytes (size = 2147483647)"), std::string::npos) << why;
  const Replayed got = replay_all(save("imgsize-bad.lcmlog", w.bytes));
  EXPECT_EQ(got.pixels, (std::vector<int>{0, 1, 2, 3, 5, 6, 7, 8, 9}));
  EXPECT_EQ(got.src->reader()->skipped(LogSkip::AbsurdSize), 1u);
}

void put64(std::vector<uint8_t>& b, size_t at, uint64_t v) {
  put32(b, at, static_cast<uint32_t>(v >> 32));
  put32(b, at + 4, static_cast<uint32_t>(v));
}

// Issue 38, defect 8 (and 5): one wild event time stalled a real-time replay for good (the
// pacer waited for the year 2057), and INT64_MIN/MAX overflowed its arithmetic. An event time
// outside rsd's window is refused before any arithmetic; one inside it but off the log's time
// line plays at once. At speed 1 every frame comes out (a stall would end the capture loop's
// guard of a thousand timeouts first).
TEST(LcmLog, WildEventTimesNeitherStallNorOverflowARealTimeReplay) {
  Written w = write_good_log("wild-times.lcmlog");
  put64(w.bytes, w.velocity_offsets[3] + 12, static_cast<uint64_t>(INT64_MAX));
  put64(w.bytes, w.velocity_offsets[5] + 12, static_cast<uint64_t>(INT64_MIN));
  put64(w.bytes, w.velocity_offsets[7] + 12, 1'000'000'000'000'000ULL);  // 31 years on: within the window
  const Replayed got = replay_all(save("wild-times-bad.lcmlog", w.bytes), 1.0);
  EXPECT_EQ(got.pixels, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
  EXPECT_EQ(got.src->reader()->skipped(LogSkip::Undecodable), 2u);
  EXPECT_TRUE(any_contains(got.messages, "event time 9223372036854775807 us is out of range"));
}

// Every defect in one log: each skipped once with its reason, every good frame replayed in
// order, and the summary says what happened.
TEST(LcmLog, ReplaySkipsEachDefectWithItsReasonAndReplaysTheRest) {
  Written w = write_good_log("all.lcmlog");
  std::vector<uint8_t> b = w.bytes;
  b[w.frame_offsets[1] + 1] = 0;                         // frame 1: broken sync word
  put32(b, w.frame_offsets[3] + 24, 0x7ffffff0u);        // frame 3: absurd data length
  b.resize(w.frame_offsets[kFrames - 1] + 200);          // frame 9: truncated
  // An unknown channel and a velocity_t payload on RSD_RAW (wrong fingerprint), after frame 5.
  std::vector<uint8_t> extra;
  {
    const std::string p = tmp("extra.lcmlog");
    {
      LcmLogWriter log(p);
      const auto v = velocity_bytes(5, 0);
      log.write("SOMEONE_ELSES_CHANNEL", 5, v.data(), v.size());
      log.write("RSD_RAW", 5, v.data(), v.size());
      log.write("RSD_RECT", 5, v.data(), v.size());  // a recorded output: ignored, not an error
    }
    std::ifstream in(p, std::ios::binary);
    extra.assign(std::istreambuf_iterator<char>(in), {});
  }
  b.insert(b.begin() + static_cast<std::ptrdiff_t>(w.velocity_offsets[6]), extra.begin(), extra.end());
  const std::string p = save("all-bad.lcmlog", b);
  const Replayed got = replay_all(p);
  EXPECT_EQ(got.pixels, (std::vector<int>{0, 2, 4, 5, 6, 7, 8}));
  const LcmLogReader& r = *got.src->reader();
  EXPECT_EQ(r.skipped(LogSkip::BadSync), 1u);
  EXPECT_EQ(r.skipped(LogSkip::AbsurdSize), 1u);
  EXPECT_EQ(r.skipped(LogSkip::Truncated), 1u);
  EXPECT_EQ(r.skipped(LogSkip::UnknownChannel), 1u);
  EXPECT_EQ(r.skipped(LogSkip::WrongFingerprint), 1u);
  EXPECT_EQ(r.skipped_total(), 5u);
  EXPECT_EQ(got.src->ignored(), 1u);
  EXPECT_EQ(got.src->velocity_messages(), static_cast<uint64_t>(kFrames));
  EXPECT_EQ(r.skip_summary(), "1 broken sync word, 1 absurd size, 1 truncated, 1 unknown channel, 1 wrong fingerprint");
  EXPECT_TRUE(any_contains(got.messages, p + ": event at byte " + std::to_string(w.frame_offsets[1]) + ": broken sync word"));
  EXPECT_TRUE(any_contains(got.messages, "unknown channel: channel 'SOMEONE_ELSES_CHANNEL'"));
  EXPECT_TRUE(any_contains(got.messages, "wrong fingerprint: channel 'RSD_RAW': not a bot_core.image_t"));
}

// bot_core.pose_t on the daemon's pose channel replays in log order, before the frame it
// precedes; without a pose channel configured the same events count as unknown.
TEST(LcmLog, PoseMessagesReplayInOrderOnThePoseChannel) {
  Written w = write_good_log("pose.lcmlog");
  std::vector<uint8_t> extra;
  {
    const std::string p = tmp("pose-extra.lcmlog");
    {
      LcmLogWriter log(p);
      bot_core::pose_t m{};
      m.utime = 4242;
      m.rotation_rate[1] = 0.5;
      std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
      m.encode(b.data(), 0, static_cast<int>(b.size()));
      log.write("POSE", 4242, b.data(), b.size());
    }
    std::ifstream in(p, std::ios::binary);
    extra.assign(std::istreambuf_iterator<char>(in), {});
  }
  w.bytes.insert(w.bytes.begin() + static_cast<std::ptrdiff_t>(w.frame_offsets[2]), extra.begin(), extra.end());
  const std::string p = save("pose-in.lcmlog", w.bytes);
  ReplayConfig c;
  c.file = p;
  c.speed = 0;
  ReplaySource src(c);
  std::vector<std::string> order;
  src.set_pose_message_sink("POSE", [&](const bot_core::pose_t& m) {
    EXPECT_EQ(m.utime, 4242);
    EXPECT_EQ(m.rotation_rate[1], 0.5);
    order.push_back("pose");
  });
  src.set_velocity_message_sink([&](const rsd::velocity_t&) { order.push_back("velocity"); });
  src.open();
  src.start();
  dsp::Image img(kW, kH, dsp::PixelFormat::Mono8);
  FrameMeta meta;
  while (src.capture(img.view(), meta, std::chrono::milliseconds(100)) == CaptureStatus::Frame)
    order.push_back("frame" + std::to_string(meta.sequence));
  ASSERT_GE(order.size(), 7u);
  EXPECT_EQ(std::vector<std::string>(order.begin(), order.begin() + 7),
            (std::vector<std::string>{"velocity", "frame0", "velocity", "frame1", "velocity", "pose", "frame2"}));
  EXPECT_EQ(src.pose_messages(), 1u);
  EXPECT_EQ(src.reader()->skipped_total(), 0u);
  const Replayed without = replay_all(p);  // no pose channel configured: unknown, skipped
  EXPECT_EQ(without.pixels.size(), static_cast<size_t>(kFrames));
  EXPECT_EQ(without.src->reader()->skipped(LogSkip::UnknownChannel), 1u);
}

TEST(ReplayPacer, RealTimeAndFactorsFollowTheLogsClock) {
  for (const double speed : {1.0, 4.0}) {
    ReplayPacer p(speed);
    const auto t0 = std::chrono::steady_clock::now();
    for (int64_t us = 0; us <= 200000; us += 20000) ASSERT_TRUE(p.wait(us, std::chrono::seconds(1)));
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_GE(s, 0.2 / speed * 0.99);
    EXPECT_LT(s, 0.2 / speed + 0.15);
  }
  ReplayPacer fast(0);
  EXPECT_TRUE(fast.wait(0, std::chrono::milliseconds(0)));
  EXPECT_TRUE(fast.wait(1000000000, std::chrono::milliseconds(0)));  // never waits
  double s = 0;
  EXPECT_TRUE(parse_speed("fast", s) && s == 0);
  EXPECT_TRUE(parse_speed("2.5", s) && s == 2.5);
  EXPECT_FALSE(parse_speed("-1", s));
  EXPECT_FALSE(parse_speed("0", s));
  EXPECT_FALSE(parse_speed("2x", s));
}

}  // namespace test_lcm_log_reader
