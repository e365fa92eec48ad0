#include "daemon/config.hpp"

#include <cmath>

#include "drivers/yaml_map.hpp"

namespace rsd::daemon {

using drivers::YamlMap;

namespace {

Eigen::Vector3d vec3(YamlMap& m, const std::string& key, const Eigen::Vector3d& fallback) {
  if (!m.has(key)) return fallback;
  const auto v = m.numbers(key, 3);
  return {v[0], v[1], v[2]};
}

double positive(YamlMap& m, const std::string& key, double fallback) {
  const double v = m.number(key, fallback);
  if (!(v > 0)) m.fail(key, "must be positive");
  return v;
}

void read_sim(YamlMap m, drivers::SimSourceConfig& s) {
  const int w = m.integer("width", s.camera.width), h = m.integer("height", s.camera.height);
  if (w < 16 || h < 16 || w > 8192 || h > 8192) m.fail("width", "and height must be 16..8192 pixels");
  const double hfov = m.number("hfov_deg", 60.0);
  if (!(hfov > 1 && hfov < 179)) m.fail("hfov_deg", "must be between 1 and 179 degrees");
  s.camera = dsp::CameraModel::from_hfov(w, h, hfov * M_PI / 180.0);
  s.fps = positive(m, "fps", s.fps);
  s.line_delay_s = m.number("line_delay_s", s.line_delay_s);
  if (s.line_delay_s < 0 || s.line_delay_s * h > 1.0 / s.fps) m.fail("line_delay_s", "must be >= 0 and line_delay_s x height <= 1/fps");
  if (!dsp::parse_readout(m.text("readout", "top_to_bottom"), s.readout)) m.fail("readout", "must be top_to_bottom or bottom_to_top");
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

void read_source(YamlMap m, Config& c) {
  c.driver = m.text("driver", c.driver);
  if (c.driver != "sim") m.fail("driver", "'" + c.driver + "' is not available yet (sim)");
  if (m.has("sim")) read_sim(m.map("sim"), c.sim);
  m.finish();
}

void read_pipeline(YamlMap m, PipelineConfig& p) {
  p.raw_slots = static_cast<size_t>(m.integer("raw_slots", static_cast<int>(p.raw_slots)));
  p.out_slots = static_cast<size_t>(m.integer("out_slots", static_cast<int>(p.out_slots)));
  p.queue_depth = static_cast<size_t>(m.integer("queue_depth", static_cast<int>(p.queue_depth)));
  if (p.queue_depth < 1 || p.queue_depth > 64) m.fail("queue_depth", "must be 1..64");
  if (p.raw_slots < p.queue_depth + 2) m.fail("raw_slots", "must be at least queue_depth + 2");
  if (p.out_slots < p.queue_depth + 2) m.fail("out_slots", "must be at least queue_depth + 2");
  p.publish_raw = m.boolean("publish_raw", false);
  m.finish();
}

void read_rectification(YamlMap m, RectifyConfig& r) {
  r.enabled = m.boolean("enabled", true);
  const std::string ref = m.text("reference", "middle_row");
  if (ref == "middle_row") r.reference = dsp::ReferenceRow::Middle;
  else if (ref == "first_row") r.reference = dsp::ReferenceRow::First;
  else m.fail("reference", "must be middle_row or first_row");
  const std::string depth = m.text("depth", "infinite");
  if (depth == "infinite") r.depth = DepthKind::Infinite;
  else if (depth == "plane") r.depth = DepthKind::Plane;
  else if (depth == "ground") r.depth = DepthKind::Ground;
  else m.fail("depth", "must be infinite, plane or ground");
  r.depth_m = positive(m, "depth_m", r.depth_m);
  r.camera_height_m = positive(m, "camera_height_m", r.camera_height_m);
  r.grid_px = m.integer("grid_px", r.grid_px);
  if (r.grid_px < 2 || r.grid_px > 256) m.fail("grid_px", "must be 2..256");
  r.gyro_only = m.boolean("gyro_only", false);
  r.threshold_px = positive(m, "threshold_px", r.threshold_px);
  m.finish();
}

void read_velocity(YamlMap m, Config& c) {
  c.velocity_channel = m.text("channel", c.velocity_channel);
  c.velocity_limits.max_age_s = positive(m, "max_age_s", c.velocity_limits.max_age_s);
  c.velocity_limits.max_angular_rad_s = positive(m, "max_angular_rad_s", c.velocity_limits.max_angular_rad_s);
  c.velocity_limits.max_linear_m_s = positive(m, "max_linear_m_s", c.velocity_limits.max_linear_m_s);
  m.finish();
}

void read_lcm(YamlMap m, Config& c) {
  c.lcm_url = m.text("url", c.lcm_url);
  if (c.lcm_url.rfind("udpm://", 0) == 0 && !m.boolean("allow_multicast", false))
    m.fail("url", "is multicast; set allow_multicast: true to use it (this keeps tests off the network)");
  c.channels.image = m.text("image_channel", c.channels.image);
  c.channels.raw = m.text("raw_channel", c.channels.raw);
  c.channels.info = m.text("info_channel", c.channels.info);
  c.channels.health = m.text("health_channel", c.channels.health);
  m.finish();
}

}  // namespace

Config load_config(const std::string& file) {
  Config c;
  YamlMap root = YamlMap::load(file);
  if (root.has("source")) read_source(root.map("source"), c);
  if (root.has("pipeline")) read_pipeline(root.map("pipeline"), c.pipeline);
  if (root.has("rectification")) read_rectification(root.map("rectification"), c.rectify);
  if (root.has("velocity")) read_velocity(root.map("velocity"), c);
  if (root.has("lcm")) read_lcm(root.map("lcm"), c);
  root.finish();
  return c;
}

std::string default_config_yaml() {
  return R"(# rsd configuration (every key shown with its default).
source:
  driver: sim                  # sim (aravis, v4l2, libcamera, replay: coming)
  sim:                         # the built-in simulated rolling-shutter camera
    width: 640
    height: 480
    hfov_deg: 60
    fps: 30
    line_delay_s: 0            # 0: rows read over the whole frame period
    readout: top_to_bottom     # or bottom_to_top
    exposure_s: 0.002
    format: mono8              # or rgb8
    angular_rate_rad_s: [0, 0.3, 0.8]   # the camera's own motion, camera axes
    velocity_m_s: [0.5, 0, 0]
    wobble_rad_s: 0.5
    scene_depth_m: 3           # a textured wall this far ahead
    velocity_rate_hz: 200      # the simulated IMU, published on velocity.channel
    velocity_noise: 0
    velocity_latency_s: 0
    gyro_bias_rad_s: [0, 0, 0]
    publish_velocity: true
    realtime: true
    noise_grey: 1
pipeline:
  raw_slots: 6                 # frame buffers allocated at start
  out_slots: 4
  queue_depth: 2               # frames waiting between stages before the oldest is dropped
  publish_raw: false
rectification:
  enabled: true
  reference: middle_row        # or first_row: the instant the output is a global shutter at
  depth: infinite              # infinite (rotation only), plane (depth_m), ground (camera_height_m)
  depth_m: 5
  camera_height_m: 1.5
  grid_px: 16                  # the exact map is evaluated every grid_px pixels, then interpolated
  gyro_only: false
  threshold_px: 1              # pinhole model deemed sufficient below this correction
velocity:
  channel: RSD_VELOCITY        # rsd.velocity_t
  max_age_s: 0.1               # no sample this close to the frame: publish unrectified
  max_angular_rad_s: 20        # samples beyond these limits are rejected as faults
  max_linear_m_s: 100
lcm:
  url: memq://                 # or file:///abs/path.lcmlog?mode=w ; multicast needs allow_multicast: true
  image_channel: RSD_RECT
  raw_channel: RSD_RAW
  info_channel: RSD_FRAME_INFO
  health_channel: RSD_HEALTH
)";
}

}  // namespace rsd::daemon
