// The `timing:` section of the files that state a nominal camera (rsd-recording/1's
// recording.yaml, rsd-sim scenarios, rsd-extract's --nominal): frame_rate_hz, line_delay_s,
// readout, time_offset_s, drift_ppm (docs/formats/recording-v1.md). The one reader of it.
#pragma once

#include "dsp/observation/recording.hpp"
#include "formats/yaml_map.hpp"

namespace rsd::formats {

// Keys present replace `n`'s values, absent ones keep them. Throws ConfigError naming the
// file, line and key for a bad value (frame rate not positive, negative line delay, unknown
// readout) or an unknown key.
void read_timing_section(YamlMap t, dsp::NominalModel& n);

}  // namespace rsd::formats
