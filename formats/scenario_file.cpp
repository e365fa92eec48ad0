#include "formats/scenario_file.hpp"

#include <filesystem>

#include "formats/intrinsics_file.hpp"
#include "formats/nominal_sections.hpp"
#include "formats/recording_v1.hpp"
#include "formats/yaml_map.hpp"

namespace rsd::formats {


namespace {

void read_gyro(YamlMap m, dsp::GyroSampling& g) {
  if (m.has("rate_hz")) {
    const auto r = m.numbers("rate_hz", 2);
    g.rate_min_hz = r[0], g.rate_max_hz = r[1];
  }
  g.gap_probability = m.number("gap_probability", 0.0);
  g.repeat_probability = m.number("repeat_probability", 0.0);
  g.jitter_s = m.number("jitter_s", 0.0);
  g.noise_rad_s = m.number("noise_rad_s", 0.0);
  m.finish();
}

void read_motion_source(YamlMap& m, dsp::SimConfig& s, const std::string& scenario_file) {
  const std::string kind = m.text("kind", "smooth");
  if (kind == "smooth") {
    s.motion_source = dsp::MotionSource::Smooth;
  } else if (kind == "constant") {
    s.motion_source = dsp::MotionSource::Constant;
    const auto v = m.numbers("velocity_m_s", 3), w = m.numbers("angular_rate_rad_s", 3);
    s.constant_velocity = Eigen::Vector3d(v[0], v[1], v[2]);
    s.constant_angular_rate = Eigen::Vector3d(w[0], w[1], w[2]);
  } else if (kind == "file") {
    s.motion_source = dsp::MotionSource::Samples;
    const std::string file = m.text("file", "");
    if (file.empty()) m.fail("file", "is missing (a t,x,y,z,qw,qx,qy,qz pose file)");
    const std::filesystem::path p = std::filesystem::path(scenario_file).parent_path() / file;
    s.pose_samples = read_trajectory_csv(p.string());
  } else {
    m.fail("kind", "must be smooth, constant or file");
  }
}

void read_motion(YamlMap m, dsp::SimConfig& s, const std::string& scenario_file) {
  read_motion_source(m, s, scenario_file);
  s.translation_amplitude_m = m.number("translation_amplitude_m", s.translation_amplitude_m);
  s.rotation_amplitude_rad = m.number("rotation_amplitude_rad", s.rotation_amplitude_rad);
  s.motion_frequency_hz = m.number("frequency_hz", s.motion_frequency_hz);
  s.trajectory_rate_hz = m.number("trajectory_rate_hz", s.trajectory_rate_hz);
  if (m.has("imu_to_camera")) {
    const auto R = m.numbers("imu_to_camera", 9);
    s.nominal.imu_to_camera = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>(R.data());
    if ((s.nominal.imu_to_camera * s.nominal.imu_to_camera.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-6)
      m.fail("imu_to_camera", "must be a rotation matrix (row-major)");
  }
  if (m.has("lever_arm_m")) {
    const auto l = m.numbers("lever_arm_m", 3);
    s.nominal.lever_arm = Eigen::Vector3d(l[0], l[1], l[2]);
  }
  if (m.has("gyro")) read_gyro(m.map("gyro"), s.gyro);
  m.finish();
}

void read_target(YamlMap m, dsp::SimConfig& s, dsp::TargetSpec& t) {
  const std::string kind = m.text("kind", "checkerboard");
  if (kind == "checkerboard") t.kind = dsp::TargetKind::Checkerboard;
  else if (kind == "aprilgrid") t.kind = dsp::TargetKind::AprilGrid;
  else if (kind == "points") t.kind = dsp::TargetKind::Points;
  else m.fail("kind", "must be checkerboard, aprilgrid or points");
  t.rows = m.integer("rows", t.rows);
  t.cols = m.integer("cols", t.cols);
  t.spacing_m = m.number("spacing_m", t.spacing_m);
  t.tag_spacing = m.number("tag_spacing", t.tag_spacing);
  t.count = m.integer("count", t.count);
  t.extent_m = m.number("extent_m", t.extent_m);
  if (m.has("depth_m")) {
    const auto d = m.numbers("depth_m", 2);
    t.depth_min_m = d[0], t.depth_max_m = d[1];
  }
  s.target_distance_m = m.number("distance_m", s.target_distance_m);
  if (t.rows < 1 || t.cols < 1) m.fail("rows", "and cols must be at least 1");
  if (!(t.spacing_m > 0)) m.fail("spacing_m", "must be positive");
  if (t.count < 1) m.fail("count", "must be at least 1");
  if (!(s.target_distance_m > 0)) m.fail("distance_m", "must be positive");
  m.finish();
}

void read_observations(YamlMap m, dsp::SimConfig& s) {
  const std::string kind = m.text("kind", "landmarks");
  if (kind == "landmarks") s.kind = dsp::ObservationKind::Landmarks;
  else if (kind == "matches") s.kind = dsp::ObservationKind::Matches;
  else m.fail("kind", "must be landmarks or matches");
  s.noise_px = m.number("noise_px", s.noise_px);
  s.outlier_fraction = m.number("outlier_fraction", s.outlier_fraction);
  s.matches_per_pair = m.integer("matches_per_pair", s.matches_per_pair);
  m.finish();
}

void read_unmodelled(YamlMap m, dsp::Unmodelled& u) {
  u.scene_depth_m = m.number("scene_depth_m", u.scene_depth_m);
  u.scene_fixed_in_world = m.boolean("scene_fixed_in_world", u.scene_fixed_in_world);
  u.gyro_saturation_rad_s = m.number("gyro_saturation_rad_s", u.gyro_saturation_rad_s);
  u.clock_jump_s = m.number("clock_jump_s", u.clock_jump_s);
  u.clock_jump_at_s = m.number("clock_jump_at_s", u.clock_jump_at_s);
  m.finish();
}

Eigen::Vector3d vec3(YamlMap m, const char* a, const char* b, const char* c) {
  Eigen::Vector3d v(m.number(a), m.number(b), m.number(c));
  m.finish();
  return v;
}

// lens_model: the true lens is of the other family than the nominal one (a fisheye modelled as a
// pinhole, or the reverse): its model and its terms (pinhole-equi k1..k4, pinhole-radtan k1, k2).
dsp::Distortion read_lens_model_effect(YamlMap& m, const dsp::NominalModel& n) {
  const std::string name = m.text("model", "");
  const auto model = dsp::parse_lens_model(name);
  if (!model) m.fail("model", "is '" + name + "': the lens models are pinhole-radtan and pinhole-equi");
  if (*model == n.cam.dist.model)
    m.fail("model", "is the nominal lens's own family: a change of its terms is lens_distortion");
  if (*model == dsp::LensModel::PinholeEqui)
    return dsp::Distortion::equidistant(m.number("k1", 0.0), m.number("k2", 0.0), m.number("k3", 0.0), m.number("k4", 0.0));
  return dsp::Distortion{m.number("k1", 0.0), m.number("k2", 0.0), 0, 0, 0};
}

void read_effect(YamlMap& effects, const std::string& name, const dsp::NominalModel& n, dsp::Effects& e) {
  YamlMap m = effects.map(name);
  if (name == "rolling_shutter") {
    if (m.has("frame_readout_s")) e.line_delay_s = m.number("frame_readout_s") / n.cam.height;
    else e.line_delay_s = m.number("line_delay_s");
  } else if (name == "readout_direction") {
    dsp::Readout r;
    if (!dsp::parse_readout(m.text("direction", ""), r)) m.fail("direction", "must be top_to_bottom or bottom_to_top");
    if (r == n.time.readout) m.fail("direction", "equals the nominal readout: no effect");
    e.flip_readout = true;
  } else if (name == "time_offset") {
    e.time_offset_s = m.number("time_offset_s");
  } else if (name == "clock_drift") {
    e.drift_ppm = m.number("drift_ppm");
  } else if (name == "lens_distortion") {
    // The nominal lens's own terms: k1, k2, and for a pinhole-equi lens k3, k4 too.
    e.k1k2 = Eigen::Vector2d(m.number("k1"), m.number("k2", 0.0));
    if (n.cam.dist.model == dsp::LensModel::PinholeEqui) {
      if (m.has("k3") || m.has("k4")) e.k3k4 = Eigen::Vector2d(m.number("k3", 0.0), m.number("k4", 0.0));
    }
  } else if (name == "lens_model") {
    e.lens = read_lens_model_effect(m, n);
  } else if (name == "focal_length") {
    e.fxfy = Eigen::Vector2d(m.number("fx"), m.number("fy"));
  } else if (name == "gyro_bias") {
    e.gyro_bias = vec3(m, "bx", "by", "bz");
    return;
  } else if (name == "lever_arm") {
    e.lever_arm = vec3(m, "x", "y", "z");
    return;
  } else if (name == "mount_rotation") {
    e.mount_rotation = vec3(m, "rx", "ry", "rz");
    return;
  } else if (name == "gyro_scale") {
    e.gyro_scale = vec3(m, "sx", "sy", "sz");
    return;
  } else if (name == "principal_point") {
    e.principal_point = Eigen::Vector2d(m.number("cx"), m.number("cy"));
  } else {
    effects.fail(name, "is not an effect of recording-v1 (rolling_shutter, readout_direction, time_offset, "
                       "clock_drift, lens_distortion, lens_model, focal_length, gyro_bias, lever_arm, mount_rotation, "
                       "gyro_scale, principal_point)");
  }
  m.finish();
}

}  // namespace

Scenario load_scenario(const std::string& file) {
  YamlMap root = YamlMap::load(file);
  Scenario s;
  s.file = file;
  dsp::SimConfig& c = s.sim;
  c.seed = static_cast<unsigned>(root.integer("seed", 1));
  c.duration_s = root.number("duration_s", c.duration_s);
  c.start_time_s = root.number("start_time_s", c.start_time_s);
  if (root.has("camera")) c.nominal.cam = read_camera_section(root.map("camera"), c.nominal.cam);
  if (root.has("timing")) read_timing_section(root.map("timing"), c.nominal);
  if (root.has("motion")) read_motion(root.map("motion"), c, file);
  s.target_spec.seed = c.seed;
  if (root.has("target")) read_target(root.map("target"), c, s.target_spec);
  if (root.has("observations")) read_observations(root.map("observations"), c);
  if (root.has("effects")) {
    YamlMap effects = root.map("effects");
    for (const auto& name : effects.keys()) read_effect(effects, name, c.nominal, c.effects);
    if (c.effects.lens && (c.effects.k1k2 || c.effects.k3k4))
      effects.fail("lens_model", "and lens_distortion together: lens_model gives every term of the true lens");
    effects.finish();
  }
  if (root.has("unmodelled")) read_unmodelled(root.map("unmodelled"), c.unmodelled);
  root.finish();
  if (c.kind == dsp::ObservationKind::Landmarks) {
    try {
      s.target = dsp::make_target(s.target_spec);
    } catch (const std::exception& e) {
      throw ConfigError(file + ": target: " + e.what());
    }
    c.points = s.target.landmarks;
  }
  return s;
}

}  // namespace rsd::formats
