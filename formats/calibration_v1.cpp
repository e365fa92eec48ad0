#include "formats/calibration_v1.hpp"

#include <yaml-cpp/yaml.h>

#include <Eigen/LU>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "formats/config_section.hpp"
#include "formats/number_text.hpp"
#include "formats/intrinsics_file.hpp"
#include "formats/yaml_map.hpp"
#include "dsp/core/input_limits.hpp"
#include "dsp/geometry/rotation_check.hpp"

namespace rsd::formats {

namespace {

constexpr const char* kFormat = "rsd-calibration/1";
// The keys a sigma may be given for: the numeric keys of cam0 and cam0.rsd.
const std::map<std::string, size_t> kSigmaKeys = {
    {"intrinsics", 4}, {"distortion_coeffs", 4}, {"timeshift_cam_imu", 1}, {"line_delay_s", 1},
    {"drift_ppm", 1},  {"gyro_bias_rad_s", 3},   {"gyro_scale", 3},        {"lever_arm_m", 3}};

Eigen::Vector3d vec3(YamlMap& m, const char* key, const Eigen::Vector3d& fallback) {
  if (!m.has(key)) return fallback;
  const auto v = m.numbers(key, 3);
  return {v[0], v[1], v[2]};
}

void read_t_cam_imu(YamlMap& cam, Calibration& c) {
  if (!cam.has("T_cam_imu")) return;
  const std::vector<double> t = cam.matrix("T_cam_imu", 4, 4);
  const Eigen::Matrix<double, 4, 4, Eigen::RowMajor> T(t.data());
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  if (!dsp::is_rotation(R))
    cam.fail("T_cam_imu", "has a rotation part that is not a rotation (orthonormal, determinant +1, within 1e-6)");
  if (T(3, 0) != 0 || T(3, 1) != 0 || T(3, 2) != 0 || T(3, 3) != 1) cam.fail("T_cam_imu", "must end with the row [0, 0, 0, 1]");
  c.imu_to_camera = R;
  c.imu_to_camera_t = T.topRightCorner<3, 1>();
}

void read_sigma(YamlMap s, Calibration& c) {
  for (const std::string& k : s.keys()) {
    const auto it = kSigmaKeys.find(k);
    if (it == kSigmaKeys.end()) s.fail(k, "is not a key a sigma can be given for");
    std::vector<double> v = it->second == 1 ? std::vector<double>{s.number(k)} : s.numbers(k, it->second);
    for (double x : v)
      if (!(x >= 0)) s.fail(k, "must not be negative");
    c.sigma[k] = std::move(v);
  }
  s.finish();
}

// rsd's input limits (dsp/core/input_limits.hpp) on a number or each element of a vector.
void check_range(YamlMap& m, const std::string& key, double v, const dsp::limits::Range& range) {
  if (!range.contains(v)) m.fail(key, "is " + number_text(v) + ", outside " + range.text);
}
void check_range(YamlMap& m, const std::string& key, const Eigen::Vector3d& v, const dsp::limits::Range& range) {
  for (int i = 0; i < 3; ++i) check_range(m, key, v[i], range);
}

void read_rsd(YamlMap r, Calibration& c) {
  c.has_rsd_block = true;
  if (!r.has("format")) r.fail("format", "is missing (rsd-calibration/1)");
  const std::string format = r.text("format", "");
  if (format != kFormat) r.fail("format", "is '" + format + "', expected " + kFormat);
  c.line_delay_s = r.number("line_delay_s", c.line_delay_s);
  if (!dsp::limits::kLineDelayS.contains(c.line_delay_s))
    r.fail("line_delay_s", std::string("must be ") + dsp::limits::kLineDelayS.text + " (0: global shutter)");
  if (r.has("readout") && !dsp::parse_readout(r.text("readout", ""), c.readout))
    r.fail("readout", "must be top_to_bottom or bottom_to_top");
  c.drift_ppm = r.number("drift_ppm", c.drift_ppm);
  check_range(r, "drift_ppm", c.drift_ppm, dsp::limits::kDriftPpm);
  c.gyro_bias_rad_s = vec3(r, "gyro_bias_rad_s", c.gyro_bias_rad_s);
  check_range(r, "gyro_bias_rad_s", c.gyro_bias_rad_s, dsp::limits::kGyroBiasRadS);
  c.gyro_scale = vec3(r, "gyro_scale", c.gyro_scale);
  check_range(r, "gyro_scale", c.gyro_scale, dsp::limits::kGyroScale);
  c.lever_arm_m = vec3(r, "lever_arm_m", c.lever_arm_m);
  check_range(r, "lever_arm_m", c.lever_arm_m, dsp::limits::kLeverArmM);
  c.source = r.text("source", "");
  if (r.has("sigma")) read_sigma(r.map("sigma"), c);
  r.finish();  // unknown keys inside cam0.rsd are errors
}

// ---------------------------------------------------------------- writing

YAML::Node number(double x) { return YAML::Node(number_text(x)); }

YAML::Node flow(const double* v, int n) {
  YAML::Node s(YAML::NodeType::Sequence);
  for (int i = 0; i < n; ++i) s.push_back(number(v[i]));
  s.SetStyle(YAML::EmitterStyle::Flow);
  return s;
}

YAML::Node flow(const Eigen::Vector3d& v) { return flow(v.data(), 3); }

}  // namespace

Calibration read_calibration(const std::string& file) {
  YamlMap root = YamlMap::load(file);
  YamlMap cam = root.map("cam0");
  Calibration c;
  c.file = file;
  c.cam = read_kalibr_camera(cam);
  read_t_cam_imu(cam, c);
  c.timeshift_cam_imu_s = cam.number("timeshift_cam_imu", 0.0);
  check_range(cam, "timeshift_cam_imu", c.timeshift_cam_imu_s, dsp::limits::kTimeShiftS);
  if (cam.has("rsd")) read_rsd(cam.map("rsd"), c);
  return c;
}

void require_resolution(const Calibration& c, int width, int height) {
  if (c.cam.width != width || c.cam.height != height)
    throw ConfigError(c.file + ": 'cam0.resolution' is [" + std::to_string(c.cam.width) + ", " + std::to_string(c.cam.height) +
                      "], but the camera delivers " + std::to_string(width) + "x" + std::to_string(height));
}

void write_calibration(const std::string& file, const Calibration& c) {
  YAML::Node cam;
  cam["camera_model"] = "pinhole";
  const double k[4] = {c.cam.fx, c.cam.fy, c.cam.cx, c.cam.cy};
  cam["intrinsics"] = flow(k, 4);
  // Kalibr's names: radtan [k1, k2, p1, p2], equidistant [k1, k2, k3, k4] (pinhole-equi).
  cam["distortion_model"] = c.cam.dist.model == dsp::LensModel::PinholeEqui ? "equidistant" : "radtan";
  cam["distortion_coeffs"] = flow(dsp::file_terms(c.cam.dist).data(), 4);
  const double res[2] = {static_cast<double>(c.cam.width), static_cast<double>(c.cam.height)};
  cam["resolution"] = flow(res, 2);
  Eigen::Matrix<double, 4, 4, Eigen::RowMajor> T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = c.imu_to_camera;
  T.topRightCorner<3, 1>() = c.imu_to_camera_t;
  for (int r = 0; r < 4; ++r) cam["T_cam_imu"].push_back(flow(T.row(r).data(), 4));
  cam["timeshift_cam_imu"] = number(c.timeshift_cam_imu_s);
  YAML::Node rsd;
  rsd["format"] = kFormat;
  rsd["line_delay_s"] = number(c.line_delay_s);
  rsd["readout"] = std::string(dsp::to_string(c.readout));
  rsd["drift_ppm"] = number(c.drift_ppm);
  rsd["gyro_bias_rad_s"] = flow(c.gyro_bias_rad_s);
  rsd["gyro_scale"] = flow(c.gyro_scale);
  rsd["lever_arm_m"] = flow(c.lever_arm_m);
  if (!c.source.empty()) rsd["source"] = c.source;
  for (const auto& [key, v] : c.sigma) rsd["sigma"][key] = v.size() == 1 ? number(v[0]) : flow(v.data(), static_cast<int>(v.size()));
  cam["rsd"] = rsd;
  YAML::Node root;
  root["cam0"] = cam;
  // Written beside the file and renamed over it: a reader (a restarting daemon loading its
  // state file) sees the old file or the new one, never half of one.
  const std::string tmp = file + ".tmp";
  {
    std::ofstream out(tmp);
    out << "# " << kFormat << " (docs/formats/calibration-v1.md): a Kalibr camchain-imucam file with rsd's additions\n"
        << YAML::Dump(root) << "\n";
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw std::runtime_error(file + ": cannot write the calibration");
    }
  }
  if (std::rename(tmp.c_str(), file.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp.c_str());
    throw std::runtime_error(file + ": cannot write the calibration (" + why + ")");
  }
}

Calibration calibration_of(const dsp::NominalModel& n, const std::string& source) {
  Calibration c;
  c.cam = n.cam;
  c.imu_to_camera = n.imu_to_camera;
  c.timeshift_cam_imu_s = n.time.time_offset_s;  // t_imu = t_cam + offset, as time_offset_s
  c.line_delay_s = n.time.line_delay_s;
  c.readout = n.time.readout;
  c.drift_ppm = n.time.drift_ppm;
  c.lever_arm_m = n.lever_arm;
  c.source = source;
  c.has_rsd_block = true;
  c.file = source;
  return c;
}

}  // namespace rsd::formats
