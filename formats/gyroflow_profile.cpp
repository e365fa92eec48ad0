#include "formats/gyroflow_profile.hpp"

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "dsp/core/input_limits.hpp"
#include "formats/yaml_map.hpp"

namespace rsd::formats {
namespace {

// calib_dimension: two whole sides within rsd's frame limits.
void read_dimension(YamlMap dim, dsp::CameraModel& cam) {
  const double w = dim.number("w"), h = dim.number("h");
  for (const auto& [key, v] : {std::pair{"w", w}, std::pair{"h", h}})
    if (!dsp::limits::side_ok(v)) dim.fail(key, std::string("must be a whole number of ") + dsp::limits::kSide.text);
  cam.width = static_cast<int>(w);
  cam.height = static_cast<int>(h);
}

// fisheye_params: K without skew, and OpenCV's fisheye coefficients.
void read_fisheye(YamlMap fp, dsp::CameraModel& cam) {
  const std::vector<double> K = fp.matrix("camera_matrix", 3, 3);
  if (K[1] != 0 || K[3] != 0 || K[6] != 0 || K[7] != 0 || K[8] != 1)
    fp.fail("camera_matrix", "must have the form [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]");
  cam.fx = K[0], cam.cx = K[2], cam.fy = K[4], cam.cy = K[5];
  const std::vector<double> d = fp.numbers("distortion_coeffs", 4);
  cam.dist = dsp::Distortion::equidistant(d[0], d[1], d[2], d[3]);
  if (const dsp::CameraOutOfRange r = dsp::out_of_range(cam); r.part != dsp::CameraOutOfRange::None)
    fp.fail(r.part == dsp::CameraOutOfRange::Distortion ? "distortion_coeffs" : "camera_matrix", "has " + r.why);
}

// The keys that would make the profile another camera than rsd's model: refused by name.
void refuse_other_models(YamlMap& root) {
  if (root.has("use_opencv_standard") && !root.is_null("use_opencv_standard") && root.boolean("use_opencv_standard", false))
    root.fail("use_opencv_standard", "is true: the lens is OpenCV's standard model (calib_params), which rsd does "
                                     "not read from gyroflow profiles; use a fisheye profile or a Kalibr camchain");
  if (root.has("distortion_model") && !root.is_null("distortion_model")) {
    const std::string m = root.text("distortion_model", "");
    if (m != "opencv_fisheye")
      root.fail("distortion_model", "is '" + m + "': rsd reads gyroflow's opencv_fisheye profiles only");
  }
  for (const char* key : {"input_horizontal_stretch", "input_vertical_stretch"})
    if (root.has(key) && !root.is_null(key) && root.number(key) != 1)
      root.fail(key, "is not 1: an anamorphic (stretched) input is not rsd's camera model");
}

void read_readout(YamlMap& root, GyroflowProfile& p) {
  if (root.has("frame_readout_time") && !root.is_null("frame_readout_time")) {
    const double ms = root.number("frame_readout_time");
    if (!(ms >= 0 && ms <= 1000)) root.fail("frame_readout_time", "must be 0..1000 ms");
    if (ms > 0) p.frame_readout_s = ms * 1e-3;  // gyroflow writes 0 for "not measured" too
  }
  if (root.has("frame_readout_direction") && !root.is_null("frame_readout_direction")) {
    const std::string d = root.text("frame_readout_direction", "");
    if (d == "BottomToTop") p.readout = dsp::Readout::BottomToTop;
    else if (d != "TopToBottom")
      root.fail("frame_readout_direction", "is '" + d + "': rsd's rows are read TopToBottom or BottomToTop");
  }
}

}  // namespace

GyroflowProfile read_gyroflow_profile(const std::string& file) {
  YamlMap root = YamlMap::load(file);
  GyroflowProfile p;
  p.name = root.has("name") && !root.is_null("name") ? root.text("name", "") : "";
  if (p.name.empty()) p.name = std::filesystem::path(file).stem().string();
  refuse_other_models(root);
  read_dimension(root.map("calib_dimension"), p.cam);
  read_fisheye(root.map("fisheye_params"), p.cam);
  read_readout(root, p);
  return p;
}

dsp::CameraModel profile_camera_at(const GyroflowProfile& p, const std::string& file, int width, int height) {
  const double sx = static_cast<double>(width) / p.cam.width, sy = static_cast<double>(height) / p.cam.height;
  if (std::abs(sx / sy - 1) > 0.01)
    throw ConfigError(file + ": 'calib_dimension' is " + std::to_string(p.cam.width) + "x" + std::to_string(p.cam.height) +
                      ", another aspect ratio than " + std::to_string(width) + "x" + std::to_string(height) +
                      ": another crop of the sensor needs its own profile");
  return dsp::scaled_camera(p.cam, width, height);
}

}  // namespace rsd::formats
