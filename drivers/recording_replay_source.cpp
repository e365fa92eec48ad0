#include "drivers/recording_replay_source.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include <spdlog/spdlog.h>

namespace rsd::drivers {

std::vector<VelocitySample> body_rates(const std::vector<dsp::PoseSample>& poses) {
  std::vector<VelocitySample> out;
  for (size_t k = 1; k < poses.size(); ++k) {
    const dsp::PoseSample &a = poses[k - 1], &b = poses[k];
    const double dt = b.t - a.t;
    if (!(dt > 0)) continue;  // a repeated stamp says nothing about the rate
    // R_b = R_a Exp(w dt): the rate in body axes, as dR/dt = R [w]x (a gyro on the body).
    const Eigen::AngleAxisd rel(a.q.conjugate() * b.q);
    const Eigen::Vector3d w = rel.axis() * rel.angle() / dt;
    const Eigen::Vector3d v = a.q.slerp(0.5, b.q).conjugate() * ((b.p - a.p) / dt);
    VelocitySample s;
    s.t_ns = std::llround(0.5 * (a.t + b.t) * 1e9);
    s.imu_frame = true;  // the body's axes and the motion clock: the calibration applies
    s.has_linear = true;
    for (int i = 0; i < 3; ++i) s.w[i] = w[i], s.v[i] = v[i];
    out.push_back(s);
  }
  return out;
}

RecordingReplaySource::RecordingReplaySource(RecordingReplayConfig cfg) : cfg_(std::move(cfg)), pacer_(cfg_.speed) {}

void RecordingReplaySource::open() {
  if (cfg_.dir.empty()) throw std::runtime_error("source.recording.dir is empty: give rsd --replay DIR");
  rec_ = formats::read_images_recording(cfg_.dir);  // names file, line and field on bad input
  ImagesConfig ic;
  if (rec_.video.empty()) ic.files = rec_.files;
  else {
    ic.video = rec_.video;
    for (const std::string& f : rec_.files) ic.video_frames.push_back(std::stol(f));
  }
  for (const dsp::FrameStamp& f : rec_.rec.frames) {
    ic.stamps_s.push_back(f.t);
    ic.numbers.push_back(static_cast<uint64_t>(f.frame));
  }
  images_ = std::make_unique<ImagesSource>(ic);
  images_->open();
  const dsp::NominalModel& n = rec_.rec.nominal;
  if (n.cam.width != images_->format().width || n.cam.height != images_->format().height)
    throw std::runtime_error(cfg_.dir + "/recording.yaml: camera is " + std::to_string(n.cam.width) + "x" +
                             std::to_string(n.cam.height) + ", the pictures are " + std::to_string(images_->format().width) + "x" +
                             std::to_string(images_->format().height));
  timing_.height = n.cam.height;
  timing_.line_delay_s = cfg_.line_delay_s > 0 ? cfg_.line_delay_s : n.time.line_delay_s;
  timing_.readout = cfg_.readout.value_or(n.time.readout);
  timing_.frame_rate_hz = n.frame_rate_hz;
  if (rec_.rec.motion == dsp::MotionKind::Gyro) {
    for (const dsp::GyroSample& g : rec_.rec.gyro) {
      VelocitySample s;
      s.t_ns = std::llround(g.t * 1e9);
      s.imu_frame = true;
      for (int i = 0; i < 3; ++i) s.w[i] = g.w[i];
      motion_.push_back(s);
    }
  } else {
    motion_ = body_rates(rec_.rec.trajectory);
  }
  start();
}

double RecordingReplaySource::offset_s() const { return cfg_.time_offset_s.value_or(rec_.rec.nominal.time.time_offset_s); }

void RecordingReplaySource::start() {
  images_->start();
  next_frame_ = 0;
  pacer_.reset();
  // Motion from half a second before the first frame's: what came long before says nothing
  // about the frames (and the velocity input takes the first sample it sees as the drift's T0).
  const auto from = std::llround((rec_.rec.frames.front().t + offset_s() - 0.5) * 1e9);
  next_motion_ = 0;
  while (next_motion_ < motion_.size() && motion_[next_motion_].t_ns < from) ++next_motion_;
}

void RecordingReplaySource::deliver_motion_until(int64_t until_ns) {
  for (; next_motion_ < motion_.size() && motion_[next_motion_].t_ns <= until_ns; ++next_motion_)
    if (sink_) sink_(motion_[next_motion_]);
}

CaptureStatus RecordingReplaySource::capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) {
  if (next_frame_ >= rec_.rec.frames.size()) {
    deliver_motion_until(std::numeric_limits<int64_t>::max());  // the rest: nothing lost
    return CaptureStatus::EndOfStream;
  }
  const double t = rec_.rec.frames[next_frame_].t;
  if (!pacer_.wait(std::llround(t * 1e6), timeout)) return CaptureStatus::Timeout;
  // The motion over this frame's readout (on the motion clock, at the nominal offset), and a
  // margin for a calibrated offset that differs from it.
  deliver_motion_until(std::llround((t + timing_.frame_readout_s() + offset_s() + cfg_.motion_lead_s) * 1e9));
  CaptureStatus st;
  try {
    st = images_->capture(dst, meta, timeout);
  } catch (const std::exception& e) {  // this picture only: the ones after it may be fine
    ++next_frame_;
    const uint64_t n = refused_.fetch_add(1, std::memory_order_relaxed) + 1;
    if (refused_log_.due(n)) spdlog::error("{}: picture refused ({} so far): {}", cfg_.dir, n, e.what());
    return CaptureStatus::Timeout;
  }
  if (st == CaptureStatus::Frame) {
    ++next_frame_;
    frames_.fetch_add(1, std::memory_order_relaxed);
  }
  return st;
}

double RecordingReplaySource::progress() const {
  const size_t n = rec_.rec.frames.size();
  return n ? static_cast<double>(frames()) / static_cast<double>(n) : 1.0;
}

std::string RecordingReplaySource::summary(double seconds) const {
  char text[512];
  std::snprintf(text, sizeof text, "replayed %llu of %zu frames from %s in %.2f s (%.1f fps), %zu %s samples",
                static_cast<unsigned long long>(frames()), rec_.rec.frames.size(), cfg_.dir.c_str(), seconds,
                seconds > 0 ? static_cast<double>(frames()) / seconds : 0.0, motion_.size(),
                rec_.rec.motion == dsp::MotionKind::Gyro ? "gyro" : "trajectory-rate");
  return text;
}

void visit_config(formats::ConfigSection& c, RecordingReplayConfig& r) {
  visit_replay_path(c, "dir", r.dir, "an images recording (rsd-recording/1); relative to this file; or rsd --replay DIR");
  visit_replay_speed(c, r.speed);
  c.value("motion_lead_s", r.motion_lead_s, "motion delivered ahead of each frame's last row (beyond the nominal offset)");
  c.check(std::isfinite(r.motion_lead_s) && r.motion_lead_s >= 0, "motion_lead_s", "must be a non-negative number of seconds");
}

Driver recording_driver() {
  Driver d = make_driver<RecordingReplaySource, RecordingReplayConfig>(
      "recording", "an images recording's pictures and motion (rsd --replay DIR; docs/replay.md)", false, visit_config);
  // Not a real camera (the recording names its camera), but a calibration's row timing applies.
  d.use_row_timing = [](std::any& c, double line_delay_s, std::optional<dsp::Readout> readout, bool force) {
    auto& r = std::any_cast<RecordingReplayConfig&>(c);
    if (force || r.line_delay_s == 0) r.line_delay_s = line_delay_s;
    if (readout && force) r.readout = readout;
  };
  d.use_clock_offset = [](std::any& c, double offset_s) { std::any_cast<RecordingReplayConfig&>(c).time_offset_s = offset_s; };
  return d;
}

}  // namespace rsd::drivers
