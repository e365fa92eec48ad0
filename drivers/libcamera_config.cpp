// source.libcamera: a libcamera camera's section, read and printed by one visit.
#include "drivers/libcamera_source.hpp"
#include "dsp/core/input_limits.hpp"

namespace rsd::drivers {

void visit_config(formats::ConfigSection& c, LibcameraConfig& l) {
  c.value("camera_id", l.camera_id, "\"\": the first camera");
  c.value("width", l.width);
  c.check(l.width >= kMinSide && l.width <= kMaxSide, "width", std::string("must be ") + dsp::limits::kSide.text);
  c.value("height", l.height);
  c.check(l.height >= kMinSide && l.height <= kMaxSide, "height", std::string("must be ") + dsp::limits::kSide.text);
  c.pixel_format("format", l.format);  // asked for; the camera's nearest is taken
  c.value("role", l.role);
  c.value("fps", l.fps);
  c.check(l.fps > 0 && l.fps <= kMaxRateHz, "fps", "must be positive, at most 10000");
  c.value("line_delay_s", l.line_delay_s);
  c.check(l.line_delay_s >= 0 && l.line_delay_s < 1, "line_delay_s", "must be 0 (the readout fills the frame period) .. 1 s");
  c.choice("readout", l.readout, {{"top_to_bottom", dsp::Readout::TopToBottom}, {"bottom_to_top", dsp::Readout::BottomToTop}});
  c.value("exposure_s", l.exposure_s);
  c.check(l.exposure_s >= 0 && l.exposure_s <= kMaxExposureS, "exposure_s", "must be 0 (the driver's) .. 10 s");
}

Driver libcamera_driver() {
  Driver d = make_driver<LibcameraSource, LibcameraConfig>("libcamera", "a camera through libcamera (Raspberry Pi and other ISPs)",
                                                           true, visit_config);
  d.address_key = "camera_id";
  return d;
}

}  // namespace rsd::drivers
