// source.v4l2: a V4L2 device's section, read and printed by one visit.
#include "drivers/v4l2_source.hpp"
#include "dsp/core/input_limits.hpp"

namespace rsd::drivers {

void visit_config(formats::ConfigSection& c, V4l2Config& v) {
  c.value("device", v.device);
  c.value("width", v.width);
  c.check(v.width >= kMinSide && v.width <= kMaxSide, "width", std::string("must be ") + dsp::limits::kSide.text);
  c.value("height", v.height);
  c.check(v.height >= kMinSide && v.height <= kMaxSide, "height", std::string("must be ") + dsp::limits::kSide.text);
  c.value("pixel_format", v.pixel_format, "GREY, Y16, RGB24, BGR3, YUYV, NV12, YU12, or a Bayer fourcc: RGGB .. GB16");
  c.value("fps", v.fps);
  c.check(v.fps > 0 && v.fps <= kMaxRateHz, "fps", "must be positive, at most 10000");
  c.value("buffers", v.buffers);
  c.check(v.buffers >= 2 && v.buffers <= static_cast<unsigned>(kMaxBuffers), "buffers", "must be 2..64");
  c.value("line_delay_s", v.line_delay_s);
  c.check(v.line_delay_s >= 0 && v.line_delay_s < 1, "line_delay_s", "must be 0 (the readout fills the frame period) .. 1 s");
  c.choice("readout", v.readout, {{"top_to_bottom", dsp::Readout::TopToBottom}, {"bottom_to_top", dsp::Readout::BottomToTop}});
  c.value("exposure_s", v.exposure_s, "0: ask the driver");
  c.check(v.exposure_s >= 0 && v.exposure_s <= kMaxExposureS, "exposure_s", "must be 0 (the driver's) .. 10 s");
}

Driver v4l2_driver() {
  Driver d = make_driver<V4l2Source, V4l2Config>("v4l2", "a V4L2 device (kernel video capture)", true, visit_config);
  d.address_key = "device";
  return d;
}

}  // namespace rsd::drivers
