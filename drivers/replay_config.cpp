// source.replay: a recorded log's section, read and printed by one visit.
#include <filesystem>

#include "drivers/replay_source.hpp"
#include "formats/number_text.hpp"

namespace rsd::drivers {

void visit_replay_path(formats::ConfigSection& c, const char* key, std::string& path, const char* comment) {
  c.path(key, path, comment);
}

void visit_replay_speed(formats::ConfigSection& c, double& speed) {
  std::string text = speed == 0 ? "fast" : formats::number_text(speed);
  c.value("speed", text, "1: real time, N: N times faster, fast: no waiting and no drops");
  if (c.has("speed")) c.check(parse_speed(text, speed), "speed", "must be a positive factor (1: real time) or fast");
}

void visit_config(formats::ConfigSection& c, ReplayConfig& r) {
  visit_replay_path(c, "file", r.file, "relative to this file; or rsd --replay LOG");
  visit_replay_speed(c, r.speed);
  c.value("loop", r.loop);
  c.value("channel", r.channel, "bot_core.image_t raw frames with their row timing");
  c.value("velocity_channel", r.velocity_channel);
}

Driver replay_driver() {
  return make_driver<ReplaySource, ReplayConfig>("replay", "a log from rsd --record, rsd-sim or lcm-logger (docs/replay.md)", false,
                                                 visit_config);
}

}  // namespace rsd::drivers
