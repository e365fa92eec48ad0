// source.lcm: frames over LCM, the section read and printed by one visit.
#include "drivers/lcm_source.hpp"
#include "dsp/core/input_limits.hpp"

namespace rsd::drivers {

void visit_config(formats::ConfigSection& c, LcmSourceConfig& l) {
  c.value("url", l.url, "LCM's TCP queue (server: java -cp lcm.jar lcm.lcm.TCPService 7700)");
  c.value("allow_multicast", l.allow_multicast);
  c.check(l.url.rfind("udpm://", 0) != 0 || l.allow_multicast, "url",
          "is multicast; set allow_multicast: true to use it (this keeps tests off the network)");
  c.value("channel", l.channel);
  c.value("velocity_channel", l.velocity_channel);
  c.value("open_timeout_s", l.open_timeout_s, "wait this long for the first frame, then retry with backoff");
  c.check(l.open_timeout_s > 0 && l.open_timeout_s <= 3600, "open_timeout_s", "must be positive, at most 3600 s");
  c.value("fps", l.fallback_fps, "frame rate when the frames do not carry their timing");
  c.check(dsp::limits::kFrameRateHz.contains(l.fallback_fps), "fps", std::string("must be ") + dsp::limits::kFrameRateHz.text);
}

Driver lcm_driver() {
  return make_driver<LcmSource, LcmSourceConfig>("lcm", "frames published by rsd-replay, lcm-logplayer or a camera node", false,
                                                 visit_config);
}

}  // namespace rsd::drivers
