#include "daemon/service.hpp"

#include <cstdio>
#include <memory>
#include <thread>

#include "daemon/systemd_notify.hpp"
#include "daemon/velocity_input.hpp"

namespace rsd::daemon {

namespace {

using Clock = std::chrono::steady_clock;

// Opens the camera, retrying with exponential backoff (0.5 s .. 8 s) until it answers or
// the service is asked to stop.
bool open_with_backoff(drivers::CameraSource& src, StopFlags& flags, SystemdNotify& sd, Clock::time_point deadline) {
  double backoff = 0.5;
  for (;;) {
    try {
      src.open();
      return true;
    } catch (const drivers::CameraError& e) {
      std::fprintf(stderr, "rsd: %s: %s; retrying in %.1f s\n", src.name().c_str(), e.what(), backoff);
      sd.status(std::string("no camera: ") + e.what());
      const auto until = Clock::now() + std::chrono::duration<double>(backoff);
      while (Clock::now() < until)
        if (flags.stop.load() || Clock::now() >= deadline) return false;
        else std::this_thread::sleep_for(std::chrono::milliseconds(50));
      backoff = std::min(backoff * 2, 8.0);
    }
  }
}

// Everything one run needs. The camera is opened first (it fixes the frame format), then
// the publisher and the rectifier are sized for it once.
struct Session {
  const Config& cfg;
  std::unique_ptr<drivers::CameraSource> source;
  std::unique_ptr<LcmPublisher> pub;
  VelocityBuffer velocity;
  std::unique_ptr<VelocityInput> velocity_in;
  std::unique_ptr<FrameRectifier> rectifier;
  std::unique_ptr<Pipeline> pipeline;
  int reconnects = 0;
  // Counters of the pipelines before a reconnect: health and limits count since start.
  uint64_t in_before = 0, out_before = 0, drops_before = 0;
  uint64_t frames_out() const { return out_before + pipeline->stats().frames_out.load(); }

  Session(const Config& c, const SourceFactory& factory)
      : cfg(c), source(factory ? factory(c) : make_source(c.source)), velocity(c.velocity_limits) {}

  // After the camera has opened: LCM, the velocity input and the rectifier.
  void wire() {
    pub = std::make_unique<LcmPublisher>(cfg.lcm_url, cfg.channels, source->format());
    velocity_in = std::make_unique<VelocityInput>(pub->handle(), cfg.velocity_channel, velocity, cfg.velocity_input);
    lcm_t* lcm = pub->handle();
    const std::string channel = cfg.velocity_channel;
    source->set_velocity_sink([lcm, channel](const drivers::VelocitySample& s) { VelocityInput::publish(lcm, channel, s); });
    velocity_in->start();
  }

  void start_pipeline() {
    rectifier = std::make_unique<FrameRectifier>(cfg.rectify, camera_model(cfg.source, source->format()), source->timing(),
                                                 source->format());
    pipeline = std::make_unique<Pipeline>(cfg.pipeline, *source, *rectifier, *pub, velocity);
    source->start();
    pipeline->start();
  }
};

void report_health(Session& s, const char* state, double dt, uint64_t& last_in, uint64_t& last_out, bool line,
                   SystemdNotify& sd) {
  const PipelineStats& st = s.pipeline->stats();
  rsd::health_t& h = s.pub->health();
  h.utime = drivers::monotonic_ns() / 1000;
  h.source = s.source->name();
  h.source_state = state;
  h.frames_in = static_cast<int64_t>(s.in_before + st.frames_in.load());
  h.frames_out = static_cast<int64_t>(s.out_before + st.frames_out.load());
  h.drops = static_cast<int64_t>(s.drops_before + st.drops.load());
  h.queue_depth = static_cast<int32_t>(s.pipeline->queue_depth());
  h.latency_p50_ms = s.pipeline->latency().quantile(0.5);
  h.latency_p99_ms = s.pipeline->latency().quantile(0.99);
  h.fps_in = static_cast<double>(h.frames_in - static_cast<int64_t>(last_in)) / dt;
  h.fps_out = static_cast<double>(h.frames_out - static_cast<int64_t>(last_out)) / dt;
  h.reconnects = s.reconnects;
  s.pub->publish_health();
  s.pipeline->latency().reset();
  last_in = static_cast<uint64_t>(h.frames_in), last_out = static_cast<uint64_t>(h.frames_out);
  char text[256];
  std::snprintf(text, sizeof text, "%s %s: in %lld (%.1f fps) out %lld, rectified %llu, drops %lld, latency p50 %.2f ms p99 %.2f ms",
                h.source.c_str(), state, static_cast<long long>(h.frames_in), h.fps_in, static_cast<long long>(h.frames_out),
                static_cast<unsigned long long>(st.rectified.load()), static_cast<long long>(h.drops), h.latency_p50_ms,
                h.latency_p99_ms);
  sd.status(text);
  if (line) std::fprintf(stderr, "\rrsd: %s   ", text);
}

}  // namespace

int run_service(const Config& cfg, const std::string&, StopFlags& flags, const RunLimits& limits,
                const SourceFactory& factory, RunSummary* summary) {
  SystemdNotify sd;
  Session s(cfg, factory);
  const auto deadline = limits.max_seconds > 0
                            ? Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(limits.max_seconds))
                            : Clock::time_point::max();
  if (!open_with_backoff(*s.source, flags, sd, deadline)) return 0;
  s.wire();
  s.start_pipeline();
  sd.ready();
  const auto t_start = Clock::now();
  auto t_health = t_start;
  uint64_t last_in = 0, last_out = 0;
  while (!flags.stop.load() && !flags.reload.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    sd.watchdog();
    const auto now = Clock::now();
    if (limits.max_frames && s.frames_out() >= limits.max_frames) break;
    if (limits.max_seconds > 0 && now - t_start >= std::chrono::duration<double>(limits.max_seconds)) break;
    if (s.pipeline->camera_lost()) {  // reconnect: stop, reopen with backoff, restart
      std::fprintf(stderr, "\nrsd: camera lost: %s\n", s.pipeline->camera_error().c_str());
      s.pipeline->stop();
      s.source->stop();
      ++s.reconnects;
      s.in_before += s.pipeline->stats().frames_in.load();
      s.out_before += s.pipeline->stats().frames_out.load();
      s.drops_before += s.pipeline->stats().drops.load();
      s.pub->health().source_state = "reconnecting";
      s.pub->publish_health();
      if (!open_with_backoff(*s.source, flags, sd, deadline)) break;
      s.start_pipeline();
    }
    if (now - t_health >= std::chrono::seconds(1)) {
      report_health(s, "streaming", std::chrono::duration<double>(now - t_health).count(), last_in, last_out,
                    limits.status_line, sd);
      t_health = now;
    }
  }
  sd.stopping();
  s.pipeline->stop();  // flushes what is in flight
  s.source->stop();
  s.velocity_in->stop();
  report_health(s, "stopped", std::max(1e-3, std::chrono::duration<double>(Clock::now() - t_health).count()), last_in,
                last_out, limits.status_line, sd);
  if (limits.status_line) std::fprintf(stderr, "\n");
  if (summary) *summary = {s.frames_out(), s.reconnects};
  return 0;
}

}  // namespace rsd::daemon
