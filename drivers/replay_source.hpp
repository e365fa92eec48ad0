// The replay source: an LCM log (rsd --record, rsd-sim, lcm-logger) played into the pipeline
// as if it were a live camera. Raw frames (bot_core.image_t on `channel`) become captures;
// velocity (rsd.velocity_t on `velocity_channel`) is delivered in log order, before the
// frames that follow it, so the velocity the rectifier sees at each frame is the same on
// every replay; so are bot_core.pose_t messages on the daemon's pose channel, if it has one
// (set_pose_message_sink). Recorded outputs (rectified images, frame info, health) are ignored; other
// channels and damaged events are skipped and counted (formats/lcm_log.hpp).
//
// Pacing follows the events' timestamps: speed 1 is real time, N is N times faster, 0 ("fast")
// does not wait at all (the daemon then hands frames over without dropping any).
#pragma once

#include <bot_core/image_t.hpp>

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "formats/lcm_log.hpp"
#include "drivers/message_source.hpp"
#include "drivers/playback.hpp"
#include "drivers/driver.hpp"
#include "formats/image_t_codec.hpp"
#include "dsp/core/time_line.hpp"

namespace rsd::drivers {

struct ReplayConfig {
  std::string file;
  double speed = 1.0;  // 1: real time; N: N x; 0: as fast as possible
  bool loop = false;   // start again at the end (times continue, shifted by the log's length)
  std::string channel = "RSD_RAW";
  std::string velocity_channel = "RSD_VELOCITY";
  // Channels rsd itself records (outputs): skipped without counting them as unknown.
  std::vector<std::string> ignore = {"RSD_RECT", "RSD_FRAME_INFO", "RSD_HEALTH", "RSD_CALIBRATION"};
  double fallback_fps = 30;  // frame rate when the log does not say and has one frame only
  bool quiet_skips = false;  // count skips without printing them
};

// Sleeps until a log time, scaled: the first time seen maps to now.
class ReplayPacer {
 public:
  explicit ReplayPacer(double speed = 1.0) : speed_(speed) {}
  void reset() { started_ = false, line_.reset(); }
  // Waits until the event at `log_us` is due, at most `timeout`; true when due.
  bool wait(int64_t log_us, std::chrono::milliseconds timeout);
  bool fast() const { return speed_ <= 0; }

 private:
  double speed_;
  bool started_ = false;
  int64_t log0_us_ = 0, wall0_ns_ = 0;
  // The log's event times (us): a wild one plays at once without moving the pace, instead of
  // stalling the replay until its time comes; a log whose times jumped for good (a recording
  // paused, logs joined) is paced again from its third event on the new line.
  dsp::TimeLine line_{60'000'000, 3, true};
};

// Parses "fast" / "max" (0) or a positive factor; false otherwise.
bool parse_speed(const std::string& text, double& speed);
// The keys every replay's section shares: a path relative to the configuration file, the speed.
void visit_replay_path(formats::ConfigSection& c, const char* key, std::string& path, const char* comment);
void visit_replay_speed(formats::ConfigSection& c, double& speed);

class ReplaySource final : public MessageSource, public Playback {
 public:
  explicit ReplaySource(ReplayConfig cfg);
  std::string name() const override { return "replay"; }
  // Reads the log up to its first usable raw frame for the format, timing and intrinsics.
  // Throws std::runtime_error (not CameraError: retrying cannot help) naming the file.
  void open() override;
  FrameFormat format() const override { return first_.format; }
  dsp::RowTiming timing() const override { return timing_; }
  void start() override;
  CaptureStatus capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) override;
  void stop() override {}
  std::optional<dsp::CameraModel> recorded_camera() const override { return first_.camera; }

  const ReplayConfig& config() const { return cfg_; }
  // For a progress bar and the closing summary (read from another thread: approximate).
  double progress() const override;
  uint64_t frames() const override { return frames_.load(std::memory_order_relaxed); }
  bool fast() const override { return cfg_.speed <= 0; }
  std::string summary(double seconds) const override;
  uint64_t ignored() const { return ignored_; }
  uint64_t passes() const { return passes_; }
  const formats::LcmLogReader* reader() const { return reader_.get(); }

 private:
  // The offsets of the next --loop pass; false (said in the log) when they would leave rsd's
  // window for times.
  bool next_pass_offsets();
  bool take_frame(const dsp::ImageView& dst, FrameMeta& meta);
  void take_velocity();
  void take_pose();
  // A message's own utime moved by this pass's offset (--loop), through dsp::Stamp.
  int64_t on_this_pass(int64_t utime) const;
  bool ignored_channel(const std::string& c) const;
  ReplayConfig cfg_;
  formats::RecordedFrame first_;
  dsp::RowTiming timing_;
  std::unique_ptr<formats::LcmLogReader> reader_;
  formats::LogEvent ev_;
  bool pending_ = false;
  ReplayPacer pacer_;
  bot_core::image_t img_;
  formats::RecordedFrame frame_;
  std::string why_;
  // Read by the service's thread for the progress bar while the capture thread writes them.
  std::atomic<uint64_t> frames_{0}, position_{0};
  uint64_t frames_this_pass_ = 0, ignored_ = 0, passes_ = 0;
  int64_t first_frame_ns_ = 0, last_frame_ns_ = 0, offset_ns_ = 0, ts_offset_us_ = 0, last_ts_us_ = 0, first_ts_us_ = 0;
  std::vector<std::string> unknown_seen_;
};

// The driver's entry (drivers/driver_registry.cpp) and its config section (source.replay).
Driver replay_driver();
void visit_config(formats::ConfigSection& c, ReplayConfig& s);

}  // namespace rsd::drivers
