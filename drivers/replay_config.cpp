// source.replay: a recorded log's section, read and printed by one visit.
#include <filesystem>

#include "drivers/replay_source.hpp"

namespace rsd::drivers {

void visit_config(formats::ConfigSection& c, ReplayConfig& r) {
  std::string file = r.file;
  c.value("file", file, "relative to this file; or rsd --replay LOG");
  if (!file.empty() && std::filesystem::path(file).is_relative() && !c.file().empty())
    file = (std::filesystem::path(c.file()).parent_path() / file).string();
  r.file = file;
  std::string speed = r.speed == 0 ? "fast" : formats::config_number(r.speed);
  c.value("speed", speed, "1: real time, N: N times faster, fast: no waiting and no drops");
  if (c.has("speed")) c.check(parse_speed(speed, r.speed), "speed", "must be a positive factor (1: real time) or fast");
  c.value("loop", r.loop);
  c.value("channel", r.channel, "bot_core.image_t raw frames with their row timing");
  c.value("velocity_channel", r.velocity_channel);
}

Driver replay_driver() {
  return make_driver<ReplaySource, ReplayConfig>("replay", "a log from rsd --record, rsd-sim or lcm-logger (docs/replay.md)", false,
                                                 visit_config);
}

}  // namespace rsd::drivers
