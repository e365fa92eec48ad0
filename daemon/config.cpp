#include "daemon/config.hpp"
#include "daemon/worker_pool.hpp"

#include <sched.h>

#include <algorithm>
#include <cmath>

#include "daemon/log.hpp"
#include "dsp/geometry/rotation_check.hpp"
#include "drivers/driver_registry.hpp"
#include "formats/config_section.hpp"
#include "formats/yaml_map.hpp"

namespace rsd::daemon {

using formats::YamlMap;

namespace {

void visit_pipeline(formats::ConfigSection& c, PipelineConfig& p) {
  auto count = [&](const char* key, size_t& v, const char* comment) {
    int i = static_cast<int>(v);
    c.value(key, i, comment);
    v = static_cast<size_t>(std::max(i, 0));
  };
  count("raw_slots", p.raw_slots, "frame buffers allocated at start");
  count("out_slots", p.out_slots, nullptr);
  count("queue_depth", p.queue_depth, "frames waiting between stages before the oldest is dropped");
  c.check(p.queue_depth >= 1 && p.queue_depth <= 64, "queue_depth", "must be 1..64");
  c.check(p.raw_slots >= p.queue_depth + 2, "raw_slots", "must be at least queue_depth + 2");
  c.check(p.out_slots >= p.queue_depth + 2, "out_slots", "must be at least queue_depth + 2");
  c.check(p.raw_slots <= 64, "raw_slots", "must be at most 64 (each is a frame buffer allocated at start)");
  c.check(p.out_slots <= 64, "out_slots", "must be at most 64 (each is a frame buffer allocated at start)");
  c.value("publish_raw", p.publish_raw);
}

void visit_rectification(formats::ConfigSection& c, RectifyConfig& r) {
  c.value("enabled", r.enabled);
  c.choice("output", r.output, {{"same_lens", RectifyOutput::SameLens}, {"pinhole", RectifyOutput::Pinhole}},
           "or pinhole: the lens undone too, at output_hfov_deg");
  c.value("output_hfov_deg", r.output_hfov_deg, "pinhole output: horizontal field of view (degrees), centred");
  c.check(std::isfinite(r.output_hfov_deg) && r.output_hfov_deg >= 1 && r.output_hfov_deg <= 170, "output_hfov_deg",
          "must be 1..170 degrees");
  c.choice("reference", r.reference, {{"middle_row", dsp::ReferenceRow::Middle}, {"first_row", dsp::ReferenceRow::First}},
           "or first_row: the instant the output is a global shutter at");
  c.choice("depth", r.depth, {{"infinite", DepthKind::Infinite}, {"plane", DepthKind::Plane}, {"ground", DepthKind::Ground}},
           "infinite (rotation only), plane (depth_m), ground (camera_height_m)");
  c.value("depth_m", r.depth_m);
  c.check(r.depth_m > 0, "depth_m", "must be positive");
  c.value("camera_height_m", r.camera_height_m);
  c.check(r.camera_height_m > 0, "camera_height_m", "must be positive");
  c.value("grid_px", r.grid_px, "first node spacing of the map; it refines itself until within 0.05 px");
  c.check(r.grid_px >= 4 && r.grid_px <= 256, "grid_px", "must be 4..256");
  c.value("gyro_only", r.gyro_only);
  c.value("threshold_px", r.threshold_px, "pinhole model deemed sufficient below this correction");
  c.check(r.threshold_px > 0, "threshold_px", "must be positive");
  c.value("imu_wait_ms", r.imu_wait_ms, "wait this long at most for IMU samples covering a frame's last row");
  c.check(std::isfinite(r.imu_wait_ms) && r.imu_wait_ms >= 0 && r.imu_wait_ms <= 1000, "imu_wait_ms", "must be 0..1000 ms");
  c.value("workers", r.workers, "threads that resample each frame together (the rectify thread included), created at start");
  c.check(r.workers >= 1 && r.workers <= WorkerPool::kMaxWorkers, "workers", "must be 1..64");
}

void visit_velocity(formats::ConfigSection& c, Config& cfg) {
  c.value("channel", cfg.velocity_channel, "rsd.velocity_t");
  VelocityLimits& l = cfg.velocity_limits;
  c.value("max_age_s", l.max_age_s, "no sample this close to the frame: publish unrectified");
  c.check(l.max_age_s > 0 && l.max_age_s <= 10, "max_age_s", "must be positive, at most 10 s");
  c.value("max_angular_rad_s", l.max_angular_rad_s, "samples beyond these limits are rejected as faults");
  c.check(l.max_angular_rad_s > 0 && l.max_angular_rad_s <= 1000, "max_angular_rad_s", "must be positive, at most 1000 rad/s");
  c.value("max_linear_m_s", l.max_linear_m_s);
  c.check(l.max_linear_m_s > 0 && l.max_linear_m_s <= 10000, "max_linear_m_s", "must be positive, at most 10000 m/s");
  VelocityInputConfig& in = cfg.velocity_input;
  c.value("pose_channel", in.pose_channel, "also read bot_core.pose_t here (rotation_rate, vel: body frame); \"\": off");
  c.check(in.pose_channel.empty() || in.pose_channel != cfg.velocity_channel, "pose_channel", "must differ from velocity.channel");
  c.value("imu_to_camera", in.imu_to_camera, "rsd.velocity_t FRAME_IMU: w_camera = R w_imu (row-major)");
  c.check(dsp::is_rotation(in.imu_to_camera), "imu_to_camera", "must be a rotation matrix (row-major, orthonormal, determinant +1)");
  c.value("body_to_camera", in.body_to_camera, "bot_core.pose_t: w_camera = R w_body (row-major)");
  c.check(dsp::is_rotation(in.body_to_camera), "body_to_camera", "must be a rotation matrix (row-major, orthonormal, determinant +1)");
  c.value("gyro_only", in.gyro_only, "drop linear velocity at input (every sample has_linear: false)");
  c.value("max_clock_offset_s", in.max_clock_offset_s,
          "with a live camera, refuse messages stamped further than this from the camera clock (0: no check)");
  c.check(in.max_clock_offset_s >= 0 && in.max_clock_offset_s <= 3600, "max_clock_offset_s", "must be 0..3600 s");
}

void visit_lcm(formats::ConfigSection& c, Config& cfg) {
  c.value("url", cfg.lcm_url, "or file:///abs/path.lcmlog?mode=w ; multicast needs allow_multicast: true");
  bool allow_multicast = false;
  if (c.has("allow_multicast")) c.value("allow_multicast", allow_multicast);
  c.check(cfg.lcm_url.rfind("udpm://", 0) != 0 || allow_multicast, "url",
          "is multicast; set allow_multicast: true to use it (this keeps tests off the network)");
  c.value("image_channel", cfg.channels.image);
  c.value("raw_channel", cfg.channels.raw);
  c.value("info_channel", cfg.channels.info);
  c.value("health_channel", cfg.channels.health);
}

void visit_realtime(formats::ConfigSection& c, RealtimeConfig& r) {
  c.value("enabled", r.enabled, "SCHED_FIFO capture and locked memory (rsd --realtime, as the service unit runs it)");
  c.value("capture_priority", r.capture_priority, "SCHED_FIFO priority of the capture thread");
  c.check(r.capture_priority >= 1 && r.capture_priority <= 99, "capture_priority", "must be 1..99");
  c.value("lock_memory", r.lock_memory, "mlockall once start-up has allocated the frame buffers");
  for (auto [key, cpu] : {std::pair{"capture_cpu", &r.capture_cpu}, {"rectify_cpu", &r.rectify_cpu}, {"publish_cpu", &r.publish_cpu}}) {
    c.value(key, *cpu, key == std::string("capture_cpu") ? "pin a pipeline thread to a CPU (-1: any), enabled or not" : nullptr);
    c.check(*cpu >= -1 && *cpu < CPU_SETSIZE, key, "must be -1 (any) or a CPU number");
  }
}

void visit_health(formats::ConfigSection& c, HealthConfig& h) {
  c.value("stall_after_s", h.stall_after_s, "no frame for this long: the source is stalled (0: five frame periods, at least 1 s)");
  c.check(std::isfinite(h.stall_after_s) && h.stall_after_s >= 0 && h.stall_after_s <= 3600, "stall_after_s", "must be 0..3600 s");
  c.value("low_fps_fraction", h.low_fps_fraction, "warn when a camera delivers below this fraction of its configured rate ...");
  c.check(h.low_fps_fraction >= 0 && h.low_fps_fraction <= 1, "low_fps_fraction", "must be 0..1 (0: never warn)");
  c.value("low_fps_after_s", h.low_fps_after_s, "... for this long");
  c.check(std::isfinite(h.low_fps_after_s) && h.low_fps_after_s >= 1 && h.low_fps_after_s <= 3600, "low_fps_after_s",
          "must be 1..3600 s");
}

void visit_log(formats::ConfigSection& c, std::string& level) {
  c.value("level", level, "trace, debug, info, warning, error, critical or off (rsd --log-level overrides)");
  c.check(parse_log_level(level).has_value(), "level", "must be trace, debug, info, warning, error, critical or off");
}

// The whole file, section by section: read or printed by the same visit.
void visit_config(formats::ConfigSection& c, Config& cfg) {
  c.section("source", [&](formats::ConfigSection& s) { visit_source(s, cfg.source); });
  c.section("pipeline", [&](formats::ConfigSection& s) { visit_pipeline(s, cfg.pipeline); });
  c.section("realtime", [&](formats::ConfigSection& s) { visit_realtime(s, cfg.pipeline.realtime); });
  c.section("rectification", [&](formats::ConfigSection& s) { visit_rectification(s, cfg.rectify); });
  c.section("velocity", [&](formats::ConfigSection& s) { visit_velocity(s, cfg); });
  c.section("lcm", [&](formats::ConfigSection& s) { visit_lcm(s, cfg); });
  c.section("health", [&](formats::ConfigSection& s) { visit_health(s, cfg.health); });
  c.section("calibration", [&](formats::ConfigSection& s) { visit_online_calibration(s, cfg.online); });
  c.section("log", [&](formats::ConfigSection& s) { visit_log(s, cfg.log_level); });
}

// The IMU part of a calibration: the velocity input's rotation, clock offset and drift, bias,
// scale and lever arm.
void use_imu_calibration(Config& c, const formats::Calibration& cal) {
  VelocityInputConfig& in = c.velocity_input;
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  if (in.imu_to_camera != I && cal.imu_to_camera != I && in.imu_to_camera != cal.imu_to_camera)
    throw formats::ConfigError(cal.file + ": the calibration's T_cam_imu and velocity.imu_to_camera both rotate the IMU: keep one");
  if (cal.imu_to_camera != I) in.imu_to_camera = cal.imu_to_camera;
  in.imu_time_offset_s = cal.timeshift_cam_imu_s;
  in.gyro_bias_rad_s = cal.gyro_bias_rad_s;
  in.gyro_scale = cal.gyro_scale;
  in.drift_ppm = cal.drift_ppm;
  in.lever_arm_m = cal.lever_arm_m;
  in.pose_calibrated = true;
  for (const drivers::Driver& d : drivers::all_drivers()) d.use_clock_offset(c.source.settings[d.name], cal.timeshift_cam_imu_s);
}

}  // namespace

Config load_config(const std::string& file) {
  Config c;
  formats::ConfigReader reader(formats::YamlMap::load(file));
  visit_config(reader, c);
  reader.finish();
  if (c.source.calibration) use_imu_calibration(c, *c.source.calibration);
  return c;
}

void use_calibration_file(Config& c, const std::string& file) { apply_calibration(c, formats::read_calibration(file)); }

void apply_calibration(Config& c, formats::Calibration cal) {
  // The command line's calibration replaces what the configuration says of the same things.
  c.source.camera.reset();
  c.source.camera_origin = "source.camera";
  if (cal.imu_to_camera != Eigen::Matrix3d::Identity()) c.velocity_input.imu_to_camera = Eigen::Matrix3d::Identity();
  use_imu_calibration(c, cal);
  use_calibration(c.source, std::move(cal));
}

std::string default_config_yaml() {
  Config defaults;
  formats::DefaultsPrinter printer;
  printer.note("rsd configuration (every key shown with its default).");
  visit_config(printer, defaults);
  return printer.text();
}

}  // namespace rsd::daemon
