#include "tools/extract/nominal_model.hpp"

#include <sstream>

#include "dsp/core/statistics.hpp"
#include "dsp/geometry/rotation_check.hpp"
#include "formats/intrinsics_file.hpp"
#include "formats/nominal_sections.hpp"
#include "formats/yaml_map.hpp"
#include "tools/common/cli_util.hpp"
#include "tools/common/picture_observations.hpp"

namespace rsd::tools::extract {

using formats::MotionLog;

namespace {

Eigen::Matrix3d rotation(const std::vector<double>& r, const std::string& what) {
  const Eigen::Matrix3d R = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>(r.data());
  if (!dsp::is_rotation(R))
    throw UsageError(what + ": not a rotation matrix (row-major, orthonormal, determinant +1)");
  return R;
}


// --nominal: recording.yaml's camera, timing and motion keys; a whole recording.yaml is
// accepted (its other keys are ignored), so a simulator's header can serve as the nominal.
void read_nominal_file(const std::string& file, Nominal& n, bool& line_delay_given) {
  formats::YamlMap root = formats::YamlMap::load(file);
  if (root.has("camera")) {
    formats::YamlMap c = root.map("camera");
    if (!c.has("fx")) c.fail("fx", "is missing (the nominal focal length, pixels)");
    n.model.cam = formats::read_camera_section(c, n.model.cam);
    n.have_camera = true;
  }
  if (root.has("timing")) {
    formats::YamlMap t = root.map("timing");
    if (t.has("line_delay_s")) line_delay_given = true;
    formats::read_timing_section(t, n.model);
  }
  if (root.has("motion")) {
    formats::YamlMap m = root.map("motion");
    formats::read_motion_extrinsics(m, n.model);
    if (m.has("imu_to_camera")) n.imu_to_camera = n.model.imu_to_camera;
    m.text("kind", ""), m.text("file", "");  // a recording.yaml's own files: not ours to follow
    m.finish();
  }
  if (root.has("observations")) root.map("observations");
  root.text("format", ""), root.text("frames", ""), root.number("noise_px", 0.0);
  root.finish();
}

// The options, highest precedence, over what the files and the log said.
void apply_options(const Options& o, Nominal& n, std::string& line_delay_from) {
  if (o.frame_rate_hz) n.model.frame_rate_hz = *o.frame_rate_hz;
  if (o.time_offset_s) n.model.time.time_offset_s = *o.time_offset_s;
  if (!o.readout.empty() && !dsp::parse_readout(o.readout, n.model.time.readout))
    throw UsageError("--readout: expected top_to_bottom or bottom_to_top, got '" + o.readout + "'");
  if (o.line_delay_s) n.model.time.line_delay_s = *o.line_delay_s, line_delay_from = "--line-delay";
  if (o.global_shutter) n.model.time.line_delay_s = 0, line_delay_from = "--assume-global-shutter";
  if (!o.lever_arm.empty()) n.model.lever_arm = *parse_vec3(o.lever_arm);
  if (!o.imu_to_camera.empty()) {
    const std::string expected = "--imu-to-camera: expected nine comma-separated numbers, got '" + o.imu_to_camera + "'";
    std::vector<double> r;
    std::stringstream in(o.imu_to_camera);
    for (std::string x; std::getline(in, x, ',');) {
      const auto v = parse_number(x);
      if (!v) throw UsageError(expected);
      r.push_back(*v);
    }
    if (r.size() != 9) throw UsageError(expected);
    n.imu_to_camera = rotation(r, "--imu-to-camera");
  }
}

}  // namespace

Nominal nominal_model(const Options& o, const formats::MotionLog& s) {
  Nominal n;
  const formats::LogFrame& f0 = s.frames.front();
  n.model.cam.width = f0.width, n.model.cam.height = f0.height;
  n.model.cam.cx = 0.5 * (f0.width - 1), n.model.cam.cy = 0.5 * (f0.height - 1);
  std::vector<double> dt;
  for (size_t k = 1; k < s.frames.size(); ++k) dt.push_back(s.frames[k].t - s.frames[k - 1].t);
  if (!dt.empty() && dsp::median(dt) > 0) n.model.frame_rate_hz = 1.0 / dsp::median(dt);
  std::string line_delay_from = "global shutter (nothing says otherwise)";
  bool line_delay_given = false;
  // Lowest precedence first: the log's metadata, then the intrinsics file, the nominal file, options.
  if (f0.line_delay_s) n.model.time.line_delay_s = *f0.line_delay_s, line_delay_from = "the log's metadata (line_delay_ns, or a .gcsv's frame_readout_time)";
  if (f0.readout) n.model.time.readout = *f0.readout;
  if (!o.intrinsics.empty()) {
    const formats::Intrinsics in = formats::load_intrinsics(o.intrinsics, o.intrinsics_camera);
    n.model.cam = in.cam, n.have_camera = true;
    if (in.line_delay_s) n.model.time.line_delay_s = *in.line_delay_s, line_delay_from = in.source;
    if (in.timeshift_cam_imu_s) n.model.time.time_offset_s = *in.timeshift_cam_imu_s;  // t_imu = t_cam + shift
    n.notes.push_back("intrinsics from " + in.source);
  }
  if (!o.nominal.empty()) {
    if (!o.intrinsics.empty()) {
      formats::YamlMap probe = formats::YamlMap::load(o.nominal);
      if (probe.has("camera")) throw UsageError("--nominal " + o.nominal + " has a camera: block and --intrinsics was given: state the camera once");
    }
    read_nominal_file(o.nominal, n, line_delay_given);
    if (line_delay_given) line_delay_from = o.nominal;
  }
  if (!n.have_camera)
    throw UsageError("no nominal intrinsics: give --nominal FILE with a camera: block (fx, fy, cx, cy) or --intrinsics FILE");
  if (n.model.cam.width != f0.width || n.model.cam.height != f0.height)
    throw UsageError("the nominal camera is " + std::to_string(n.model.cam.width) + "x" + std::to_string(n.model.cam.height) +
                     " but " + o.log + " has " + std::to_string(f0.width) + "x" + std::to_string(f0.height) + " frames on " + o.image_channel);
  apply_options(o, n, line_delay_from);
  n.notes.push_back("line delay " + format_number(n.model.time.line_delay_s, 6) + " s from " + line_delay_from);
  return n;
}

std::vector<bool> covered(const MotionLog& s, const Nominal& n, bool by_gyro) {
  std::vector<double> t;
  for (const formats::LogFrame& f : s.frames) t.push_back(f.t);
  return covered_by_motion(t, by_gyro ? s.gyro.front().t : s.poses.front().t, by_gyro ? s.gyro.back().t : s.poses.back().t,
                           n.model);
}

std::vector<dsp::FrameStamp> covered_frames(const MotionLog& s, const std::vector<bool>& ok, const std::string& input) {
  std::vector<dsp::FrameStamp> frames;
  for (size_t k = 0; k < s.frames.size(); ++k)
    if (ok[k]) frames.push_back({static_cast<int>(k), s.frames[k].t});
  if (frames.empty())
    throw std::runtime_error(input + ": the motion does not cover any frame's readout (frames and motion on different clocks?)");
  return frames;
}

}  // namespace rsd::tools::extract
