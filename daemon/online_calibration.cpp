#include "daemon/online_calibration.hpp"

#include <pthread.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/core.hpp>
#include <rsd/calibration_t.hpp>

#include "daemon/log.hpp"
#include "drivers/monotonic_clock.hpp"
#include "dsp/core/pixel_conversion.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "formats/calibration_v1.hpp"

namespace rsd::daemon {

namespace {

constexpr size_t kSlots = 4;         // one being tracked, three waiting (the tracker keeps its own copy)
constexpr size_t kGyroRing = 8192;   // 40 s of a 200 Hz gyro
constexpr double kMaxPairGap_s = 0.25;  // frames further apart are not matched (the chain restarts)
constexpr double kUpdateEvery_s = 1.0;  // of frame time: one fit a second
constexpr int kNice = 10;

// The estimator's tracking, a third of its former cost (issue 36): features carried from pair
// to pair, corners found at half size when the pairs have lost a fifth of them, and a smaller LK
// window than the offline extraction's (FeatureTracks.CarriedThroughAChainTheyStayExactAndCoverTheFrame:
// as exact on a textured scene).
dsp::TrackOptions track_options(const OnlineCalibrationConfig& c) {
  dsp::TrackOptions o;
  o.max_per_pair = c.features;
  o.window_px = 11;
  o.carry = true;
  o.detect_level = 1;
  return o;
}

}  // namespace

const char* to_string(OnlineMode m) {
  switch (m) {
    case OnlineMode::Off: return "off";
    case OnlineMode::Observe: return "observe";
    case OnlineMode::Apply: return "apply";
  }
  return "?";
}

void visit_online_calibration(formats::ConfigSection& c, OnlineCalibrationConfig& o) {
  c.choice("online", o.mode, {{"off", OnlineMode::Off}, {"observe", OnlineMode::Observe}, {"apply", OnlineMode::Apply}},
           "off, observe (learn the IMU time offset, line delay, gyro bias; publish them) or apply (rectify with them once converged)");
  c.value("channel", o.channel, "rsd.calibration_t, once a second");
  c.check(!o.channel.empty(), "channel", "must not be empty");
  c.path("state_file", o.state_file, "the last converged estimate (rsd-calibration/1), loaded at start; relative to this file; \"\": none");
  c.value("max_fps", o.max_fps, "frames handed to the estimator at most this often");
  c.check(std::isfinite(o.max_fps) && o.max_fps >= 1 && o.max_fps <= 240, "max_fps", "must be 1..240");
  c.value("features", o.features, "features tracked per frame pair");
  c.check(o.features >= 20 && o.features <= 1000, "features", "must be 20..1000");
  c.value("window_s", o.estimator.window_s, "the sliding window each fit sees");
  c.check(std::isfinite(o.estimator.window_s) && o.estimator.window_s >= 0.5 && o.estimator.window_s <= 30, "window_s",
          "must be 0.5..30 s");
  c.value("min_rate_rad_s", o.estimator.min_rate_rad_s, "less rotation (RMS) than this: the estimate is held");
  c.check(std::isfinite(o.estimator.min_rate_rad_s) && o.estimator.min_rate_rad_s >= 0, "min_rate_rad_s", "must be 0 or more");
  c.value("apply_sigmas", o.apply_sigmas, "apply: switch again only when the estimate moved this many sigmas");
  c.check(std::isfinite(o.apply_sigmas) && o.apply_sigmas >= 0, "apply_sigmas", "must be 0 or more");
}

std::optional<dsp::OnlineCalibration> load_online_state(const OnlineCalibrationConfig& c, const Eigen::Matrix3d& imu_to_camera) {
  const std::string& file = c.state_file;
  if (c.mode == OnlineMode::Off || file.empty() || !std::filesystem::exists(file)) return std::nullopt;
  try {
    const formats::Calibration cal = formats::read_calibration(file);
    if (!cal.has_rsd_block || !(cal.line_delay_s > 0)) throw std::runtime_error(file + ": no rsd block with a line delay");
    spdlog::info("online calibration: starting from {} (time offset {:.3f} ms, line delay {:.3f} us)", file,
                 cal.timeshift_cam_imu_s * 1e3, cal.line_delay_s * 1e6);
    return dsp::OnlineCalibration{cal.timeshift_cam_imu_s, cal.line_delay_s, cal.gyro_bias_rad_s,
                                  dsp::log_so3(cal.imu_to_camera * imu_to_camera.transpose()), cal.drift_ppm};
  } catch (const std::exception& e) {
    spdlog::error("calibration.state_file: {}; starting from the configured calibration", e.what());
    return std::nullopt;
  }
}

OnlineCalibrator::OnlineCalibrator(const OnlineCalibrationConfig& cfg, const OnlineSetup& setup, LcmPublisher& pub)
    : cfg_(cfg), setup_(setup), pub_(pub),
      est_(std::make_unique<dsp::OnlineEstimator>(setup.nominal, setup.start, cfg.estimator, setup.gyro_scale)),
      free_(kSlots), ready_(kSlots), ring_(kGyroRing), tracker_(track_options(cfg)) {
  for (size_t i = 0; i < kSlots; ++i) {
    slots_.push_back({dsp::Image(setup.nominal.cam.width, setup.nominal.cam.height, dsp::PixelFormat::Mono8), 0});
    free_.put(static_cast<uint32_t>(i));
  }
  latest_ = est_->estimate();
}

OnlineCalibrator::~OnlineCalibrator() { stop(); }

void OnlineCalibrator::start() {
  if (running_.exchange(true)) return;
  // spdlog's registry, which the thread logs through, exists before the thread does: it is
  // created lazily inside libspdlog, a guard ThreadSanitizer cannot see (and reported as a race
  // when the service's first log line came after this thread's start).
  (void)spdlog::default_logger_raw();
  thread_ = std::thread([this] {
    // Named first: tools (top -H) and the tests' allocation counter tell it from the hot path.
    pthread_setname_np(pthread_self(), kThreadName);
    // A low priority (nice 10 for this thread: about a tenth of a core's share against a busy
    // normal thread): capture, rectification and publishing come first and never wait for it,
    // yet a loaded machine does not starve it altogether, as SCHED_IDLE would.
    if (setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), kNice) != 0) spdlog::debug("online calibration: nice not permitted");
    run();
  });
}

void OnlineCalibrator::stop() {
  if (!running_.exchange(false)) return;
  ready_.wake();
  if (thread_.joinable()) thread_.join();
}

void OnlineCalibrator::offer(const dsp::ImageView& raw, const drivers::FrameMeta& meta) {
  const double t = static_cast<double>(meta.first_row_ns) * 1e-9;
  if (t - last_offer_t_ < 0.95 / cfg_.max_fps) return;  // faster than the estimator wants
  offered_.fetch_add(1, std::memory_order_relaxed);
  const std::optional<uint32_t> s = free_.get();
  if (!s) {  // the estimator is busy with every slot: this frame is not tracked
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  last_offer_t_ = t;
  Slot& slot = slots_[*s];
  dsp::convert_to_luma(raw, slot.luma.view());
  slot.t = t;
  (void)ready_.push(*s);  // never full: it holds at most every slot
}

void OnlineCalibrator::gyro(int64_t utime_imu, const double* w) {
  const uint64_t tail = ring_tail_.load(std::memory_order_relaxed);
  if (tail - ring_head_.load(std::memory_order_acquire) >= ring_.size()) {
    gyro_dropped_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  ring_[tail % ring_.size()] = {static_cast<double>(utime_imu) * 1e-6, {w[0], w[1], w[2]}};
  ring_tail_.store(tail + 1, std::memory_order_release);
}

void OnlineCalibrator::drain_gyro() {
  uint64_t head = ring_head_.load(std::memory_order_relaxed);
  const uint64_t tail = ring_tail_.load(std::memory_order_acquire);
  for (; head < tail; ++head) {
    const GyroEntry& g = ring_[head % ring_.size()];
    est_->add_gyro(g.t, Eigen::Vector3d(g.w[0], g.w[1], g.w[2]));
  }
  ring_head_.store(head, std::memory_order_release);
}

void OnlineCalibrator::run() {
  while (running_.load()) {
    const uint32_t seen = ready_.epoch();
    const std::optional<uint32_t> s = ready_.pop();
    if (!s) {
      ready_.wait(seen);
      continue;
    }
    drain_gyro();
    const double t = slots_[*s].t;
    bool tracked = true;
    try {
      track(*s);
    } catch (const std::exception& e) {  // a bug or a bad frame: said, and the chain restarts
      spdlog::warn("online calibration: {}", e.what());
      tracker_.restart();
      prev_t_.reset();
      tracked = false;
    }
    free_.put(*s);  // the tracker keeps its own copy
    if (!tracked) continue;
    if (t >= next_update_t_) {
      next_update_t_ = t + kUpdateEvery_s;
      after_update(est_->update());
    }
    timespec cpu{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu);
    cpu_s_.store(static_cast<double>(cpu.tv_sec) + 1e-9 * static_cast<double>(cpu.tv_nsec), std::memory_order_relaxed);
  }
}

// Matches between the frame the tracker holds and this one, which it holds in its place (its
// features carried on: detecting afresh every frame cost a third of the estimator's time).
void OnlineCalibrator::track(uint32_t s) {
  const Slot& cur = slots_[s];
  if (prev_t_ && !(cur.t > *prev_t_ && cur.t - *prev_t_ <= kMaxPairGap_s)) tracker_.restart();
  const cv::Mat frame(cur.luma.height, cur.luma.width, CV_8UC1, const_cast<uint8_t*>(cur.luma.data.data()));
  const dsp::PairTracks m = tracker_.next(frame);
  if (!m.a.empty()) est_->add_matches(*prev_t_, cur.t, m.a, m.b);
  prev_t_ = cur.t;
}

// "learned", "held: too little rotation (0.05 rad/s RMS)": a value's note as calibration_t and
// the state file say it.
std::string note_text(const dsp::ValueNote& n) {
  return n.why.empty() ? dsp::to_string(n.status) : std::string(dsp::to_string(n.status)) + ": " + n.why;
}

// A line in the log when the state changes (or a held or rejected window says something new),
// and when the frames decide how the rows are read.
void log_transition(const dsp::OnlineEstimate& before, const dsp::OnlineEstimate& e) {
  if (e.rows != before.rows && e.shutter == dsp::Shutter::Unknown && e.rows != dsp::RowsSeen::Undecided)
    spdlog::info("online calibration: the frames show a {} shutter (line delay {:.3f} +- {:.3f} us)", dsp::to_string(e.rows),
                 e.value.line_delay_s * 1e6, e.sigma.line_delay_s * 1e6);
  if (e.state == before.state && e.reason == before.reason) return;
  if (e.state == dsp::OnlineState::Held || e.state == dsp::OnlineState::Rejected) {
    spdlog::info("online calibration {}: {}", dsp::to_string(e.state), e.reason);
    return;
  }
  spdlog::info("online calibration {}: time offset {:.3f} +- {:.3f} ms, line delay {:.3f} +- {:.3f} us, gyro bias [{:.4f}, {:.4f}, "
               "{:.4f}] +- {:.4f} rad/s{}{}",
               dsp::to_string(e.state), e.value.time_offset_s * 1e3, e.sigma.time_offset_s * 1e3, e.value.line_delay_s * 1e6,
               e.sigma.line_delay_s * 1e6, e.value.gyro_bias.x(), e.value.gyro_bias.y(), e.value.gyro_bias.z(),
               e.sigma.gyro_bias.maxCoeff(), e.reason.empty() ? "" : "; ", e.reason);
}

void OnlineCalibrator::after_update(const dsp::OnlineEstimate& e) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    log_transition(latest_, e);
    latest_ = e;
  }
  if (e.state != dsp::OnlineState::Converged) return;
  const dsp::OnlineCalibration v = applicable(e);
  if (!cfg_.state_file.empty()) write_state(e, v);
  if (cfg_.mode != OnlineMode::Apply) return;
  // Hysteresis: once applied, the rectifier switches again only for a real change: beyond
  // apply_sigmas of the estimate and beyond what moves a pixel by a few hundredths (0.2 ms of
  // offset, 1% of line delay, 1 mrad/s of bias at 1 rad/s and f = 500 px: about 0.05-0.1 px).
  auto moved = [&](double now, double then, double sigma, double floor) {
    return std::abs(now - then) > std::max(cfg_.apply_sigmas * sigma, floor);
  };
  bool switch_now = !decided_;
  if (decided_) {
    // The offsets compared at one time (each holds at its own, and moves at its drift); a drift
    // that moved by 5 ppm walks 0.2 ms in 40 s.
    switch_now = moved(v.time_offset_s, decided_->offset_at(v.offset_at_s), e.sigma.time_offset_s, 2e-4) ||
                 moved(v.drift_ppm, decided_->drift_ppm, e.sigma.drift_ppm, 5) ||
                 moved(v.line_delay_s, decided_->line_delay_s, e.sigma.line_delay_s, 0.01 * decided_->line_delay_s);
    for (int i = 0; i < 3; ++i)
      switch_now = switch_now || moved(v.gyro_bias[i], decided_->gyro_bias[i], e.sigma.gyro_bias[i], 1e-3) ||
                   moved(v.mount_rotation[i], decided_->mount_rotation[i], e.sigma.mount_rotation[i], 1e-3);
  }
  if (!switch_now) return;
  decided_ = v;
  std::lock_guard<std::mutex> lock(mutex_);
  pending_ = v;
}

// What a converged estimate changes: its values, the mount rotation only where the motion
// showed it (else the configured mount).
dsp::OnlineCalibration OnlineCalibrator::applicable(const dsp::OnlineEstimate& e) {
  dsp::OnlineCalibration v = e.value;
  if (!e.mount_known) v.mount_rotation.setZero();
  return v;
}

// The state file: the base calibration with the estimate's values and their sigmas, rewritten
// when the estimate moved beyond its sigma from what the file holds.
void OnlineCalibrator::write_state(const dsp::OnlineEstimate& e, const dsp::OnlineCalibration& v) {
  if (written_ && std::abs(v.time_offset_s - written_->offset_at(v.offset_at_s)) <= e.sigma.time_offset_s &&
      std::abs(v.drift_ppm - written_->drift_ppm) <= e.sigma.drift_ppm &&
      std::abs(v.line_delay_s - written_->line_delay_s) <= e.sigma.line_delay_s &&
      ((v.gyro_bias - written_->gyro_bias).array().abs() <= e.sigma.gyro_bias.array()).all() &&
      ((v.mount_rotation - written_->mount_rotation).array().abs() <= e.sigma.mount_rotation.array()).all())
    return;
  formats::Calibration c = setup_.base;
  c.timeshift_cam_imu_s = v.time_offset_s;
  c.drift_ppm = v.drift_ppm;
  c.line_delay_s = v.line_delay_s;
  c.gyro_bias_rad_s = v.gyro_bias;
  c.imu_to_camera = dsp::exp_so3(v.mount_rotation) * setup_.nominal.imu_to_camera;
  c.has_rsd_block = true;
  // Which values were learned, which held or fixed and why (calibration-v1 has no key for it:
  // its free-text source); sigmas for the values learned.
  c.source = "rsd online calibration (converged over a " + std::to_string(e.window.t_end - e.window.t_begin) +
             " s window; " + dsp::to_string(e.shutter) + " shutter, rows " + dsp::to_string(e.rows) +
             "): time offset " + note_text(e.notes.time_offset) + "; line delay " + note_text(e.notes.line_delay) +
             "; gyro bias " + note_text(e.notes.gyro_bias) + "; mount rotation " + note_text(e.notes.mount_rotation) +
             "; clock drift " + note_text(e.notes.drift);
  for (const char* key : {"timeshift_cam_imu", "line_delay_s", "gyro_bias_rad_s", "drift_ppm"}) c.sigma.erase(key);
  auto learned = [](const dsp::ValueNote& n) { return n.status == dsp::ValueStatus::Learned; };
  if (learned(e.notes.time_offset)) c.sigma["timeshift_cam_imu"] = {e.sigma.time_offset_s};
  if (learned(e.notes.line_delay)) c.sigma["line_delay_s"] = {e.sigma.line_delay_s};
  if (learned(e.notes.gyro_bias)) c.sigma["gyro_bias_rad_s"] = {e.sigma.gyro_bias.x(), e.sigma.gyro_bias.y(), e.sigma.gyro_bias.z()};
  if (learned(e.notes.drift)) c.sigma["drift_ppm"] = {e.sigma.drift_ppm};
  try {
    formats::write_calibration(cfg_.state_file, c);
    written_ = v;
  } catch (const std::exception& ex) {
    spdlog::error("online calibration: {}", ex.what());
  }
}

std::optional<dsp::OnlineCalibration> OnlineCalibrator::take_apply() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::optional<dsp::OnlineCalibration> p = pending_;
  pending_.reset();
  return p;
}

void OnlineCalibrator::retry_apply(const dsp::OnlineCalibration& c) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!pending_) pending_ = c;
}

// The estimator thread's CPU time over the wall time since the last call (the service asks
// once a second).
double OnlineCalibrator::cpu_share() {
  const double cpu = cpu_s_.load(std::memory_order_relaxed), wall = static_cast<double>(drivers::monotonic_ns()) * 1e-9;
  const double share = last_wall_s_ > 0 && wall > last_wall_s_ ? (cpu - last_cpu_s_) / (wall - last_wall_s_) : 0.0;
  last_cpu_s_ = cpu, last_wall_s_ = wall;
  return share;
}

dsp::OnlineEstimate OnlineCalibrator::latest() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_;
}

// "online converged: offset 2.50 ms, line delay 69.44 us, bias [4.0 -3.0 2.0] mrad/s" (held or
// rejected windows add their reason; before the first fit, what it waits for).
std::string OnlineCalibrator::status_text() const {
  const dsp::OnlineEstimate e = latest();
  if (e.updates == 0)
    return e.reason.empty() ? "online calibration: waiting for a window of frames" : "online calibration held: " + e.reason;
  const bool kept = e.state == dsp::OnlineState::Held || e.state == dsp::OnlineState::Rejected;
  const std::string state = kept ? (e.converged ? "converged, " : "") + std::string(dsp::to_string(e.state)) : dsp::to_string(e.state);
  char text[160];
  std::snprintf(text, sizeof text, "online %s: offset %.2f ms, line delay %.2f us, bias [%.1f %.1f %.1f] mrad/s", state.c_str(),
                e.value.time_offset_s * 1e3, e.value.line_delay_s * 1e6, e.value.gyro_bias.x() * 1e3, e.value.gyro_bias.y() * 1e3,
                e.value.gyro_bias.z() * 1e3);
  return kept && !e.reason.empty() ? std::string(text) + " (" + e.reason + ")" : std::string(text);
}

void OnlineCalibrator::publish() {
  const dsp::OnlineEstimate e = latest();
  rsd::calibration_t m;
  m.utime = drivers::realtime_ns() / 1000;
  m.mode = to_string(cfg_.mode);
  m.state = dsp::to_string(e.state);
  m.reason = e.reason;
  m.shutter = dsp::to_string(e.shutter);
  m.rows = dsp::to_string(e.rows);
  m.time_offset_status = note_text(e.notes.time_offset);
  m.line_delay_status = note_text(e.notes.line_delay);
  m.gyro_bias_status = note_text(e.notes.gyro_bias);
  m.mount_status = note_text(e.notes.mount_rotation);
  m.drift_status = note_text(e.notes.drift);
  m.converged = e.converged;
  m.applied = applied_.load();
  m.time_offset_s = e.value.time_offset_s, m.time_offset_sigma_s = e.sigma.time_offset_s;
  m.line_delay_s = e.value.line_delay_s, m.line_delay_sigma_s = e.sigma.line_delay_s;
  for (int i = 0; i < 3; ++i) m.gyro_bias_rad_s[i] = e.value.gyro_bias[i], m.gyro_bias_sigma_rad_s[i] = e.sigma.gyro_bias[i];
  m.mount_known = e.mount_known;
  for (int i = 0; i < 3; ++i)
    m.mount_rotation_rad[i] = e.value.mount_rotation[i], m.mount_rotation_sigma_rad[i] = e.sigma.mount_rotation[i];
  m.drift_ppm = e.value.drift_ppm, m.drift_sigma_ppm = e.sigma.drift_ppm, m.offset_at_s = e.value.offset_at_s;
  m.window_begin_s = e.window.t_begin, m.window_end_s = e.window.t_end;
  m.window_frames = e.window.frames, m.window_matches = e.window.matches;
  m.fitted_matches = e.window.fitted, m.inlier_matches = e.window.inliers;
  m.gyro_samples = e.window.gyro_samples;
  m.rate_rms_rad_s = e.window.rate_rms_rad_s, m.residual_px = e.window.residual_px;
  m.rate_spread_rad_s = e.window.rate_spread_rad_s;
  m.updates = e.updates;
  m.frames_offered = static_cast<int64_t>(offered_.load()), m.frames_dropped = static_cast<int64_t>(dropped_.load());
  m.cpu_share = cpu_share();
  std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
  const int len = m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  if (len > 0) pub_.publish_encoded(cfg_.channel, buf.data(), static_cast<size_t>(len));
}

}  // namespace rsd::daemon
