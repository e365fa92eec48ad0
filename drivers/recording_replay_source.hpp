// An images recording (docs/formats/recording-v1.md, observations.kind: images) played as a
// camera: rsd --replay DIR. The pictures (images.csv or a video) are the frames, stamped with
// frames.csv's times (camera clock) and numbered with its frame numbers; the row timing is
// recording.yaml's nominal one. The motion goes to the velocity input as the motion sensor's
// own measurements, on its clock and in its axes, for the calibration to correct: gyro.csv as
// it is, a trajectory as the body rates and velocity between consecutive poses (body axes).
// Each frame is preceded by every motion sample up to its readout's end plus the nominal
// clock offset and a margin, so the rectifier finds the motion covering every row.
//
// Pacing follows frames.csv: speed 1 is real time, N is N times faster, 0 ("fast") does not
// wait (the daemon then hands frames over without dropping any).
//
// Thread contract: as every CameraSource; progress() and frames() from any thread.
#pragma once

#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/driver.hpp"
#include "drivers/images_source.hpp"
#include "drivers/playback.hpp"
#include "drivers/replay_source.hpp"
#include "drivers/tenfold_log.hpp"
#include "formats/recording_v1.hpp"

namespace rsd::drivers {

struct RecordingReplayConfig {
  std::string dir;
  double speed = 1.0;  // 1: real time; N: N x; 0: as fast as possible
  // Motion samples delivered ahead of each frame's last row (beyond the nominal clock offset).
  double motion_lead_s = 0.05;
  // A calibration's row timing (source.calibration_file, rsd --calibration) over the recording's
  // nominal one; not a key of the section.
  double line_delay_s = 0;  // 0: recording.yaml's
  std::optional<dsp::Readout> readout;
  std::optional<double> time_offset_s;  // the calibration's clock offset; default recording.yaml's
};

// The body's angular rate (body axes) and velocity (body axes) between consecutive poses,
// stamped at their midpoints: what an IMU on the body would report, on the motion clock.
std::vector<VelocitySample> body_rates(const std::vector<dsp::PoseSample>& poses);

class RecordingReplaySource final : public CameraSource, public Playback {
 public:
  explicit RecordingReplaySource(RecordingReplayConfig cfg);
  std::string name() const override { return "recording"; }
  // Reads and checks the recording (std::runtime_error naming the file: retrying cannot help).
  void open() override;
  FrameFormat format() const override { return images_->format(); }
  dsp::RowTiming timing() const override { return timing_; }
  void start() override;
  CaptureStatus capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) override;
  void stop() override {}
  void set_velocity_sink(VelocitySink sink) override { sink_ = std::move(sink); }

  double progress() const override;
  uint64_t frames() const override { return frames_.load(std::memory_order_relaxed); }
  bool fast() const override { return cfg_.speed <= 0; }
  std::string summary(double seconds) const override;
  // Pictures that could not be read or do not match the first (truncated, missing, another size
  // or pixel format): each refused and counted (rsd.health_t's frames_refused), the first and
  // every tenfold named in the log; the replay goes on with the next picture.
  uint64_t refused() const override { return refused_.load(std::memory_order_relaxed); }

  const formats::ImagesRecording& recording() const { return rec_; }

 private:
  void deliver_motion_until(int64_t until_ns);  // every motion sample stamped up to until_ns
  double offset_s() const;
  RecordingReplayConfig cfg_;
  formats::ImagesRecording rec_;
  std::unique_ptr<ImagesSource> images_;
  dsp::RowTiming timing_;
  std::vector<VelocitySample> motion_;
  size_t next_motion_ = 0, next_frame_ = 0;
  ReplayPacer pacer_;
  VelocitySink sink_;
  std::atomic<uint64_t> frames_{0}, refused_{0};
  TenfoldLog refused_log_;  // the capture thread's
};

Driver recording_driver();
void visit_config(formats::ConfigSection& c, RecordingReplayConfig& s);

}  // namespace rsd::drivers
