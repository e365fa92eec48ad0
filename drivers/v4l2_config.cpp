// source.v4l2: a V4L2 device's section, read and printed by one visit.
#include "drivers/v4l2_source.hpp"

namespace rsd::drivers {

void visit_config(formats::ConfigSection& c, V4l2Config& v) {
  c.value("device", v.device);
  c.value("width", v.width);
  c.value("height", v.height);
  c.value("pixel_format", v.pixel_format, "GREY, Y16, YUYV, RGB24");
  c.value("fps", v.fps);
  c.check(v.fps > 0, "fps", "must be positive");
  c.value("buffers", v.buffers);
  c.value("line_delay_s", v.line_delay_s);
  c.choice("readout", v.readout, {{"top_to_bottom", dsp::Readout::TopToBottom}, {"bottom_to_top", dsp::Readout::BottomToTop}});
  c.value("exposure_s", v.exposure_s, "0: ask the driver");
}

Driver v4l2_driver() {
  Driver d = make_driver<V4l2Source, V4l2Config>("v4l2", "a V4L2 device (kernel video capture)", true, visit_config);
  d.address_key = "device";
  return d;
}

}  // namespace rsd::drivers
