#include "formats/nominal_sections.hpp"

#include <Eigen/LU>
#include <string>

#include "dsp/core/input_limits.hpp"
#include "dsp/geometry/rotation_check.hpp"

namespace rsd::formats {

namespace {

// rsd's input limits (dsp/core/input_limits.hpp), under the key that gave the number.
void check_range(YamlMap& m, const char* key, double v, const dsp::limits::Range& r) {
  if (!r.contains(v)) m.fail(key, std::string("must be ") + r.text);
}

}  // namespace

void read_timing_section(YamlMap t, dsp::NominalModel& n) {
  n.frame_rate_hz = t.number("frame_rate_hz", n.frame_rate_hz);
  check_range(t, "frame_rate_hz", n.frame_rate_hz, dsp::limits::kFrameRateHz);
  n.time.line_delay_s = t.number("line_delay_s", n.time.line_delay_s);
  check_range(t, "line_delay_s", n.time.line_delay_s, dsp::limits::kLineDelayS);
  if (t.has("readout") && !dsp::parse_readout(t.text("readout", ""), n.time.readout))
    t.fail("readout", "must be top_to_bottom or bottom_to_top");
  n.time.time_offset_s = t.number("time_offset_s", n.time.time_offset_s);
  check_range(t, "time_offset_s", n.time.time_offset_s, dsp::limits::kTimeShiftS);
  n.time.drift_ppm = t.number("drift_ppm", n.time.drift_ppm);
  check_range(t, "drift_ppm", n.time.drift_ppm, dsp::limits::kDriftPpm);
  t.finish();
}

void read_motion_extrinsics(YamlMap& m, dsp::NominalModel& n) {
  if (m.has("imu_to_camera")) {
    const auto r = m.numbers("imu_to_camera", 9);
    const Eigen::Matrix3d R = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>(r.data());
    if (!dsp::is_rotation(R))
      m.fail("imu_to_camera", "is not a rotation matrix (row-major, orthonormal, determinant +1)");
    n.imu_to_camera = R;
  }
  if (m.has("lever_arm_m")) {
    const auto l = m.numbers("lever_arm_m", 3);
    n.lever_arm = Eigen::Vector3d(l[0], l[1], l[2]);
  }
}

}  // namespace rsd::formats
