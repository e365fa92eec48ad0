// The sections of the files that state a nominal camera (rsd-recording/1's recording.yaml,
// rsd-sim scenarios, rsd-extract's --nominal), one reader each (docs/formats/recording-v1.md):
// `timing:` (frame_rate_hz, line_delay_s, readout, time_offset_s, drift_ppm) and the
// extrinsics of `motion:` (imu_to_camera, lever_arm_m). `camera:` is read_camera_section's
// (formats/intrinsics_file.hpp).
#pragma once

#include "dsp/observation/recording.hpp"
#include "formats/yaml_map.hpp"

namespace rsd::formats {

// Keys present replace `n`'s values, absent ones keep them. Throws ConfigError naming the
// file, line and key for a bad value (frame rate not positive, negative line delay, unknown
// readout) or an unknown key.
void read_timing_section(YamlMap t, dsp::NominalModel& n);

// imu_to_camera (nine numbers, row-major, checked a rotation) and lever_arm_m, where given.
// The section's other keys (a recording's kind and file) are the caller's to read.
void read_motion_extrinsics(YamlMap& m, dsp::NominalModel& n);

}  // namespace rsd::formats
