#include "formats/timing_section.hpp"

namespace rsd::formats {

void read_timing_section(YamlMap t, dsp::NominalModel& n) {
  n.frame_rate_hz = t.number("frame_rate_hz", n.frame_rate_hz);
  if (!(n.frame_rate_hz > 0)) t.fail("frame_rate_hz", "must be positive");
  n.time.line_delay_s = t.number("line_delay_s", n.time.line_delay_s);
  if (n.time.line_delay_s < 0) t.fail("line_delay_s", "must not be negative");
  if (t.has("readout") && !dsp::parse_readout(t.text("readout", ""), n.time.readout))
    t.fail("readout", "must be top_to_bottom or bottom_to_top");
  n.time.time_offset_s = t.number("time_offset_s", n.time.time_offset_s);
  n.time.drift_ppm = t.number("drift_ppm", n.time.drift_ppm);
  t.finish();
}

}  // namespace rsd::formats
