// source.aravis: a GigE Vision camera's section, read and printed by one visit.
#include "drivers/aravis_source.hpp"
#include "dsp/core/input_limits.hpp"

namespace rsd::drivers {

void visit_config(formats::ConfigSection& c, AravisConfig& a) {
  c.value("camera", a.camera);
  c.value("pixel_format", a.pixel_format, "Mono8, Mono16, RGB8");
  c.value("width", a.width, "0: keep the camera's");
  c.check(a.width == 0 || (a.width >= kMinSide && a.width <= kMaxSide), "width", std::string("must be 0 (keep the camera's) or ") + dsp::limits::kSide.text);
  c.value("height", a.height);
  c.check(a.height == 0 || (a.height >= kMinSide && a.height <= kMaxSide), "height", std::string("must be 0 (keep the camera's) or ") + dsp::limits::kSide.text);
  c.value("frame_rate_hz", a.frame_rate_hz);
  c.check(a.frame_rate_hz >= 0 && a.frame_rate_hz <= kMaxRateHz, "frame_rate_hz", "must be 0 (keep the camera's) .. 10000");
  c.value("exposure_s", a.exposure_s);
  c.check(a.exposure_s >= 0 && a.exposure_s <= kMaxExposureS, "exposure_s", "must be 0 (keep the camera's) .. 10 s");
  c.value("buffers", a.buffers);
  c.check(a.buffers >= 2 && a.buffers <= kMaxBuffers, "buffers", "must be 2..64");
  c.value("line_delay_s", a.line_delay_s, "0: the readout fills the frame period");
  c.check(a.line_delay_s >= 0 && a.line_delay_s < 1, "line_delay_s", "must be 0 (the readout fills the frame period) .. 1 s");
  c.choice("readout", a.readout, {{"top_to_bottom", dsp::Readout::TopToBottom}, {"bottom_to_top", dsp::Readout::BottomToTop}});
  c.choice("stamp", a.stamp, {{"exposure_start", CameraStamp::ExposureStart}, {"exposure_end", CameraStamp::ExposureEnd}},
           "what the camera's timestamp marks: exposure_start or exposure_end");
  c.value("leader_delay_s", a.leader_delay_s);
  c.check(a.leader_delay_s >= 0 && a.leader_delay_s < 1, "leader_delay_s", "must be 0 .. 1 s");
  c.value("use_camera_clock", a.use_camera_clock);
}

Driver aravis_driver() {
  Driver d = make_driver<AravisSource, AravisConfig>("aravis", "GigE Vision, opened by address (never by discovery), or Fake_1",
                                                     true, visit_config);
  d.address_key = "camera";
  return d;
}

}  // namespace rsd::drivers
