// What the camera source is doing, judged once a second by the health reporter from the
// frames that arrived: the source state health_t.source_state reports (starting, streaming,
// stalled; the service itself says reconnecting and stopping), and what is worth a log line: a
// stall and its end, an achieved frame rate that stays below the configured one and its
// recovery. Pure logic on the numbers it is given, so that it is tested without a camera.
//
// Thread contract: one thread (the service's) calls everything.
#pragma once

#include <cstdint>
#include <string>

namespace rsd::daemon {

struct HealthConfig {
  // No frame for this long: stalled. 0: five frame periods, at least 1 s.
  double stall_after_s = 0;
  // Warn when the achieved rate stays below this fraction of the configured one ...
  double low_fps_fraction = 0.9;
  // ... for this many consecutive seconds.
  double low_fps_after_s = 3;
};

class SourceWatch {
 public:
  // `configured_fps`: the rate the source was asked for (0: unknown, no rate warning).
  // `paced`: the rate is the source's promise (a live camera), not a replay's choice.
  SourceWatch(const HealthConfig& cfg, std::string source, double configured_fps, bool paced);

  struct Verdict {
    const char* state = "starting";  // "starting", "streaming" or "stalled"
    std::string warning;             // a line to log as a warning, or ""
    std::string info;                // a line to log as information, or ""
  };
  // `now_s`: seconds since the source started; `frames`: frames received since then;
  // `last_frame_s`: when the newest arrived (ignored while frames is 0); `fps`: the rate over
  // the last interval.
  Verdict update(double now_s, uint64_t frames, double last_frame_s, double fps);

  double stall_after_s() const { return stall_after_s_; }
  double configured_fps() const { return configured_fps_; }

 private:
  HealthConfig cfg_;
  std::string source_;
  double configured_fps_;
  bool paced_;
  double stall_after_s_;
  bool stalled_ = false;
  double low_since_s_ = -1;  // when the rate first fell short, -1 while it does not
  bool low_said_ = false;
};

}  // namespace rsd::daemon
