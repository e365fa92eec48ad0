// rsd --record: a camera source wrapped so that every frame it delivers is also written to
// the recording as a raw bot_core.image_t (per-row timing and intrinsics in the metadata,
// formats/image_t_codec.hpp), on the capture thread right after capture. Velocity the
// source reports is recorded by the service's velocity sink on the same thread, before the
// frame it precedes: the log's order is the order the live pipeline saw, which is what makes
// a replay reproduce the run. Encoding uses a message and buffer sized once.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "drivers/camera_source.hpp"
#include "formats/lcm_log.hpp"
#include "formats/image_t_codec.hpp"

namespace rsd::daemon {

class RecordingSource final : public drivers::CameraSource {
 public:
  RecordingSource(drivers::CameraSource& inner, formats::LcmLogWriter& log, std::string raw_channel)
      : inner_(inner), log_(log), channel_(std::move(raw_channel)) {}
  std::string name() const override { return inner_.name(); }
  void open() override { inner_.open(); }
  drivers::FrameFormat format() const override { return inner_.format(); }
  dsp::RowTiming timing() const override { return inner_.timing(); }
  // After open(): the intrinsics to record with each frame (once the service knows them).
  void set_camera(const dsp::CameraModel& cam) {
    encoder_ = std::make_unique<formats::RawFrameEncoder>(inner_.format(), inner_.timing(), cam);
  }
  void start() override { inner_.start(); }
  drivers::CaptureStatus capture(const dsp::ImageView& dst, drivers::FrameMeta& meta,
                                 std::chrono::milliseconds timeout) override;
  void stop() override { inner_.stop(); }
  void set_velocity_sink(drivers::VelocitySink s) override { inner_.set_velocity_sink(std::move(s)); }

 private:
  drivers::CameraSource& inner_;
  formats::LcmLogWriter& log_;
  std::string channel_;
  std::unique_ptr<formats::RawFrameEncoder> encoder_;
};

}  // namespace rsd::daemon
