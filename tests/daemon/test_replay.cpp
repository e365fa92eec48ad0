// Record -> replay -> identical outputs, through the whole service (run_service, in process):
// a simulated run recorded with --record is replayed twice as fast as possible, each replay
// recorded too; the rectified images and frame infos of the two replays are identical byte
// for byte, and equal to the live run's (all but the pipeline's own counters: sequence and
// drops_total, which depend on what the live pipeline dropped). A replay with a different
// rectification setting differs (the comparison can fail). Also: the hot path with recording
// on makes no heap allocation, a damaged log replays the rest through the service, and the
// replay speed is honoured.
#include <gtest/gtest.h>

#include <bot_core/image_t.hpp>
#include <rsd/frame_info_t.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include "daemon/pipeline.hpp"
#include "daemon/recording_source.hpp"
#include "daemon/service.hpp"
#include "daemon/velocity_input.hpp"
#include "formats/lcm_log.hpp"
#include "formats/image_t_codec.hpp"
#include "drivers/sim_source.hpp"
#include "tests/support/temp_dir.hpp"
#include "drivers/replay_source.hpp"

#include "tests/support/allocation_counter.hpp"  // every C++ allocation of this process, counted
#include "tests/support/sanitizer.hpp"

using namespace rsd;

namespace {

// The logs this process wrote go when it ends.
const test::TempDir& g_tmp = test::register_temp_dir("rsd_test_replay_");
std::string tmp(const std::string& name) { return g_tmp.path(name); }

daemon::Config sim_config(const std::string& record) {
  daemon::Config c;
  c.source.settings_of<drivers::SimSourceConfig>("sim").camera = dsp::CameraModel::from_hfov(160, 120, 1.0);
  c.source.settings_of<drivers::SimSourceConfig>("sim").fps = 30;
  c.source.settings_of<drivers::SimSourceConfig>("sim").realtime = true;  // a live camera
  c.record_file = record;
  return c;
}

daemon::Config replay_config(const std::string& log, const std::string& record, double speed = 0) {
  daemon::Config c;
  c.source.driver = "replay";
  c.source.settings_of<drivers::ReplayConfig>("replay").file = log;
  c.source.settings_of<drivers::ReplayConfig>("replay").speed = speed;
  c.record_file = record;
  return c;
}

daemon::RunSummary run(const daemon::Config& c, uint64_t frames = 0) {
  daemon::StopFlags flags;
  daemon::RunLimits limits;
  limits.max_frames = frames;
  limits.max_seconds = 60;
  limits.status_line = false;
  daemon::RunSummary s;
  daemon::run_service(c, flags, limits, {}, &s);
  return s;
}

struct Output {
  std::vector<uint8_t> rect_event;  // the RSD_RECT message as recorded
  bot_core::image_t rect;
  rsd::frame_info_t info;
  bool has_rect = false, has_info = false;
};

struct Recording {
  std::map<int64_t, Output> by_utime;  // outputs by the frame's first-row time
  int raw = 0, velocity = 0;
};

// The rectified image's first-row time on the monotonic clock (its utime is Unix time, which
// frame_info_t does not carry): the key that pairs it with its frame_info_t.
int64_t frame_utime(const bot_core::image_t& img) {
  for (int i = 0; i < img.nmetadata; ++i)
    if (img.metadata[i].key == "frame_utime")
      return std::stoll(std::string(img.metadata[i].value.begin(), img.metadata[i].value.end()));
  ADD_FAILURE() << "a rectified image without frame_utime";
  return -1;
}

Recording read_recording(const std::string& path) {
  Recording r;
  formats::LcmLogReader reader(path);
  formats::LogEvent ev;
  std::string why;
  while (reader.next(ev)) {
    if (ev.channel == "RSD_RAW") ++r.raw;
    if (ev.channel == "RSD_VELOCITY") ++r.velocity;
    if (ev.channel == "RSD_RECT") {
      bot_core::image_t img;
      EXPECT_EQ(formats::decode_checked(ev.data.data(), ev.data.size(), img, why), formats::DecodeStatus::Ok);
      Output& o = r.by_utime[frame_utime(img)];
      o.rect_event = ev.data;
      o.rect = img;
      o.has_rect = true;
    }
    if (ev.channel == "RSD_FRAME_INFO") {
      rsd::frame_info_t info;
      EXPECT_EQ(formats::decode_checked(ev.data.data(), ev.data.size(), info, why), formats::DecodeStatus::Ok);
      Output& o = r.by_utime[info.utime];
      o.info = info;
      o.has_info = true;
    }
  }
  EXPECT_EQ(reader.skipped_total(), 0u) << reader.skip_summary();
  return r;
}

// Every field of frame_info_t but the pipeline's counters (sequence, drops_total).
void expect_same_info(const rsd::frame_info_t& a, const rsd::frame_info_t& b, int64_t utime) {
  SCOPED_TRACE("frame at utime " + std::to_string(utime));
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.source_sequence, b.source_sequence);
  EXPECT_EQ(a.line_delay_s, b.line_delay_s);
  EXPECT_EQ(a.readout, b.readout);
  EXPECT_EQ(a.exposure_s, b.exposure_s);
  EXPECT_EQ(a.reference_time_s, b.reference_time_s);
  EXPECT_EQ(a.rectified, b.rectified);
  EXPECT_EQ(a.unrectified_reason, b.unrectified_reason);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(a.angular_velocity[i], b.angular_velocity[i]);
    EXPECT_EQ(a.linear_velocity[i], b.linear_velocity[i]);
  }
  EXPECT_EQ(a.velocity_age_s, b.velocity_age_s);
  EXPECT_EQ(a.max_correction_px, b.max_correction_px);
  EXPECT_EQ(a.pinhole_sufficient, b.pinhole_sufficient);
}

// The live run and its two replays, made once for the tests below.
struct Runs {
  std::string live = tmp("live.lcmlog"), r1 = tmp("replay1.lcmlog"), r2 = tmp("replay2.lcmlog");
  daemon::RunSummary s_live, s1, s2;
  Runs() {
    s_live = run(sim_config(live), 30);
    s1 = run(replay_config(live, r1));
    s2 = run(replay_config(live, r2));
  }
};
const Runs& runs() {
  static Runs r;
  return r;
}

}  // namespace

TEST(Replay, TwoReplaysOfARecordingAreBitIdentical) {
  const Runs& R = runs();
  const Recording live = read_recording(R.live);
  const Recording a = read_recording(R.r1), b = read_recording(R.r2);
  ASSERT_GE(live.raw, 30);
  // Every recorded frame replayed (fast replays drop nothing), nothing skipped.
  EXPECT_EQ(R.s1.replayed, static_cast<uint64_t>(live.raw));
  EXPECT_EQ(R.s1.frames_out, static_cast<uint64_t>(live.raw));
  EXPECT_EQ(R.s1.skipped, 0u);
  ASSERT_EQ(a.by_utime.size(), static_cast<size_t>(live.raw));
  ASSERT_EQ(b.by_utime.size(), a.by_utime.size());
  EXPECT_EQ(a.raw, live.raw);            // the replay's recording holds the frames again
  EXPECT_EQ(a.velocity, live.velocity);  // and the velocity, as delivered
  int rectified = 0;
  for (const auto& [utime, oa] : a.by_utime) {
    const Output& ob = b.by_utime.at(utime);
    ASSERT_TRUE(oa.has_rect && oa.has_info && ob.has_rect && ob.has_info);
    EXPECT_EQ(oa.rect_event, ob.rect_event) << "rectified image at utime " << utime;
    expect_same_info(oa.info, ob.info, utime);
    EXPECT_EQ(oa.info.sequence, ob.info.sequence);
    EXPECT_EQ(oa.info.drops_total, 0);
    rectified += oa.info.rectified;
  }
  EXPECT_GE(rectified, live.raw - 1);  // the velocity was replayed: frames were rectified
}

TEST(Replay, ReplayOfASimulatedRunReproducesTheLiveOutputs) {
  const Runs& R = runs();
  const Recording live = read_recording(R.live), a = read_recording(R.r1);
  size_t compared = 0;
  int rectified_changed = 0;
  int64_t live_drops = 0;  // what the live pipeline said it dropped (a busy machine's doing)
  for (const auto& [utime, ol] : live.by_utime) {
    if (!ol.has_rect || !ol.has_info) continue;  // the live pipeline may have dropped it
    live_drops = std::max(live_drops, ol.info.drops_total);
    const Output& oa = a.by_utime.at(utime);
    EXPECT_EQ(ol.rect.data, oa.rect.data) << "rectified pixels at utime " << utime;
    EXPECT_EQ(ol.rect.width, oa.rect.width);
    expect_same_info(ol.info, oa.info, utime);
    rectified_changed += ol.info.rectified && ol.info.max_correction_px > 0.5;
    ++compared;
  }
  // Every recorded frame compared or said dropped by the live run (a run under TSan beside a
  // busy machine dropped 5 of 37), but for the few its stop cut short.
  EXPECT_GE(compared + static_cast<size_t>(live_drops), static_cast<size_t>(live.raw) - 3);
  EXPECT_GE(rectified_changed, 20);  // the outputs are real corrections, not copies
}

TEST(Replay, ADifferentSettingGivesDifferentOutputs) {
  const Runs& R = runs();
  daemon::Config c = replay_config(R.live, tmp("replay-first-row.lcmlog"));
  c.rectify.reference = dsp::ReferenceRow::First;
  run(c);
  const Recording a = read_recording(R.r1), f = read_recording(c.record_file);
  ASSERT_EQ(a.by_utime.size(), f.by_utime.size());
  int differ = 0;
  for (const auto& [utime, oa] : a.by_utime) differ += oa.rect.data != f.by_utime.at(utime).rect.data;
  EXPECT_GE(differ, static_cast<int>(a.by_utime.size()) - 1);
}

TEST(Replay, SpeedFactorIsHonoured) {
  const Runs& R = runs();
  const double log_s = 30.0 / 30;  // about 30 frames at 30 fps
  const daemon::RunSummary s = run(replay_config(R.live, "", 4.0));
  EXPECT_GE(s.seconds, 0.8 * log_s / 4);
  // Clearly faster than real time: a limit a sanitizer's slowness (and the online calibration's
  // thread beside it) widens tenfold, as every time limit of the suite there.
  EXPECT_LT(s.seconds, log_s * test::kTimeScale) << (test::kSanitized ? test::kSanitizedNote : "");
  EXPECT_GE(s.replayed, 30u);
}

TEST(Replay, DamagedLogReplaysTheRestThroughTheService) {
  const Runs& R = runs();
  std::ifstream in(R.live, std::ios::binary);
  std::vector<uint8_t> b((std::istreambuf_iterator<char>(in)), {});
  // Break the sync word of the 10th raw frame and cut the file in the middle of the last one.
  formats::LcmLogReader reader(R.live);
  formats::LogEvent ev;
  std::vector<uint64_t> raw;
  while (reader.next(ev))
    if (ev.channel == "RSD_RAW") raw.push_back(ev.offset);
  b[raw[9]] = 0;
  b.resize(raw.back() + 1000);
  const std::string bad = tmp("damaged.lcmlog");
  std::ofstream(bad, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  const daemon::RunSummary s = run(replay_config(bad, ""));
  EXPECT_EQ(s.replayed, raw.size() - 2);
  EXPECT_EQ(s.frames_out, raw.size() - 2);
  EXPECT_EQ(s.skipped, 2u);
  EXPECT_EQ(s.skips, "1 broken sync word, 1 truncated");
}

// The capture -> rectify -> publish path with recording on (raw frames, velocity and outputs
// written to a log) allocates nothing after start-up.
TEST(Replay, RecordingHotPathAllocatesNothingAfterStartUp) {
  drivers::SimSourceConfig sc;
  sc.camera = dsp::CameraModel::from_hfov(160, 120, 1.0);
  sc.realtime = false;
  drivers::SimSource sim(sc);
  const std::string path = tmp("alloc.lcmlog");
  formats::LcmLogWriter log(path);
  daemon::LcmPublisher pub("memq://", {}, {160, 120, dsp::PixelFormat::Mono8});
  pub.set_recorder(&log);
  daemon::VelocityBuffer velocity;
  daemon::VelocityInput vin(pub.handle(), "RSD_VELOCITY", velocity);
  daemon::RecordingSource rec(sim, log, "RSD_RAW");
  const std::string channel = "RSD_VELOCITY";
  rec.set_velocity_sink([&](const drivers::VelocitySample& s) {  // as the service wires it
    const rsd::velocity_t m = daemon::VelocityInput::to_message(s);
    vin.deliver(m);
    uint8_t buf[128];
    const int len = m.encode(buf, 0, sizeof buf);
    pub.publish_encoded(channel, buf, static_cast<size_t>(len));
  });
  rec.open();
  rec.set_camera(sc.camera);
  daemon::FrameRectifier rectifier(daemon::RectifyConfig{}, sc.camera, rec.timing(), rec.format());
  daemon::PipelineConfig pc;
  pc.lossless = true;
  daemon::Pipeline pipeline(pc, rec, rectifier, pub, velocity);
  rec.start();
  pipeline.start();
  auto frames = [&] { return pipeline.stats().frames_out.load(); };
  for (int i = 0; i < 6000 && frames() < 50; ++i) lcm_handle_timeout(pub.handle(), 1);
  // 300 frames; at sanitizer speed (several times slower) 100, which still records every stage.
  const uint64_t want = test::kSanitized ? 100 : 300;
  const uint64_t before = g_allocations.load(), f0 = frames();
  for (int i = 0; i < 12000 && frames() < f0 + want; ++i) lcm_handle_timeout(pub.handle(), 1);
  const uint64_t after = g_allocations.load(), n = frames() - f0;
  pipeline.stop();
  log.flush();
  EXPECT_GE(n, want) << (test::kSanitized ? test::kSanitizedNote : "");
  EXPECT_EQ(after - before, 0u) << "heap allocations over " << n << " recorded frames";
  EXPECT_EQ(log.errors(), 0u);
  EXPECT_GE(vin.ignored(), 1u);  // LCM's echo of the delivered velocity was not pushed twice
  const Recording r = read_recording(path);
  EXPECT_GE(r.raw, static_cast<int>(want + 50));  // the warm-up's 50 frames and those measured
  EXPECT_GE(r.by_utime.size(), want + 50);
}
