#include "daemon/config.hpp"

#include <cmath>

#include "formats/yaml_map.hpp"

namespace rsd::daemon {

using formats::YamlMap;

namespace {

double positive(formats::YamlMap& m, const std::string& key, double fallback) {
  const double v = m.number(key, fallback);
  if (!(v > 0)) m.fail(key, "must be positive");
  return v;
}

// A row-major 3x3 rotation (nine numbers), checked orthonormal with determinant +1.
Eigen::Matrix3d rotation(formats::YamlMap& m, const std::string& key, const Eigen::Matrix3d& fallback) {
  if (!m.has(key)) return fallback;
  const auto v = m.numbers(key, 9);
  Eigen::Matrix3d r;
  for (int i = 0; i < 9; ++i) r(i / 3, i % 3) = v[static_cast<size_t>(i)];
  if (!is_rotation(r, 1e-6)) m.fail(key, "must be a rotation matrix (row-major, orthonormal, determinant +1)");
  return r;
}

void read_pipeline(formats::YamlMap m, PipelineConfig& p) {
  p.raw_slots = static_cast<size_t>(m.integer("raw_slots", static_cast<int>(p.raw_slots)));
  p.out_slots = static_cast<size_t>(m.integer("out_slots", static_cast<int>(p.out_slots)));
  p.queue_depth = static_cast<size_t>(m.integer("queue_depth", static_cast<int>(p.queue_depth)));
  if (p.queue_depth < 1 || p.queue_depth > 64) m.fail("queue_depth", "must be 1..64");
  if (p.raw_slots < p.queue_depth + 2) m.fail("raw_slots", "must be at least queue_depth + 2");
  if (p.out_slots < p.queue_depth + 2) m.fail("out_slots", "must be at least queue_depth + 2");
  p.publish_raw = m.boolean("publish_raw", false);
  m.finish();
}

void read_rectification(formats::YamlMap m, RectifyConfig& r) {
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
  if (r.grid_px < 4 || r.grid_px > 256) m.fail("grid_px", "must be 4..256");
  r.gyro_only = m.boolean("gyro_only", false);
  r.threshold_px = positive(m, "threshold_px", r.threshold_px);
  m.finish();
}

void read_velocity(formats::YamlMap m, Config& c) {
  c.velocity_channel = m.text("channel", c.velocity_channel);
  c.velocity_limits.max_age_s = positive(m, "max_age_s", c.velocity_limits.max_age_s);
  c.velocity_limits.max_angular_rad_s = positive(m, "max_angular_rad_s", c.velocity_limits.max_angular_rad_s);
  c.velocity_limits.max_linear_m_s = positive(m, "max_linear_m_s", c.velocity_limits.max_linear_m_s);
  VelocityInputConfig& in = c.velocity_input;
  in.pose_channel = m.text("pose_channel", in.pose_channel);
  if (!in.pose_channel.empty() && in.pose_channel == c.velocity_channel) m.fail("pose_channel", "must differ from velocity.channel");
  in.imu_to_camera = rotation(m, "imu_to_camera", in.imu_to_camera);
  in.body_to_camera = rotation(m, "body_to_camera", in.body_to_camera);
  in.gyro_only = m.boolean("gyro_only", in.gyro_only);
  m.finish();
}

void read_lcm(formats::YamlMap m, Config& c) {
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
  formats::YamlMap root = formats::YamlMap::load(file);
  if (root.has("source")) read_source(root.map("source"), c.source);
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
  driver: sim                  # sim, aravis, v4l2, libcamera, replay (a recorded log) or lcm (frames over LCM)
  # camera: {width: 1280, height: 720, fx: 900, fy: 900, cx: 639.5, cy: 359.5, distortion: [0, 0, 0, 0]}
  # intrinsics_file: camchain.yaml   # or a Kalibr camchain / ROS camera_info file (intrinsics_camera: cam0)
  # The intrinsics of a real camera are required (camera or intrinsics_file).
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
  aravis:                      # GigE Vision, opened by address (never by discovery), or Fake_1
    camera: 127.0.0.1
    pixel_format: Mono8        # Mono8, Mono16, RGB8
    width: 0                   # 0: keep the camera's
    height: 0
    frame_rate_hz: 0
    exposure_s: 0
    buffers: 8
    line_delay_s: 0            # 0: the readout fills the frame period
    readout: top_to_bottom
    stamp: exposure_start      # what the camera's timestamp marks: exposure_start or exposure_end
    leader_delay_s: 0
    use_camera_clock: true
  v4l2:
    device: /dev/video0
    width: 640
    height: 480
    pixel_format: GREY         # GREY, Y16, YUYV, RGB24
    fps: 30
    buffers: 4
    line_delay_s: 0
    readout: top_to_bottom
    exposure_s: 0              # 0: ask the driver
  libcamera:
    camera_id: ""              # "": the first camera
    width: 640
    height: 480
    format: mono8
    role: auto
    fps: 30
    line_delay_s: 0
    readout: top_to_bottom
    exposure_s: 0
  replay:                      # a log from rsd --record, rsd-sim or lcm-logger (docs/replay.md)
    file: ""                   # relative to this file; or rsd --replay LOG
    speed: 1                   # 1: real time, N: N times faster, fast: no waiting and no drops
    loop: false
    channel: RSD_RAW           # bot_core.image_t raw frames with their row timing
    velocity_channel: RSD_VELOCITY
  lcm:                         # frames published by rsd-replay, lcm-logplayer or a camera node
    url: tcpq://127.0.0.1:7700 # LCM's TCP queue (server: java -cp lcm.jar lcm.lcm.TCPService 7700)
    allow_multicast: false
    channel: RSD_RAW
    velocity_channel: RSD_VELOCITY
    open_timeout_s: 2          # wait this long for the first frame, then retry with backoff
    fps: 30                    # frame rate when the frames do not carry their timing
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
  grid_px: 32                  # first node spacing of the map; it refines itself until within 0.05 px
  gyro_only: false
  threshold_px: 1              # pinhole model deemed sufficient below this correction
velocity:
  channel: RSD_VELOCITY        # rsd.velocity_t
  max_age_s: 0.1               # no sample this close to the frame: publish unrectified
  max_angular_rad_s: 20        # samples beyond these limits are rejected as faults
  max_linear_m_s: 100
  pose_channel: ""             # also read bot_core.pose_t here (rotation_rate, vel: body frame); "": off
  imu_to_camera: [1, 0, 0, 0, 1, 0, 0, 0, 1]   # rsd.velocity_t FRAME_IMU: w_camera = R w_imu (row-major)
  body_to_camera: [1, 0, 0, 0, 1, 0, 0, 0, 1]  # bot_core.pose_t: w_camera = R w_body (row-major)
  gyro_only: false             # drop linear velocity at input (every sample has_linear: false)
lcm:
  url: memq://                 # or file:///abs/path.lcmlog?mode=w ; multicast needs allow_multicast: true
  image_channel: RSD_RECT
  raw_channel: RSD_RAW
  info_channel: RSD_FRAME_INFO
  health_channel: RSD_HEALTH
)";
}

}  // namespace rsd::daemon
