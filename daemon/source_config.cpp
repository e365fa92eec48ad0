#include "daemon/source_config.hpp"

#include <cmath>
#include <filesystem>

#include "formats/intrinsics_file.hpp"

namespace rsd::daemon {

using formats::YamlMap;

namespace {

Eigen::Vector3d vec3(formats::YamlMap& m, const std::string& key, const Eigen::Vector3d& fallback) {
  if (!m.has(key)) return fallback;
  const auto v = m.numbers(key, 3);
  return {v[0], v[1], v[2]};
}

double positive(formats::YamlMap& m, const std::string& key, double fallback) {
  const double v = m.number(key, fallback);
  if (!(v > 0)) m.fail(key, "must be positive");
  return v;
}

dsp::Readout readout(formats::YamlMap& m, dsp::Readout fallback) {
  dsp::Readout r = fallback;
  if (m.has("readout") && !dsp::parse_readout(m.text("readout", ""), r))
    m.fail("readout", "must be top_to_bottom or bottom_to_top");
  return r;
}

void read_sim(formats::YamlMap m, drivers::SimSourceConfig& s) {
  const int w = m.integer("width", s.camera.width), h = m.integer("height", s.camera.height);
  if (w < 16 || h < 16 || w > 8192 || h > 8192) m.fail("width", "and height must be 16..8192 pixels");
  const double hfov = m.number("hfov_deg", 60.0);
  if (!(hfov > 1 && hfov < 179)) m.fail("hfov_deg", "must be between 1 and 179 degrees");
  s.camera = dsp::CameraModel::from_hfov(w, h, hfov * M_PI / 180.0);
  s.fps = positive(m, "fps", s.fps);
  s.line_delay_s = m.number("line_delay_s", s.line_delay_s);
  if (s.line_delay_s < 0 || s.line_delay_s * h > 1.0 / s.fps) m.fail("line_delay_s", "must be >= 0 and line_delay_s x height <= 1/fps");
  s.readout = readout(m, s.readout);
  s.exposure_s = m.number("exposure_s", s.exposure_s);
  const std::string fmt = m.text("format", "mono8");
  if (fmt == "mono8") s.format = dsp::PixelFormat::Mono8;
  else if (fmt == "rgb8") s.format = dsp::PixelFormat::Rgb8;
  else m.fail("format", "must be mono8 or rgb8");
  s.angular_rate = vec3(m, "angular_rate_rad_s", s.angular_rate);
  s.velocity = vec3(m, "velocity_m_s", s.velocity);
  s.wobble_rad_s = m.number("wobble_rad_s", s.wobble_rad_s);
  s.scene_depth_m = positive(m, "scene_depth_m", s.scene_depth_m);
  s.velocity_rate_hz = positive(m, "velocity_rate_hz", s.velocity_rate_hz);
  s.velocity_noise = m.number("velocity_noise", s.velocity_noise);
  s.velocity_latency_s = m.number("velocity_latency_s", s.velocity_latency_s);
  s.gyro_bias = vec3(m, "gyro_bias_rad_s", s.gyro_bias);
  s.publish_velocity = m.boolean("publish_velocity", true);
  s.realtime = m.boolean("realtime", true);
  s.noise_grey = m.number("noise_grey", s.noise_grey);
  m.finish();
}

void read_aravis(formats::YamlMap m, drivers::AravisConfig& a) {
  a.camera = m.text("camera", a.camera);
  a.pixel_format = m.text("pixel_format", a.pixel_format);
  a.width = m.integer("width", a.width);
  a.height = m.integer("height", a.height);
  a.frame_rate_hz = m.number("frame_rate_hz", a.frame_rate_hz);
  a.exposure_s = m.number("exposure_s", a.exposure_s);
  a.buffers = m.integer("buffers", a.buffers);
  a.line_delay_s = m.number("line_delay_s", a.line_delay_s);
  a.readout = readout(m, a.readout);
  const std::string stamp = m.text("stamp", "exposure_start");
  if (stamp == "exposure_start") a.stamp = drivers::CameraStamp::ExposureStart;
  else if (stamp == "exposure_end") a.stamp = drivers::CameraStamp::ExposureEnd;
  else m.fail("stamp", "must be exposure_start or exposure_end");
  a.leader_delay_s = m.number("leader_delay_s", a.leader_delay_s);
  a.use_camera_clock = m.boolean("use_camera_clock", a.use_camera_clock);
  m.finish();
}

void read_v4l2(formats::YamlMap m, drivers::V4l2Config& v) {
  v.device = m.text("device", v.device);
  v.width = m.integer("width", v.width);
  v.height = m.integer("height", v.height);
  v.pixel_format = m.text("pixel_format", v.pixel_format);
  v.fps = positive(m, "fps", v.fps);
  v.buffers = static_cast<unsigned>(m.integer("buffers", static_cast<int>(v.buffers)));
  v.line_delay_s = m.number("line_delay_s", v.line_delay_s);
  v.readout = readout(m, v.readout);
  v.exposure_s = m.number("exposure_s", v.exposure_s);
  m.finish();
}

void read_libcamera(formats::YamlMap m, drivers::LibcameraConfig& l) {
  l.camera_id = m.text("camera_id", l.camera_id);
  l.width = m.integer("width", l.width);
  l.height = m.integer("height", l.height);
  const std::string fmt = m.text("format", "mono8");
  if (fmt == "mono8") l.format = dsp::PixelFormat::Mono8;
  else if (fmt == "rgb8") l.format = dsp::PixelFormat::Rgb8;
  else m.fail("format", "must be mono8 or rgb8");
  l.role = m.text("role", l.role);
  l.fps = positive(m, "fps", l.fps);
  l.line_delay_s = m.number("line_delay_s", l.line_delay_s);
  l.readout = readout(m, l.readout);
  l.exposure_s = m.number("exposure_s", l.exposure_s);
  m.finish();
}

void read_replay(formats::YamlMap m, drivers::ReplayConfig& r) {
  std::filesystem::path file = m.text("file", r.file);
  if (!file.empty() && file.is_relative()) file = std::filesystem::path(m.file()).parent_path() / file;
  r.file = file.string();
  if (m.has("speed") && !drivers::parse_speed(m.text("speed", ""), r.speed))
    m.fail("speed", "must be a positive factor (1: real time) or fast");
  r.loop = m.boolean("loop", r.loop);
  r.channel = m.text("channel", r.channel);
  r.velocity_channel = m.text("velocity_channel", r.velocity_channel);
  m.finish();
}

void read_lcm_source(formats::YamlMap m, drivers::LcmSourceConfig& l) {
  l.url = m.text("url", l.url);
  l.allow_multicast = m.boolean("allow_multicast", l.allow_multicast);
  if (l.url.rfind("udpm://", 0) == 0 && !l.allow_multicast)
    m.fail("url", "is multicast; set allow_multicast: true to use it (this keeps tests off the network)");
  l.channel = m.text("channel", l.channel);
  l.velocity_channel = m.text("velocity_channel", l.velocity_channel);
  l.open_timeout_s = positive(m, "open_timeout_s", l.open_timeout_s);
  l.fallback_fps = positive(m, "fps", l.fallback_fps);
  m.finish();
}

// Intrinsics (and a rolling-shutter line delay, if Kalibr estimated one) from a Kalibr
// camchain or ROS camera_info file, relative paths taken from the configuration's directory.
void read_intrinsics_file(formats::YamlMap& m, SourceConfig& s) {
  std::filesystem::path file = m.text("intrinsics_file", "");
  if (file.is_relative()) file = std::filesystem::path(m.file()).parent_path() / file;
  const formats::Intrinsics in = formats::load_intrinsics(file.string(), m.text("intrinsics_camera", ""));
  s.camera = in.cam;
  if (in.line_delay_s) {  // a calibrated line delay beats "the readout fills the frame"
    if (s.aravis.line_delay_s == 0) s.aravis.line_delay_s = *in.line_delay_s;
    if (s.v4l2.line_delay_s == 0) s.v4l2.line_delay_s = *in.line_delay_s;
    if (s.libcamera.line_delay_s == 0) s.libcamera.line_delay_s = *in.line_delay_s;
  }
}

}  // namespace

void read_source(formats::YamlMap m, SourceConfig& s) {
  s.driver = m.text("driver", s.driver);
  if (s.driver != "sim" && s.driver != "aravis" && s.driver != "v4l2" && s.driver != "libcamera" &&
      s.driver != "replay" && s.driver != "lcm")
    m.fail("driver", "must be sim, aravis, v4l2, libcamera, replay or lcm, not '" + s.driver + "'");
  if (m.has("sim")) read_sim(m.map("sim"), s.sim);
  if (m.has("aravis")) read_aravis(m.map("aravis"), s.aravis);
  if (m.has("v4l2")) read_v4l2(m.map("v4l2"), s.v4l2);
  if (m.has("libcamera")) read_libcamera(m.map("libcamera"), s.libcamera);
  if (m.has("replay")) read_replay(m.map("replay"), s.replay);
  if (s.driver == "replay" && s.replay.file.empty()) m.fail("driver", "'replay' needs replay.file: the LCM log to play");
  if (m.has("lcm")) read_lcm_source(m.map("lcm"), s.lcm);
  if (m.has("camera")) {
    dsp::CameraModel none;  // no defaults for a real camera: size and focal length are required
    none.width = none.height = 0;
    none.fx = none.fy = 0;
    s.camera = formats::read_camera_section(m.map("camera"), none);
  }
  if (m.has("intrinsics_file")) {
    if (s.camera) m.fail("intrinsics_file", "and source.camera both give intrinsics: keep one");
    read_intrinsics_file(m, s);
  }
  // Replayed and received frames may carry their intrinsics (rsd --record writes them).
  if (s.driver != "sim" && s.driver != "replay" && s.driver != "lcm" && !s.camera)
    m.fail("driver", "'" + s.driver + "' needs the camera's intrinsics: add source.camera {width, height, fx, fy, cx, cy, distortion} or source.intrinsics_file (Kalibr camchain or ROS camera_info)");
  m.finish();
}

std::unique_ptr<drivers::CameraSource> make_source(const SourceConfig& s) {
  if (s.driver == "aravis") return std::make_unique<drivers::AravisSource>(s.aravis);
  if (s.driver == "v4l2") return std::make_unique<drivers::V4l2Source>(s.v4l2);
  if (s.driver == "libcamera") return std::make_unique<drivers::LibcameraSource>(s.libcamera);
  if (s.driver == "replay") return std::make_unique<drivers::ReplaySource>(s.replay);
  if (s.driver == "lcm") return std::make_unique<drivers::LcmSource>(s.lcm);
  return std::make_unique<drivers::SimSource>(s.sim);
}

dsp::CameraModel camera_model(const SourceConfig& s, const drivers::FrameFormat& f,
                              const std::optional<dsp::CameraModel>& recorded) {
  if (s.driver == "sim") return s.sim.camera;
  if (!s.camera && !recorded)
    throw std::runtime_error("source '" + s.driver + "': the frames carry no intrinsics (only rsd --record writes them): "
                             "add source.camera or source.intrinsics_file");
  const dsp::CameraModel& c = s.camera ? *s.camera : *recorded;
  if (c.width != f.width || c.height != f.height)
    throw std::runtime_error("source.camera is " + std::to_string(c.width) + "x" + std::to_string(c.height) +
                             " but the camera delivers " + std::to_string(f.width) + "x" + std::to_string(f.height));
  return c;
}

}  // namespace rsd::daemon
