#include "daemon/source_watch.hpp"

#include <algorithm>
#include <cstdio>

namespace rsd::daemon {

namespace {

std::string format(const char* fmt, double a, double b = 0, double c = 0) {
  char text[256];
  std::snprintf(text, sizeof text, fmt, a, b, c);
  return text;
}

}  // namespace

SourceWatch::SourceWatch(const HealthConfig& cfg, std::string source, double configured_fps, bool paced)
    : cfg_(cfg), source_(std::move(source)), configured_fps_(configured_fps), paced_(paced) {
  stall_after_s_ = cfg.stall_after_s > 0 ? cfg.stall_after_s : std::max(1.0, configured_fps > 0 ? 5 / configured_fps : 1.0);
}

SourceWatch::Verdict SourceWatch::update(double now_s, uint64_t frames, double last_frame_s, double fps) {
  Verdict v;
  // Before the first frame the source is starting, however long it takes (a camera warming up,
  // a log's first frame far in): the service reports a run that never got one.
  if (frames == 0) return v;
  const double silent_s = now_s - last_frame_s;
  if (silent_s > stall_after_s_) {
    v.state = "stalled";
    if (!stalled_) v.warning = source_ + format(": stalled: no frame for %.1f s (stall_after_s %.1f)", silent_s, stall_after_s_);
    stalled_ = true;
    low_since_s_ = -1;  // a stall is its own warning
    return v;
  }
  v.state = "streaming";
  if (stalled_) v.info = source_ + ": streaming again after a stall";
  stalled_ = false;
  if (!paced_ || configured_fps_ <= 0) return v;
  if (fps < cfg_.low_fps_fraction * configured_fps_) {
    if (low_since_s_ < 0) low_since_s_ = now_s;
    if (!low_said_ && now_s - low_since_s_ >= cfg_.low_fps_after_s) {
      v.warning = source_ + format(": delivering %.1f fps, below the configured %.1f fps for %.0f s", fps, configured_fps_,
                                   now_s - low_since_s_);
      low_said_ = true;
    }
  } else {
    if (low_said_) v.info = source_ + format(": back at %.1f fps (configured %.1f)", fps, configured_fps_);
    low_since_s_ = -1;
    low_said_ = false;
  }
  return v;
}

}  // namespace rsd::daemon
