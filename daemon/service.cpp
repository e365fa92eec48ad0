#include "daemon/service.hpp"
#include "daemon/worker_pool.hpp"

#include <cmath>
#include <cstdio>
#include <memory>
#include <thread>

#include "daemon/log.hpp"
#include "daemon/recording_source.hpp"
#include "daemon/source_watch.hpp"
#include "daemon/systemd_notify.hpp"
#include "daemon/velocity_input.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "drivers/tenfold_log.hpp"
#include "drivers/message_source.hpp"
#include "drivers/monotonic_clock.hpp"
#include "drivers/replay_source.hpp"

namespace rsd::daemon {

namespace {

using Clock = std::chrono::steady_clock;

// Opens the camera, retrying with exponential backoff (0.5 s .. 8 s) until it answers or
// the service is asked to stop (or its run ends). Returns "" or the last error.
std::string open_with_backoff(drivers::CameraSource& src, StopFlags& flags, SystemdNotify& sd, Clock::time_point deadline) {
  double backoff = 0.5;
  for (;;) {
    try {
      src.open();
      return "";
    } catch (const drivers::CameraError& e) {
      spdlog::warn("{}: {}; retrying in {:.1f} s", src.name(), e.what(), backoff);
      sd.status(std::string("no camera: ") + e.what());
      const auto until = Clock::now() + std::chrono::duration<double>(backoff);
      while (Clock::now() < until)
        if (flags.stop.load() || Clock::now() >= deadline) return e.what();
        else std::this_thread::sleep_for(std::chrono::milliseconds(50));
      backoff = std::min(backoff * 2, 8.0);
    }
  }
}

// Everything one run needs. The camera is opened first (it fixes the frame format), then
// the publisher and the rectifier are sized for it once.
struct Session {
  Config cfg;  // in effect: a SIGHUP calibration replaces its calibration parts
  std::unique_ptr<formats::LcmLogWriter> recorder;  // rsd --record (outlives its writers)
  std::unique_ptr<drivers::CameraSource> source;
  std::unique_ptr<RecordingSource> recording;       // the source, recorded
  std::unique_ptr<LcmPublisher> pub;
  // calibration.online: the estimator thread. After the publisher it uses, before the velocity
  // input and the pipeline that feed it (destroyed in the reverse order: they stop first).
  std::unique_ptr<OnlineCalibrator> online;
  VelocityBuffer velocity;
  std::unique_ptr<VelocityInput> velocity_in;
  std::unique_ptr<WorkerPool> workers;  // the rectifiers' helper threads (rectification.workers)
  std::unique_ptr<FrameRectifier> rectifier;
  std::unique_ptr<FrameRectifier> next_rectifier;  // a SIGHUP calibration, until the pipeline takes it up
  int calibrations_applied = 0;
  std::unique_ptr<Pipeline> pipeline;
  std::unique_ptr<FrameFiles> files;  // rsd --output-dir / --output-video
  // calibration.online apply: the estimate the rectifier and the velocity input use (its line
  // delay replaces the configured one in geometry()).
  std::optional<dsp::OnlineCalibration> online_applied;
  Eigen::Matrix3d mount_base = Eigen::Matrix3d::Identity();  // the configured imu_to_camera the estimate's mount turns
  std::vector<uint8_t> pose_buf = std::vector<uint8_t>(512);
  std::unique_ptr<SourceWatch> watch;  // the source's state, afresh with every pipeline
  int reconnects = 0;
  drivers::TenfoldLog refused_log, record_log;  // frames the pipeline refused; the recording's write errors
  // Counters of the pipelines before a reconnect: health and limits count since start.
  uint64_t in_before = 0, out_before = 0, drops_before = 0, refused_before = 0;
  uint64_t frames_out() const { return out_before + pipeline->stats().frames_out.load(); }

  Session(const Config& c, const SourceFactory& factory)
      : cfg(c), source(factory ? factory(c) : make_source(c.source)), velocity(c.velocity_limits) {
    if (!cfg.record_file.empty()) {
      recorder = std::make_unique<formats::LcmLogWriter>(cfg.record_file, cfg.record_append);
      recording = std::make_unique<RecordingSource>(*source, *recorder, cfg.channels.raw);
    }
    // Before open(): the lcm source subscribes there. Poses are delivered from capture() only,
    // after wire() has made the velocity input and the publisher.
    if (drivers::MessageSource* m = messages(); m && !cfg.velocity_input.pose_channel.empty())
      m->set_pose_message_sink(cfg.velocity_input.pose_channel, [this](const bot_core::pose_t& p) {
        velocity_in->deliver(p);
        const int len = p.encode(pose_buf.data(), 0, static_cast<int>(pose_buf.size()));  // sized once: fixed-size type
        if (len > 0) pub->publish_encoded(cfg.velocity_input.pose_channel, pose_buf.data(), static_cast<size_t>(len));
      });
  }
  drivers::CameraSource& active() { return recording ? static_cast<drivers::CameraSource&>(*recording) : *source; }
  // Where the intrinsics in use came from, for the start-up line.
  std::string intrinsics_origin() const {
    if (cfg.source.camera) return cfg.source.camera_origin;
    if (const drivers::MessageSource* m = messages(); m && m->recorded_camera()) return "the log";
    return "the source's own (nominal)";
  }
  drivers::MessageSource* messages() const { return dynamic_cast<drivers::MessageSource*>(source.get()); }
  drivers::Playback* playback() const { return dynamic_cast<drivers::Playback*>(source.get()); }
  drivers::ReplaySource* replay() const { return dynamic_cast<drivers::ReplaySource*>(source.get()); }

  // After the camera has opened: LCM, the velocity input and the rectifier.
  void wire() {
    pub = std::make_unique<LcmPublisher>(cfg.lcm_url, cfg.channels, source->format());
    pub->set_recorder(recorder.get());
    mount_base = cfg.velocity_input.imu_to_camera;
    const std::optional<dsp::OnlineCalibration> state = load_online_state(cfg.online, mount_base);
    if (state && cfg.online.mode == OnlineMode::Apply) use_online(cfg, *state);
    velocity_in = std::make_unique<VelocityInput>(pub->handle(), cfg.velocity_channel, velocity, cfg.velocity_input, cfg.lcm_url,
                                                  &pub->lcm_lock());
    online = make_online(state);
    velocity_in->set_gyro_tap(online.get());
    velocity_in->set_clock_check(!playback() && !messages());  // a live camera: messages share its clock
    // The source's own velocity goes into the buffer on the source's thread, before the frame
    // it precedes (see VelocityInput::deliver), and out on LCM (and into the recording).
    auto publish = [this](const rsd::velocity_t& m) {
      uint8_t buf[128];
      const int len = m.encode(buf, 0, sizeof buf);
      if (len > 0) pub->publish_encoded(cfg.velocity_channel, buf, static_cast<size_t>(len));
    };
    velocity_in->set_recorder(recorder.get());
    if (drivers::MessageSource* m = messages()) {
      m->set_velocity_message_sink([this, publish](const rsd::velocity_t& msg) {
        velocity_in->deliver(msg);
        publish(msg);
      });
    } else {
      source->set_velocity_sink([this, publish](const drivers::VelocitySample& s) {
        velocity_in->deliver(s);
        publish(VelocityInput::to_message(s));
      });
    }
    velocity_in->start();
  }

  // A replay's samples come in their recorded order, before the frames they precede: waiting for
  // more would make its output depend on thread timing.
  RectifyConfig rectify_config() const {
    RectifyConfig r = cfg.rectify;
    if (playback()) r.imu_wait_ms = 0;
    return r;
  }

  // The camera and row timing a configuration's calibration gives this source.
  std::pair<dsp::CameraModel, dsp::RowTiming> geometry(const Config& c) const {
    const drivers::MessageSource* m = messages();
    const dsp::CameraModel cam =
        camera_model(c.source, source->format(), m ? m->recorded_camera() : std::optional<dsp::CameraModel>());
    dsp::RowTiming timing = source->timing();
    if (const auto& cal = c.source.calibration; cal && cal->has_rsd_block && cal->line_delay_s > 0)
      timing.line_delay_s = cal->line_delay_s, timing.readout = cal->readout;
    if (online_applied) timing.line_delay_s = online_applied->line_delay_s;
    if (c.source.shutter == dsp::Shutter::Global) timing.line_delay_s = 0;  // every row at once
    return {cam, timing};
  }

  // calibration.online apply: `e`'s clock, bias and mount for the velocity input (line delay: geometry()).
  void use_online(Config& c, const dsp::OnlineCalibration& e) {
    c.velocity_input.imu_time_offset_s = e.time_offset_s;
    c.velocity_input.drift_ppm = e.drift_ppm, c.velocity_input.drift_t0_s = e.offset_at_s;  // from where the offset holds
    c.velocity_input.gyro_bias_rad_s = e.gyro_bias;
    c.velocity_input.imu_to_camera = dsp::exp_so3(e.mount_rotation) * mount_base;
    online_applied = e;
  }
  // The estimate the online calibration converged to, switched to between two frames; "" or
  // why not yet.
  std::string apply_online(const dsp::OnlineCalibration& e) {
    Config next = cfg;
    const std::optional<dsp::OnlineCalibration> before = online_applied;
    use_online(next, e);
    const std::string why = apply_calibration(next, "online");
    if (!why.empty()) online_applied = before;
    return why;
  }

  // The estimator, started from the calibration in use (or the state file's); nullptr when off.
  // A global shutter (source.shutter) learns the clock offset and the gyro bias only; a rolling
  // one with no line delay (0: a recording's, not yet measured) lets the frames decide.
  std::unique_ptr<OnlineCalibrator> make_online(std::optional<dsp::OnlineCalibration> state) {
    if (cfg.online.mode == OnlineMode::Off) return nullptr;
    const auto [cam, timing] = geometry(cfg);
    const bool global = cfg.source.shutter == dsp::Shutter::Global;
    if (global && state) state->line_delay_s = 0;
    if (!global && !(timing.line_delay_s > 0))
      spdlog::info("online calibration: {} gives no line delay; the frames will show whether its rows are read at different times",
                   source->name());
    OnlineCalibrationConfig online = cfg.online;
    online.estimator.global_shutter = global;
    OnlineSetup st;
    st.nominal.cam = cam;
    st.nominal.frame_rate_hz = timing.frame_rate_hz;
    st.nominal.time.line_delay_s = timing.line_delay_s;
    st.nominal.time.readout = timing.readout;
    st.nominal.imu_to_camera = cfg.velocity_input.imu_to_camera;
    st.start = state ? *state
                     : dsp::OnlineCalibration{cfg.velocity_input.imu_time_offset_s, timing.line_delay_s,
                                              cfg.velocity_input.gyro_bias_rad_s, Eigen::Vector3d::Zero(), cfg.velocity_input.drift_ppm};
    st.gyro_scale = cfg.velocity_input.gyro_scale;
    st.base = cfg.source.calibration ? *cfg.source.calibration : formats::calibration_of(st.nominal, "");
    st.base.cam = cam, st.base.imu_to_camera = cfg.velocity_input.imu_to_camera, st.base.gyro_scale = st.gyro_scale;
    st.base.readout = timing.readout;
    auto o = std::make_unique<OnlineCalibrator>(online, st, *pub);
    o->set_applied(online_applied.has_value());
    return o;
  }

  // SIGHUP: `next`'s calibration from the next frame on; "" or why it is refused.
  std::string apply_calibration(const Config& next, const char* label = "configured") {
    if (next_rectifier) return "the previous calibration is still being taken up; send SIGHUP again";
    try {
      const auto [cam, timing] = geometry(next);
      next_rectifier = std::make_unique<FrameRectifier>(rectify_config(), cam, timing, source->format(), workers.get());
      next_rectifier->set_calibration(label);
    } catch (const std::exception& e) {
      return e.what();
    }
    velocity_in->set_calibration(next.velocity_input);
    pipeline->use_rectifier(next_rectifier.get());
    cfg.source.camera = next.source.camera;
    cfg.source.camera_origin = next.source.camera_origin;
    cfg.source.calibration = next.source.calibration;
    cfg.velocity_input = next.velocity_input;
    ++calibrations_applied;
    return "";
  }
  // calibration.online apply: a converged estimate the estimator decided to switch to.
  void take_online() {
    const std::optional<dsp::OnlineCalibration> c = online ? online->take_apply() : std::nullopt;
    if (!c) return;
    if (const std::string why = apply_online(*c); !why.empty()) return online->retry_apply(*c);  // next time round
    online->set_applied(true);
    spdlog::info("online calibration applied from the next frame: time offset {:.3f} ms, line delay {:.3f} us, gyro bias "
                 "[{:.5f}, {:.5f}, {:.5f}] rad/s",
                 c->time_offset_s * 1e3, c->line_delay_s * 1e6, c->gyro_bias.x(), c->gyro_bias.y(), c->gyro_bias.z());
  }
  // Frees the rectifier the pipeline stopped using once it has taken up the new one.
  void collect_retired() {
    if (next_rectifier && pipeline->retired()) rectifier = std::move(next_rectifier);
  }

  void start_pipeline() {
    next_rectifier.reset();  // a stopped pipeline uses neither: the new one starts with cfg's
    const auto [cam, timing] = geometry(cfg);
    if (recording) recording->set_camera(cam);
    if (!workers || workers->concurrency() != cfg.rectify.workers) {
      rectifier.reset();  // the old pool's users first
      workers = std::make_unique<WorkerPool>(cfg.rectify.workers);
    }
    rectifier = std::make_unique<FrameRectifier>(rectify_config(), cam, timing, source->format(), workers.get());
    if (online_applied) rectifier->set_calibration("online");
    PipelineConfig pc = cfg.pipeline;
    if (playback() && playback()->fast()) pc.lossless = true;  // every frame, reproducibly
    pc.samples_until_next_frame = playback() != nullptr;        // the same numbers every time
    const bool to_files = !cfg.output.dir.empty() || !cfg.output.video.empty();
    if (to_files) pc.lossless = true;  // every frame into the files
    if (to_files && !files) {
      FrameFilesConfig fc = cfg.output;
      fc.fps = source->timing().frame_rate_hz;
      files = std::make_unique<FrameFiles>(fc, source->format().width, source->format().height);
    }
    pipeline = std::make_unique<Pipeline>(pc, active(), *rectifier, *pub, velocity);
    // A live camera promises its rate; a replay or frames over LCM come as they were sent.
    const bool paced = !playback() && !messages();
    watch = std::make_unique<SourceWatch>(cfg.health, source->name(), paced ? source->timing().frame_rate_hz : 0, paced);
    pipeline->set_frame_files(files.get());
    pipeline->set_frame_tap(online.get());
    if (online) online->start();
    active().start();
    pipeline->start();
  }
};

// The latency part of the status: "latency p50 1.20 ms p99 3.40 ms", or with frames beyond the
// histogram "latency p50 1.20 ms p99 >= 100 ms (max 153.2 ms, 4 frames at 100 ms or more)".
std::string latency_text(const rsd::health_t& h) {
  char text[160];
  if (h.latency_over_range > 0 && h.latency_p99_ms >= LatencyStats::kRangeMs)
    std::snprintf(text, sizeof text, "latency p50 %.2f ms p99 >= %.0f ms (max %.1f ms, %lld frames at %.0f ms or more)",
                  h.latency_p50_ms, LatencyStats::kRangeMs, h.latency_max_ms, static_cast<long long>(h.latency_over_range),
                  LatencyStats::kRangeMs);
  else
    std::snprintf(text, sizeof text, "latency p50 %.2f ms p99 %.2f ms", h.latency_p50_ms, h.latency_p99_ms);
  return text;
}

// Faults that repeat, said at the first and at every tenfold: frames the pipeline refused for
// their stamps, events the recording could not write.
void log_faults(Session& s, uint64_t refused, uint64_t record_errors) {
  if (s.refused_log.due(refused))
    spdlog::warn("{}: {} frames refused: a first-row time off the camera's time line (not after the previous frame's, or a wild jump)",
                 s.source->name(), refused);
  if (s.record_log.due(record_errors))
    spdlog::error("recording to {}: {} events not written ({}); the run goes on without them", s.recorder->path(),
                  record_errors, s.recorder->last_error());
}

// Health once a second (and once at the end): LCM, systemd STATUS, the status line, and a log
// line when the source's state says something new. `state`: the service's own (reconnecting,
// stopping), or nullptr for what the source watch makes of the frames.
void report_health(Session& s, const char* state, double dt, uint64_t& last_in, uint64_t& last_out, bool line,
                   SystemdNotify& sd) {
  const PipelineStats& st = s.pipeline->stats();
  rsd::health_t& h = s.pub->health();
  const int64_t now_ns = drivers::monotonic_ns(), last_ns = st.last_frame_ns.load();
  h.utime = drivers::realtime_ns() / 1000;
  h.source = s.source->name();
  h.frames_in = static_cast<int64_t>(s.in_before + st.frames_in.load());
  h.frames_out = static_cast<int64_t>(s.out_before + st.frames_out.load());
  h.drops = static_cast<int64_t>(s.drops_before + st.drops.load());
  h.queue_depth = static_cast<int32_t>(s.pipeline->queue_depth());
  h.latency_p50_ms = s.pipeline->latency().quantile(0.5);
  h.latency_p99_ms = s.pipeline->latency().quantile(0.99);
  h.latency_max_ms = s.pipeline->latency().max_ms();
  h.latency_over_range = static_cast<int64_t>(s.pipeline->latency().over_range());
  h.fps_in = static_cast<double>(h.frames_in - static_cast<int64_t>(last_in)) / dt;
  h.fps_out = static_cast<double>(h.frames_out - static_cast<int64_t>(last_out)) / dt;
  h.fps_configured = s.watch->configured_fps();
  h.seconds_since_frame = last_ns > 0 ? static_cast<double>(now_ns - last_ns) * 1e-9 : -1;
  h.reconnects = s.reconnects;
  h.frames_refused = static_cast<int64_t>(s.source->refused() + s.refused_before + st.refused.load());
  h.velocity_malformed = static_cast<int64_t>(s.velocity_in ? s.velocity_in->malformed() : 0);
  h.velocity_rejected = static_cast<int64_t>(s.velocity.rejected());
  h.record_errors = s.recorder ? static_cast<int64_t>(s.recorder->errors()) : 0;
  log_faults(s, s.refused_before + st.refused.load(), static_cast<uint64_t>(h.record_errors));
  const SourceWatch::Verdict v = s.watch->update(static_cast<double>(now_ns) * 1e-9, st.frames_in.load(),
                                                 static_cast<double>(last_ns) * 1e-9, h.fps_in);
  h.source_state = state ? state : v.state;
  s.pub->publish_health();
  s.pipeline->latency().reset();
  last_in = static_cast<uint64_t>(h.frames_in), last_out = static_cast<uint64_t>(h.frames_out);
  if (!state && !v.warning.empty()) spdlog::warn("{}", v.warning);
  if (!state && !v.info.empty()) spdlog::info("{}", v.info);
  char text[640];
  std::snprintf(text, sizeof text, "%s %s: in %lld (%.1f fps) out %lld, rectified %llu, drops %lld, %s%s%s", h.source.c_str(),
                h.source_state.c_str(), static_cast<long long>(h.frames_in), h.fps_in, static_cast<long long>(h.frames_out),
                static_cast<unsigned long long>(st.rectified.load()), static_cast<long long>(h.drops), latency_text(h).c_str(),
                s.online ? "; " : "", s.online ? s.online->status_text().c_str() : "");
  sd.status(text);
  if (line) show_status_line(text);
}

// The start-up line: what runs, from where, to where.
void log_start(const Session& s) {
  const drivers::FrameFormat f = s.source->format();
  const dsp::RowTiming t = s.source->timing();
  const RealtimeConfig& rt = s.cfg.pipeline.realtime;
  const char* pixels = dsp::format_name(f.format);
  const std::string calibration = s.cfg.source.calibration ? s.cfg.source.calibration->file : std::string("none");
  spdlog::info("{} {}x{} {} at {:.1f} fps, line delay {:.2f} us {}, intrinsics from {}, calibration file {}; LCM {} ({}, {}, {}); "
               "realtime {}",
               s.source->name(), f.width, f.height, pixels, t.frame_rate_hz, t.line_delay_s * 1e6,
               dsp::to_string(t.readout), s.intrinsics_origin(), calibration, s.cfg.lcm_url, s.cfg.channels.image, s.cfg.channels.info,
               s.cfg.channels.health, rt.enabled ? "on (capture priority " + std::to_string(rt.capture_priority) + ")" : "off");
}

// A SIGHUP with a reloader: refuse, apply between two frames, or ask the caller to restart.
bool handle_reload(Session& s, StopFlags& flags, const Reloader& reloader, SystemdNotify& sd) {
  flags.reload = false;
  sd.reloading();
  const Reload r = reloader();
  if (r.kind == Reload::Restart) {  // READY again once the caller has restarted the service
    flags.reload = true;
    return false;
  }
  // A calibration the user gave replaces what the online calibration had applied.
  const std::optional<dsp::OnlineCalibration> online = s.online_applied;
  if (r.kind == Reload::Calibration) s.online_applied.reset(), s.mount_base = r.cfg.velocity_input.imu_to_camera;
  const std::string why = r.kind == Reload::Refused ? r.why : s.apply_calibration(r.cfg);
  if (!why.empty()) s.online_applied = online;
  else if (s.online) s.online->set_applied(s.online_applied.has_value());
  if (!why.empty()) spdlog::error("reload refused, keeping the running calibration: {}", why);
  else spdlog::info("calibration reloaded: applied from the next frame");
  sd.ready();
  return true;
}

}  // namespace

void run_service(const Config& cfg, StopFlags& flags, const RunLimits& limits, const SourceFactory& factory,
                 RunSummary* summary, const Reloader& reloader) {
  SystemdNotify sd;
  Session s(cfg, factory);
  const auto deadline = limits.max_seconds > 0
                            ? Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(limits.max_seconds))
                            : Clock::time_point::max();
  if (const std::string why = open_with_backoff(s.active(), flags, sd, deadline); !why.empty())
    throw std::runtime_error("no frame ever arrived: " + s.active().name() + " never opened (" + why + ")");
  s.wire();
  s.start_pipeline();
  // Start-up has allocated what the hot path uses: lock it in memory, when asked and permitted.
  if (const RealtimeConfig& rt = cfg.pipeline.realtime; rt.enabled && rt.lock_memory)
    if (const std::string why = lock_memory(); !why.empty()) spdlog::warn("{}", why);
  log_start(s);
  sd.ready();
  const auto t_start = Clock::now();
  auto t_health = t_start, t_progress = t_start;
  uint64_t last_in = 0, last_out = 0;
  const bool progress = limits.progress && s.playback();
  const bool line = limits.status_line && !progress;
  bool settled = false;  // until_online_converged: the last health report saw it converged
  while (!flags.stop.load()) {
    if (flags.reload.load() && (!reloader || !handle_reload(s, flags, reloader, sd))) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    sd.watchdog();
    s.collect_retired();
    s.take_online();
    const auto now = Clock::now();
    if (limits.max_frames && s.frames_out() >= limits.max_frames) break;
    if (s.pipeline->finished()) break;  // a replay has played its log to the end
    if (s.pipeline->output_failed()) {
      s.pipeline->stop();
      s.active().stop();
      s.velocity_in->stop();
      throw std::runtime_error(s.pipeline->output_error());
    }
    if (progress && now - t_progress >= std::chrono::milliseconds(200)) {
      show_replay_progress(s.playback()->progress(), s.playback()->frames(), std::chrono::duration<double>(now - t_start).count());
      t_progress = now;
    }
    if (limits.max_seconds > 0 && now - t_start >= std::chrono::duration<double>(limits.max_seconds)) break;
    if (s.pipeline->camera_lost()) {  // reconnect: stop, reopen with backoff, restart
      spdlog::error("camera lost: {}", s.pipeline->camera_error());
      s.pipeline->stop();
      s.source->stop();
      ++s.reconnects;
      s.in_before += s.pipeline->stats().frames_in.load();
      s.out_before += s.pipeline->stats().frames_out.load();
      s.drops_before += s.pipeline->stats().drops.load();
      s.refused_before += s.pipeline->stats().refused.load();
      s.pub->health().source_state = "reconnecting";
      s.pub->publish_health();
      if (!open_with_backoff(s.active(), flags, sd, deadline).empty()) break;
      s.start_pipeline();
      spdlog::info("{} reopened (reconnect {})", s.source->name(), s.reconnects);
    }
    if (now - t_health >= std::chrono::seconds(1)) {
      report_health(s, nullptr, std::chrono::duration<double>(now - t_health).count(), last_in, last_out, line, sd);
      if (s.online) s.online->publish();
      t_health = now;
      if (limits.until_online_converged && settled) break;
      settled = s.online && s.online->latest().converged && (cfg.online.mode != OnlineMode::Apply || s.online_applied);
    }
  }
  // A restart for a changed configuration is a reload to systemd (RELOADING=1 went out, READY=1
  // follows from the restarted service): STOPPING=1 would start the unit's stop timeout.
  if (!flags.reload.load() || flags.stop.load()) sd.stopping();
  s.pipeline->stop();  // flushes what is in flight
  s.active().stop();
  s.velocity_in->stop();
  if (s.online) s.online->stop();
  const double seconds = std::chrono::duration<double>(Clock::now() - t_start).count();
  if (progress) show_replay_progress(s.playback()->progress(), s.playback()->frames(), seconds);
  report_health(s, "stopping", std::max(1e-3, std::chrono::duration<double>(Clock::now() - t_health).count()), last_in,
                last_out, line, sd);
  if (line || progress) end_status_line();
  RunSummary out;
  out.frames_out = s.frames_out();
  out.reconnects = s.reconnects;
  out.seconds = seconds;
  out.calibrations_applied = s.calibrations_applied;
  if (s.online) out.online = s.online->latest(), out.online_applied = s.online_applied;
  if (const drivers::Playback* p = s.playback()) {
    out.replayed = p->frames();
    if (const drivers::ReplaySource* r = s.replay(); r && r->reader()) {
      out.skipped = r->reader()->skipped_total();
      out.skips = r->reader()->skip_summary();
    }
    if (limits.status_line) spdlog::info("{}", p->summary(seconds));
  }
  if (s.files && limits.status_line) {
    std::string where = cfg.output.dir.empty() ? "" : cfg.output.dir + "/";
    if (!cfg.output.video.empty()) where += (where.empty() ? "" : " and ") + cfg.output.video;
    spdlog::info("wrote {} rectified frames to {}", s.files->written(), where);
  }
  if (s.recorder) {
    s.recorder->flush();
    if (limits.status_line)
      spdlog::info("recorded {} events to {}", s.recorder->events(), s.recorder->path());
  }
  if (summary) *summary = out;
  // A run with nothing to show ends as a failure, whatever stopped it (a camera that opened
  // and never delivered, a log without frames); a process that restarted for a new configuration
  // had something to show before.
  const uint64_t frames_in = s.in_before + s.pipeline->stats().frames_in.load();
  if (frames_in == 0 && !flags.reload.load() && !limits.frames_before)
    throw std::runtime_error("no frame ever arrived from " + s.active().name() + " in " +
                             std::to_string(static_cast<int>(std::lround(seconds))) + " s");
}

}  // namespace rsd::daemon
