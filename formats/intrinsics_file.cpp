#include "formats/intrinsics_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <vector>

#include "formats/yaml_map.hpp"
#include "dsp/core/input_limits.hpp"

namespace rsd::formats {
namespace {

// Both formats, like rsd, place pixel (0, 0) at the centre of the top-left pixel (see the
// header): the principal point is copied as written.

int required_int(YamlMap& m, const std::string& key) {
  if (!m.has(key)) m.fail(key, "is missing");
  return m.integer(key, 0);
}

std::string required_text(YamlMap& m, const std::string& key) {
  if (!m.has(key)) m.fail(key, "is missing");
  return m.text(key, "");
}

void check_focal(YamlMap& m, const std::string& key, double fx, double fy) {
  if (!(fx > 0) || !(fy > 0)) m.fail(key, "must have positive focal lengths");
}

// rsd's input limits (dsp/core/input_limits.hpp) on a camera read from `m`, each part reported
// under the key that gave it.
void check_limits(YamlMap& m, const dsp::CameraModel& c, const char* size_key, const char* matrix_key, const char* dist_key) {
  const dsp::CameraOutOfRange r = dsp::out_of_range(c);
  using P = dsp::CameraOutOfRange;
  if (r.part == P::None) return;
  m.fail(r.part == P::Size ? size_key : r.part == P::Distortion ? dist_key : matrix_key, "has " + r.why);
}

bool is_cam_key(const std::string& k) {
  return k.size() > 3 && k.compare(0, 3, "cam") == 0 &&
         std::all_of(k.begin() + 3, k.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// ---------------------------------------------------------------- Kalibr camchain

}  // namespace

dsp::CameraModel read_kalibr_camera(YamlMap& c) {
  dsp::CameraModel cam;
  const std::string model = required_text(c, "camera_model");
  if (model != "pinhole")
    c.fail("camera_model", "is '" + model + "': only 'pinhole' is supported");

  const std::vector<double> k = c.numbers("intrinsics", 4);  // [fu, fv, pu, pv]
  check_focal(c, "intrinsics", k[0], k[1]);
  cam.fx = k[0];
  cam.fy = k[1];
  cam.cx = k[2];
  cam.cy = k[3];

  const std::string dmodel = required_text(c, "distortion_model");
  if (dmodel == "radtan") {
    cam.dist = dsp::from_file_terms(dsp::LensModel::PinholeRadtan, c.numbers("distortion_coeffs", 4).data());
  } else if (dmodel == "none") {
    // No distortion; whatever distortion_coeffs holds is unused.
  } else if (dmodel == "equidistant") {
    cam.dist = dsp::from_file_terms(dsp::LensModel::PinholeEqui, c.numbers("distortion_coeffs", 4).data());
  } else {
    c.fail("distortion_model", "is '" + dmodel + "': only 'radtan', 'equidistant' (or 'none') are supported");
  }

  const std::vector<double> res = c.numbers("resolution", 2);
  for (double v : res)
    if (!dsp::limits::side_ok(v))
      c.fail("resolution", std::string("must be two whole numbers [width, height] of ") + dsp::limits::kSide.text);
  cam.width = static_cast<int>(res[0]);
  cam.height = static_cast<int>(res[1]);
  check_limits(c, cam, "resolution", "intrinsics", "distortion_coeffs");
  return cam;
}

namespace {


Intrinsics load_kalibr(const std::string& file, YamlMap& root, std::vector<std::string> cams,
                       std::string camera) {
  std::sort(cams.begin(), cams.end(), [](const std::string& a, const std::string& b) {
    return std::strtol(a.c_str() + 3, nullptr, 10) < std::strtol(b.c_str() + 3, nullptr, 10);
  });
  std::string available;
  for (const auto& c : cams) available += (available.empty() ? "" : ", ") + c;

  if (camera.empty()) {
    if (std::find(cams.begin(), cams.end(), "cam0") != cams.end())
      camera = "cam0";
    else if (cams.size() == 1)
      camera = cams.front();
    else
      root.fail(cams.front(), "and others: no cam0, name the camera to use (available: " + available + ")");
  } else if (std::find(cams.begin(), cams.end(), camera) == cams.end()) {
    root.fail(camera, "is not in this Kalibr camchain (available: " + available + ")");
  }

  YamlMap c = root.map(camera);
  Intrinsics out;
  out.source = "Kalibr camchain " + file + " " + camera;

  out.cam = read_kalibr_camera(c);

  if (c.has("line_delay")) {
    const double d = c.number("line_delay");
    if (!(d > 0)) c.fail("line_delay", "must be positive (seconds per row)");
    out.line_delay_s = d;
  }
  if (c.has("timeshift_cam_imu")) out.timeshift_cam_imu_s = c.number("timeshift_cam_imu");
  // rostopic, cam_overlaps, T_cn_cnm1, T_cam_imu and the rest: not needed, allowed.
  return out;
}

// ---------------------------------------------------------------- ROS camera_info

struct Matrix {
  int rows = 0, cols = 0;
  std::vector<double> data;
};

Matrix read_matrix(YamlMap& root, const std::string& key) {
  YamlMap m = root.map(key);
  Matrix out;
  out.rows = required_int(m, "rows");
  out.cols = required_int(m, "cols");
  if (out.rows < 1 || out.rows > 64) m.fail("rows", "must be between 1 and 64");
  if (out.cols < 1 || out.cols > 64) m.fail("cols", "must be between 1 and 64");
  out.data = m.numbers("data", static_cast<size_t>(out.rows * out.cols));  // rows x cols
  m.finish();
  return out;
}

Intrinsics load_ros(const std::string& file, YamlMap& root, const std::string& camera) {
  Intrinsics out;
  const int w = required_int(root, "image_width");
  const int h = required_int(root, "image_height");
  if (!dsp::limits::side_ok(w)) root.fail("image_width", std::string("must be ") + dsp::limits::kSide.text);
  if (!dsp::limits::side_ok(h)) root.fail("image_height", std::string("must be ") + dsp::limits::kSide.text);
  out.cam.width = w;
  out.cam.height = h;

  const std::string name = root.text("camera_name", "");
  if (!camera.empty() && camera != name)
    root.fail("camera_name", "is '" + name + "', not the camera '" + camera + "' asked for");
  out.source = "ROS camera_info " + file + (name.empty() ? "" : " (" + name + ")");

  {
    const Matrix K = read_matrix(root, "camera_matrix");
    if (K.rows != 3 || K.cols != 3) root.fail("camera_matrix", "must be 3 x 3");
    const auto& k = K.data;  // row-major [fx 0 cx; 0 fy cy; 0 0 1]
    if (k[1] != 0) root.fail("camera_matrix", "has skew (data[1] != 0), which rsd's camera model lacks");
    if (k[3] != 0 || k[6] != 0 || k[7] != 0 || k[8] != 1)
      root.fail("camera_matrix", "must have the form [fx, 0, cx, 0, fy, cy, 0, 0, 1]");
    check_focal(root, "camera_matrix", k[0], k[4]);
    out.cam.fx = k[0];
    out.cam.cx = k[2];
    out.cam.fy = k[4];
    out.cam.cy = k[5];
  }

  const std::string dmodel = required_text(root, "distortion_model");
  const Matrix D = read_matrix(root, "distortion_coefficients");
  if (D.rows != 1) root.fail("distortion_coefficients", "must have 1 row");
  const auto& d = D.data;
  if (dmodel == "plumb_bob") {
    if (d.size() != 5 && d.size() != 4)
      root.fail("distortion_coefficients", "must have 5 coefficients [k1, k2, p1, p2, k3] for plumb_bob, has " +
                                               std::to_string(d.size()));
    out.cam.dist = {d[0], d[1], d[2], d[3], d.size() == 5 ? d[4] : 0.0};
  } else if (dmodel == "rational_polynomial") {
    if (d.size() != 8)
      root.fail("distortion_coefficients",
                "must have 8 coefficients [k1, k2, p1, p2, k3, k4, k5, k6] for rational_polynomial, has " +
                    std::to_string(d.size()));
    if (d[5] != 0 || d[6] != 0 || d[7] != 0)
      root.fail("distortion_coefficients",
                "has non-zero rational_polynomial terms k4, k5, k6: not supported by the Brown-Conrady "
                "model rsd uses (k1, k2, p1, p2, k3); recalibrate with plumb_bob");
    out.cam.dist = {d[0], d[1], d[2], d[3], d[4]};
  } else if (dmodel == "equidistant") {
    if (d.size() != 4)
      root.fail("distortion_coefficients", "must have 4 coefficients [k1, k2, k3, k4] for equidistant, has " +
                                               std::to_string(d.size()));
    out.cam.dist = dsp::Distortion::equidistant(d[0], d[1], d[2], d[3]);
  } else {
    root.fail("distortion_model", "is '" + dmodel + "': only 'plumb_bob', 'equidistant' (or 'rational_polynomial' "
                                  "with k4 = k5 = k6 = 0) are supported");
  }

  check_limits(root, out.cam, "image_width", "camera_matrix", "distortion_coefficients");
  // Read for their shape only: rsd rectifies with its own model.
  if (root.has("rectification_matrix")) {
    const Matrix R = read_matrix(root, "rectification_matrix");
    if (R.rows != 3 || R.cols != 3) root.fail("rectification_matrix", "must be 3 x 3");
  }
  if (root.has("projection_matrix")) {
    const Matrix P = read_matrix(root, "projection_matrix");
    if (P.rows != 3 || P.cols != 4) root.fail("projection_matrix", "must be 3 x 4");
  }
  root.finish();
  return out;
}

}  // namespace

Intrinsics load_intrinsics(const std::string& file, const std::string& camera) {
  YamlMap root = YamlMap::load(file);
  if (root.has("image_width") || root.has("camera_matrix")) return load_ros(file, root, camera);
  std::vector<std::string> cams;
  for (const auto& k : root.keys())
    if (is_cam_key(k)) cams.push_back(k);
  if (!cams.empty()) return load_kalibr(file, root, cams, camera);
  throw ConfigError(file + ": neither a Kalibr camchain (cam0, cam1, ...) nor a ROS camera_info file "
                           "(image_width, camera_matrix, ...)");
}

dsp::CameraModel read_camera_section(YamlMap m, const dsp::CameraModel& defaults) {
  dsp::CameraModel c = defaults;
  c.width = m.integer("width", c.width);
  c.height = m.integer("height", c.height);
  // Before anything is computed from them (a width of -2^31 overflowed the default cx).
  if (!dsp::limits::side_ok(c.width) || !dsp::limits::side_ok(c.height))
    m.fail(!dsp::limits::side_ok(c.width) ? "width" : "height", std::string("must be ") + dsp::limits::kSide.text);
  c.fx = m.number("fx", c.fx);
  c.fy = m.number("fy", c.fx);
  c.cx = m.number("cx", 0.5 * (c.width - 1));
  c.cy = m.number("cy", 0.5 * (c.height - 1));
  // The lens (recording-v1's camera.model): pinhole-radtan's distortion is [k1, k2, p1, p2],
  // pinhole-equi's [k1, k2, k3, k4].
  if (m.has("model")) {
    const std::string name = required_text(m, "model");
    const auto lens = dsp::parse_lens_model(name);
    if (!lens) m.fail("model", "is '" + name + "': the lens models are pinhole-radtan and pinhole-equi");
    c.dist = dsp::Distortion{};
    c.dist.model = *lens;
  }
  if (m.has("distortion")) {
    c.dist = dsp::from_file_terms(c.dist.model, m.numbers("distortion", 4).data());
  }
  if (!(c.fx > 0 && c.fy > 0)) m.fail("fx", "and fy must be positive");
  if (const dsp::CameraOutOfRange r = dsp::out_of_range(c); r.part != dsp::CameraOutOfRange::None)
    m.fail(r.part == dsp::CameraOutOfRange::Distortion ? "distortion" : r.field, "has " + r.why);
  m.finish();
  return c;
}

}  // namespace rsd::formats
