// rsd-replay: plays a recorded LCM log's raw frames and velocity on LCM as a camera would,
// so an unmodified rsd with an `lcm` source processes them (hardware in the loop), or
// describes a log (--info).
//
//   rsd-replay LOG --lcm-url tcpq://127.0.0.1:7700 [--speed 1|N|fast]
//   rsd-replay LOG --info
//
// Unlike lcm-logplayer it checks every message first (damaged events, wrong types and absurd
// sizes are skipped and counted, formats/lcm_log.hpp) and plays only the camera's channels.
#include <CLI/CLI.hpp>
#include <lcm/lcm.h>
#include <bot_core/pose_t.hpp>
#include <rsd/frame_info_t.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <map>
#include <thread>

#include "tools/common/cli_util.hpp"
#include "formats/lcm_log.hpp"
#include "formats/image_t_codec.hpp"
#include "drivers/lcm_connect.hpp"
#include "drivers/replay_source.hpp"
#include "drivers/monotonic_clock.hpp"  // monotonic_ns

namespace {

namespace formats = rsd::formats;
using namespace rsd::drivers;

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

struct Options {
  std::string log, url, channel = "RSD_RAW", velocity_channel = "RSD_VELOCITY", pose_channel, speed_text = "1";
  double speed = 1;
  bool allow_multicast = false, quiet = false, progress = false, info = false;
};

// Events per channel, frames (and how many rsd rectified), the time span, what was skipped.
int describe(const Options& o) {
  formats::LcmLogReader reader(o.log);
  formats::LogEvent ev;
  std::map<std::string, uint64_t> per_channel;
  uint64_t frames = 0, infos = 0, rectified = 0;
  int64_t t0 = 0, t1 = 0;
  bot_core::image_t img;
  std::string why;
  while (reader.next(ev)) {
    if (per_channel.empty()) t0 = ev.timestamp_us;
    t1 = ev.timestamp_us;
    ++per_channel[ev.channel];
    if (ev.channel == o.channel) {
      formats::DecodeStatus st = formats::check_image_t(ev.data.data(), ev.data.size(), why);
      if (st == formats::DecodeStatus::Ok) st = formats::decode_checked(ev.data.data(), ev.data.size(), img, why);
      if (st != formats::DecodeStatus::Ok) reader.skip(formats::to_skip(st), ev.offset, o.channel + ": " + why);
      else ++frames;
    } else if (ev.channel == "RSD_FRAME_INFO") {
      rsd::frame_info_t info;
      if (formats::decode_checked(ev.data.data(), ev.data.size(), info, why) == formats::DecodeStatus::Ok) {
        ++infos;
        rectified += info.rectified ? 1 : 0;
      }
    }
  }
  if (per_channel.empty()) {  // a random or empty file is not a log with nothing in it
    std::fprintf(stderr, "rsd-replay: %s: no readable LCM event: not an LCM log%s%s\n", o.log.c_str(),
                 reader.skipped_total() ? "; skipped " : "", reader.skip_summary().c_str());
    return 1;
  }
  std::printf("%s: %.3f s of events\n", o.log.c_str(), static_cast<double>(t1 - t0) * 1e-6);
  for (const auto& [c, n] : per_channel) std::printf("  %-20s %llu\n", c.c_str(), static_cast<unsigned long long>(n));
  std::printf("raw frames: %llu\nframe infos: %llu (rectified %llu)\nskipped: %llu%s%s\n",
              static_cast<unsigned long long>(frames), static_cast<unsigned long long>(infos),
              static_cast<unsigned long long>(rectified), static_cast<unsigned long long>(reader.skipped_total()),
              reader.skipped_total() ? ": " : "", reader.skip_summary().c_str());
  return 0;
}

int play(const Options& o) {
  if (o.url.rfind("udpm://", 0) == 0 && !o.allow_multicast) {
    std::fprintf(stderr, "rsd-replay: --lcm-url %s is multicast; add --allow-multicast to use it\n", o.url.c_str());
    return 2;
  }
  formats::LcmLogReader reader(o.log);
  std::string hub;
  lcm_t* lcm = create_lcm(o.url, hub);
  if (!lcm) {
    std::fprintf(stderr, "rsd-replay: cannot open LCM URL '%s'%s%s\n", o.url.c_str(), hub.empty() ? "" : ": ", hub.c_str());
    return 1;
  }
  ReplayPacer pacer(o.speed);
  formats::LogEvent ev;
  bot_core::image_t img;
  rsd::velocity_t vel;
  bot_core::pose_t pose;
  formats::RecordedFrame frame;
  std::string why;
  uint64_t frames = 0, velocities = 0, ignored = 0;
  const std::vector<std::string> kOutputs = rsd::drivers::ReplayConfig{}.ignore;  // rsd's own recorded outputs
  const int64_t start = monotonic_ns();
  int64_t last_progress = start;
  while (!g_stop && reader.next(ev)) {
    const bool is_frame = ev.channel == o.channel, is_velocity = ev.channel == o.velocity_channel;
    const bool is_pose = !o.pose_channel.empty() && ev.channel == o.pose_channel;
    if (!is_frame && !is_velocity && !is_pose) {
      if (std::find(kOutputs.begin(), kOutputs.end(), ev.channel) != kOutputs.end()) ++ignored;
      else reader.skip(formats::LogSkip::UnknownChannel, ev.offset, "channel '" + ev.channel + "'");
      continue;
    }
    formats::DecodeStatus st = is_frame      ? formats::check_image_t(ev.data.data(), ev.data.size(), why)
                      : is_velocity ? formats::decode_checked(ev.data.data(), ev.data.size(), vel, why)
                                    : formats::decode_checked(ev.data.data(), ev.data.size(), pose, why);
    if (is_frame && st == formats::DecodeStatus::Ok) st = formats::decode_checked(ev.data.data(), ev.data.size(), img, why);
    if (is_frame && st == formats::DecodeStatus::Ok && !formats::parse_frame(img, frame, why)) st = formats::DecodeStatus::Undecodable;
    if (st != formats::DecodeStatus::Ok) {
      reader.skip(formats::to_skip(st), ev.offset, "channel '" + ev.channel + "': " + why);
      continue;
    }
    while (!g_stop && !pacer.wait(ev.timestamp_us, std::chrono::milliseconds(100))) {}
    lcm_publish(lcm, ev.channel.c_str(), ev.data.data(), static_cast<unsigned>(ev.data.size()));  // as recorded
    (is_frame ? frames : velocities)++;  // poses count with the velocity
    const int64_t now = monotonic_ns();
    if (o.progress && now - last_progress > 200000000) {
      last_progress = now;
      std::fprintf(stderr, "\rrsd-replay: %3.0f%%  %llu frames", 100.0 * static_cast<double>(reader.position()) /
                                                                  static_cast<double>(std::max<uint64_t>(1, reader.size())),
                   static_cast<unsigned long long>(frames));
    }
  }
  // Give a queueing transport (tcpq) a moment to hand the last messages over.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  lcm_destroy(lcm);
  const double seconds = static_cast<double>(monotonic_ns() - start) * 1e-9;
  if (!o.quiet)
    std::fprintf(stderr, "%srsd-replay: published %llu frames and %llu velocity messages from %s on %s in %.2f s (%.1f fps)%s%s%s\n",
                 o.progress ? "\n" : "", static_cast<unsigned long long>(frames), static_cast<unsigned long long>(velocities),
                 o.log.c_str(), o.url.c_str(), seconds, static_cast<double>(frames) / std::max(seconds, 1e-9),
                 ignored ? (", " + std::to_string(ignored) + " recorded outputs not played").c_str() : "",
                 reader.skipped_total() ? "; skipped " : "; nothing skipped",
                 reader.skipped_total() ? (std::to_string(reader.skipped_total()) + " events: " + reader.skip_summary()).c_str() : "");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rsd-replay: publish a recorded log's raw frames (bot_core.image_t) and velocity (rsd.velocity_t) on LCM\n"
               "as a camera would, for an rsd with an `lcm` source; or describe a log (--info)."};
  Options o;
  app.add_option("log", o.log, "LCM log (rsd --record, rsd-sim, lcm-logger)")->required()->check(CLI::ExistingFile);
  app.add_option("--lcm-url", o.url, "where to publish, e.g. tcpq://127.0.0.1:7700 (udpm:// needs --allow-multicast)");
  app.add_option("--speed", o.speed_text, "1: real time (default), N: N times faster, fast: no waiting");
  app.add_option("--channel", o.channel, "raw frame channel (default RSD_RAW)");
  app.add_option("--velocity-channel", o.velocity_channel, "velocity channel (default RSD_VELOCITY)");
  app.add_option("--pose-channel", o.pose_channel, "also play bot_core.pose_t from this channel (rsd's velocity.pose_channel)");
  app.add_flag("--allow-multicast", o.allow_multicast, "allow a udpm:// URL");
  app.add_flag("--info", o.info, "describe the log (channels, frames, rectified, skipped) and exit");
  app.add_flag("--quiet,-q", o.quiet, "no progress or summary");
  app.add_flag("--progress", o.progress, "show progress even when stderr is not a terminal");
  if (const auto rc = rsd::tools::parse_command_line(app, argc, argv)) return *rc;
  if (!parse_speed(o.speed_text, o.speed)) {
    std::fprintf(stderr, "rsd-replay: --speed: expected a positive factor or fast, not '%s'\n", o.speed_text.c_str());
    return 2;
  }
  o.progress = !o.quiet && (o.progress || isatty(STDERR_FILENO));
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  try {
    if (o.info) return describe(o);
    if (o.url.empty()) {
      std::fprintf(stderr, "rsd-replay: --lcm-url is required to play (or use --info)\n");
      return 2;
    }
    return play(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsd-replay: %s\n", e.what());
    return 1;
  }
}
