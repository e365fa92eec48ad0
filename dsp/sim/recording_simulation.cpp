#include "dsp/sim/recording_simulation.hpp"

#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>
#include <utility>

#include "dsp/geometry/camera_motion.hpp"
#include "dsp/sim/random_draws.hpp"
#include "dsp/sim/smooth_motion.hpp"

namespace rsd::dsp {


bool Effects::any() const { return !names().empty(); }

std::vector<std::string> Effects::names() const {
  std::vector<std::string> n;
  if (line_delay_s) n.push_back("rolling_shutter");
  if (flip_readout) n.push_back("readout_direction");
  if (time_offset_s) n.push_back("time_offset");
  if (drift_ppm) n.push_back("clock_drift");
  if (k1k2 || k3k4) n.push_back("lens_distortion");
  if (lens) n.push_back("lens_model");
  if (fxfy) n.push_back("focal_length");
  if (gyro_bias) n.push_back("gyro_bias");
  if (lever_arm) n.push_back("lever_arm");
  if (mount_rotation) n.push_back("mount_rotation");
  if (gyro_scale) n.push_back("gyro_scale");
  if (principal_point) n.push_back("principal_point");
  return n;
}

namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

void validate(const SimConfig& c) {
  const CameraModel& cam = c.nominal.cam;
  require(cam.width > 1 && cam.height > 1, "camera.width/height must be > 1");
  require(cam.fx > 0 && cam.fy > 0, "camera.fx/fy must be positive");
  require(c.nominal.frame_rate_hz > 0, "timing.frame_rate_hz must be positive");
  require(c.nominal.time.line_delay_s >= 0, "timing.line_delay_s must not be negative");
  require(c.duration_s > 0, "duration_s must be positive");
  require(c.noise_px >= 0, "observations.noise_px must not be negative");
  require(c.trajectory_rate_hz > 0, "motion.trajectory_rate_hz must be positive");
  require(c.motion_source != MotionSource::Samples || c.pose_samples.size() >= 2,
          "motion.file must hold at least two poses");
  require(c.gyro.rate_min_hz > 0 && c.gyro.rate_max_hz >= c.gyro.rate_min_hz,
          "motion.gyro.rate_hz must be [min, max] with 0 < min <= max");
  require(c.outlier_fraction >= 0 && c.outlier_fraction < 1, "observations.outlier_fraction must be in [0, 1)");
  require(!c.effects.line_delay_s || *c.effects.line_delay_s >= 0, "effects.rolling_shutter.line_delay_s must not be negative");
  require(!c.effects.fxfy || (c.effects.fxfy->minCoeff() > 0), "effects.focal_length fx, fy must be positive");
  require(!c.effects.gyro_scale || (c.effects.gyro_scale->minCoeff() > 0), "effects.gyro_scale sx, sy, sz must be positive");
  const Unmodelled& u = c.unmodelled;
  require(u.scene_depth_m >= 0, "unmodelled.scene_depth_m must not be negative");
  require(!u.scene_fixed_in_world || u.scene_depth_m > 0, "unmodelled.scene_fixed_in_world needs a scene_depth_m");
  require(u.scene_depth_m == 0 || c.kind == ObservationKind::Matches,
          "unmodelled.scene_depth_m applies to matches (landmarks have their points)");
  require(u.scene_slope.allFinite(), "unmodelled.scene_slope must be finite");
  require(u.gyro_saturation_rad_s >= 0, "unmodelled.gyro_saturation_rad_s must not be negative");
  require(u.stabilisation_hz >= 0, "unmodelled.stabilisation_hz must not be negative");
  require(u.stabilisation_hz == 0 || c.kind == ObservationKind::Matches,
          "unmodelled.stabilisation_hz applies to matches (a stabilised video's features)");
  require(u.clock_jump_at_s >= 0 && u.clock_jump_at_s <= c.duration_s,
          "unmodelled.clock_jump_at_s must lie within the recording");
  const double readout = cam.height * c.effects.line_delay_s.value_or(c.nominal.time.line_delay_s);
  require(readout <= (1 + 1e-9) / c.nominal.frame_rate_hz, "line delay x height exceeds the frame period");
}

}  // namespace

TrueModel true_model(const NominalModel& n, const Effects& e) {
  TrueModel t{n.cam, n.time, n.lever_arm, Eigen::Vector3d::Zero()};
  if (e.line_delay_s) t.time.line_delay_s = *e.line_delay_s;
  if (e.flip_readout)
    t.time.readout = n.time.readout == Readout::TopToBottom ? Readout::BottomToTop : Readout::TopToBottom;
  if (e.time_offset_s) t.time.time_offset_s = *e.time_offset_s;
  if (e.drift_ppm) t.time.drift_ppm = *e.drift_ppm;
  if (e.lens) t.cam.dist = *e.lens;  // a fisheye behind a pinhole nominal, or the reverse
  if (e.k1k2) t.cam.dist.k1 = e.k1k2->x(), t.cam.dist.k2 = e.k1k2->y();
  if (e.k3k4) t.cam.dist.k3 = e.k3k4->x(), t.cam.dist.k4 = e.k3k4->y();
  if (e.fxfy) t.cam.fx = e.fxfy->x(), t.cam.fy = e.fxfy->y();
  if (e.lever_arm) t.lever_arm = *e.lever_arm;
  if (e.gyro_bias) t.gyro_bias = *e.gyro_bias;
  if (e.mount_rotation) t.mount = exp_so3(*e.mount_rotation);
  if (e.gyro_scale) t.gyro_scale = *e.gyro_scale;
  if (e.principal_point) t.cam.cx = e.principal_point->x(), t.cam.cy = e.principal_point->y();
  return t;
}

namespace {

// Motion-clock span the recording must cover: the frames under the true clock model, with
// a second's margin either side so that offset searches of +-1 s stay inside the data.
std::pair<double, double> motion_span(const Recording& r, const TrueModel& m) {
  const double a = m.time.motion_time(r.frames.front().t);
  const double b = m.time.motion_time(r.frames.back().t + 1.0 / r.nominal.frame_rate_hz);
  return {std::min(a, b) - 1.0, std::max(a, b) + 1.0};
}

// The body's pose over time (world-from-body), whichever source the scenario chose. The
// rest pose is where Smooth and Constant motions start from.
class BodyMotion {
 public:
  BodyMotion(const SimConfig& c, const Eigen::Vector3d& rest, double t0)
      : c_(c), t0_(t0),
        smooth_{rest, Eigen::Matrix3d::Identity(),
                SmoothSignal3(c.seed * 7 + 1, Eigen::Vector3d::Constant(c.translation_amplitude_m), c.motion_frequency_hz),
                SmoothSignal3(c.seed * 7 + 2, Eigen::Vector3d::Constant(c.rotation_amplitude_rad), c.motion_frequency_hz)} {
    if (c.motion_source == MotionSource::Samples) {
      std::vector<SampledTrajectory::Sample> s;
      for (const auto& p : c.pose_samples) s.push_back({p.t, p.q, p.p});
      samples_.emplace(std::move(s));
    }
  }
  PoseSample at(double t) const {
    switch (c_.motion_source) {
      case MotionSource::Smooth: return {t, smooth_.position(t), smooth_.orientation(t)};
      case MotionSource::Constant: {
        // world_from_body(t) = rest * exp((t - t0) xi), xi = (v, w) in body axes.
        const Eigen::Affine3d g = ScrewMotion(Twist{c_.constant_velocity, c_.constant_angular_rate}).at(t - t0_);
        return {t, smooth_.p0 + g.translation(), Eigen::Quaterniond(g.linear())};
      }
      case MotionSource::Samples: {
        const Eigen::Affine3d cam_from_world = samples_->at(t);
        const Eigen::Matrix3d R = cam_from_world.linear().transpose();
        return {t, -R * cam_from_world.translation(), Eigen::Quaterniond(R)};
      }
    }
    return {};
  }
  // Angular rate in body axes (dR/dt = R [w]x), by central differences.
  Eigen::Vector3d body_rate(double t) const {
    const double h = 1e-5;
    return log_so3((at(t - h).q.conjugate() * at(t + h).q).toRotationMatrix()) / (2 * h);
  }

 private:
  const SimConfig& c_;
  double t0_;
  SmoothPose smooth_;
  std::optional<SampledTrajectory> samples_;
};

Eigen::Vector2d noisy(const Eigen::Vector2d& p, double sigma, std::mt19937& rng) {
  if (!(sigma > 0)) return p;
  std::normal_distribution<double> n(0, sigma);
  return p + draw<2>(n, rng);
}

void simulate_landmarks(const SimConfig& c, const TrueModel& m, SimulatedRecording& out, std::mt19937& rng) {
  Recording& r = out.rec;
  r.motion = MotionKind::Trajectory;
  r.points = c.points;
  for (int i = 0; i < c.target_rows && c.points.empty(); ++i)
    for (int j = 0; j < c.target_cols; ++j)
      r.points.push_back({i * c.target_cols + j, Eigen::Vector3d((j - 0.5 * (c.target_cols - 1)) * c.target_spacing_m,
                                                                  (i - 0.5 * (c.target_rows - 1)) * c.target_spacing_m, 0.0)});
  // The body rests target_distance_m in front of the target (z = 0 plane), looking along +z.
  const BodyMotion pose(c, Eigen::Vector3d(0, 0, -c.target_distance_m), r.frames.front().t);
  const auto [t_begin, t_end] = motion_span(r, m);
  std::vector<SampledTrajectory::Sample> samples;
  for (double t = t_begin; t <= t_end; t += 1.0 / c.trajectory_rate_hz) {
    const PoseSample p = pose.at(t);
    r.trajectory.push_back(p);
    samples.push_back({t, p.q, p.p});
  }
  // The written samples are the truth: interpolating them is the motion the data follow.
  const SampledTrajectory truth(std::move(samples));
  const LandmarkSetup setup{m.cam, m.time, m.lever_arm, m.mount};
  for (const FrameStamp& f : r.frames)
    for (const Landmark& L : r.points) {
      const auto p = predict_landmark(setup, truth, f.t, L.X);
      if (p && m.cam.contains(p->pixel, 0.0)) r.observations.push_back({f.frame, L.id, noisy(p->pixel, c.noise_px, rng)});
    }
}

std::vector<GyroSample> sample_gyro(const SimConfig& c, const BodyMotion& imu, const TrueModel& m, double t_begin,
                                    double t_end, std::mt19937& rng) {
  const GyroSampling& g = c.gyro;
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> n(0, 1);
  std::vector<GyroSample> out;
  for (double t = t_begin; t <= t_end;) {
    const double dt = 1.0 / (g.rate_min_hz + (g.rate_max_hz - g.rate_min_hz) * u(rng));
    // What the gyro reads for the IMU's true rate: w_true = diag(s) (w_measured - b).
    const Eigen::Vector3d w_true = imu.body_rate(t);
    Eigen::Vector3d w = w_true.cwiseQuotient(m.gyro_scale) + m.gyro_bias + g.noise_rad_s * draw<3>(n, rng);
    if (const double sat = c.unmodelled.gyro_saturation_rad_s; sat > 0) w = w.cwiseMax(-sat).cwiseMin(sat);
    double stamp = t + g.jitter_s * n(rng);
    if (!out.empty() && u(rng) < g.repeat_probability) stamp = out.back().t;
    out.push_back({stamp, w});
    t += (u(rng) < g.gap_probability) ? dt * (5 + 15 * u(rng)) : dt;
  }
  std::stable_sort(out.begin(), out.end(), [](const GyroSample& a, const GyroSample& b) { return a.t < b.t; });
  return out;
}

// Matches of features on a plane `depth` along frame_a's optical axis (tilted by the slope of
// its inverse depth), or on that plane as it lay at the recording's middle instant, fixed in the
// world (Unmodelled::scene_fixed_in_world), seen by a camera that translates with the body as well as turning:
// parallax, which the rotation-only model of matches cannot express. Returns frame_b's pixel of
// the feature at pixel `a` of frame_a.
class ParallaxScene {
 public:
  ParallaxScene(const SimConfig& c, const TrueModel& m, const BodyMotion& body, double t_begin, double t_end,
                const Eigen::Matrix3d& imu_to_camera)
      : setup_{m.cam, m.time, Eigen::Vector3d::Zero(), imu_to_camera.transpose()}, depth_(c.unmodelled.scene_depth_m),
        slope_(c.unmodelled.scene_slope), body_(samples(body, t_begin, t_end)) {
    if (!c.unmodelled.scene_fixed_in_world) return;
    // The camera at the middle instant: the plane before it, in world axes.
    const auto [R_wc, p_wc] = camera_in_world(0.5 * (t_begin + t_end));
    wall_ = Wall{R_wc * Eigen::Vector3d(slope_.x(), slope_.y(), 1.0), p_wc};
  }
  std::optional<Prediction> predict(double T_a, const Eigen::Vector2d& a, double T_b) const {
    const auto ray = setup_.cam.ray(a);
    if (!ray || ray->z() <= 0) return std::nullopt;
    const Eigen::Vector3d along = *ray / ray->z();  // camera axes, unit depth
    const double inverse_depth = 1 + slope_.dot(along.head<2>());  // over depth_'s, before frame_a
    if (!wall_ && inverse_depth < 0.1) return std::nullopt;
    const double t = setup_.time.motion_time(T_a + row_timing(setup_.time, setup_.cam.height).row_time(a.y()));
    const auto [R_wc, p_wc] = camera_in_world(t);  // at the row's capture
    if (!wall_) return predict_landmark(setup_, body_, T_b, p_wc + R_wc * (along * depth_ / inverse_depth));
    // The world's plane n . (X - p) = depth_: where the ray meets it, in front of the camera.
    const Eigen::Vector3d dir = R_wc * along;
    const double along_depth = (depth_ - wall_->normal.dot(p_wc - wall_->point)) / wall_->normal.dot(dir);
    if (!(along_depth > 0.1 * depth_ && along_depth < 10 * depth_)) return std::nullopt;
    return predict_landmark(setup_, body_, T_b, p_wc + along_depth * dir);
  }

 private:
  static SampledTrajectory samples(const BodyMotion& body, double t_begin, double t_end) {
    std::vector<SampledTrajectory::Sample> s;
    for (double t = t_begin; t <= t_end; t += 5e-4) {
      const PoseSample p = body.at(t);
      s.push_back({t, p.q, p.p});
    }
    return SampledTrajectory(std::move(s));
  }
  LandmarkSetup setup_;
  double depth_;
  Eigen::Vector2d slope_;
  SampledTrajectory body_;
  // The camera's orientation and position in the world at motion time t: the body's pose
  // turned by the mount.
  std::pair<Eigen::Matrix3d, Eigen::Vector3d> camera_in_world(double t) const {
    const Eigen::Affine3d body_from_world = body_.at(t);
    const Eigen::Matrix3d R_wb = body_from_world.linear().transpose();
    return {R_wb * setup_.mount, -R_wb * body_from_world.translation()};
  }
  struct Wall {
    Eigen::Vector3d normal, point;  // world axes: n . (X - point) = depth_ on the plane
  };
  std::optional<Wall> wall_;  // scene_fixed_in_world
};

// In-camera stabilisation: the orientation the pictures follow, smoothed by a first-order
// low-pass of corner `hz` run forward then backward over the samples (zero phase, as a
// stabiliser that looks ahead in its buffer does), on the sphere by slerp; forward only when it
// does not look ahead.
void stabilise(std::vector<OrientationTrack::Sample>& s, double hz, bool looks_ahead) {
  if (s.size() < 2) return;
  const double tau = 1.0 / (2 * M_PI * hz);
  auto pass = [&](auto begin, auto end) {
    Eigen::Quaterniond q = begin->q;
    for (auto it = begin, prev = begin; it != end; prev = it++) {
      const double a = std::abs(it->t - prev->t) / (tau + std::abs(it->t - prev->t));
      if (q.dot(it->q) < 0) q.coeffs() *= -1;
      q = q.slerp(a, it->q).normalized();
      it->q = q;
    }
  };
  pass(s.begin(), s.end());
  if (looks_ahead) pass(s.rbegin(), s.rend());
}

void simulate_matches(const SimConfig& c, const TrueModel& m, SimulatedRecording& out, std::mt19937& rng) {
  Recording& r = out.rec;
  r.motion = MotionKind::Gyro;
  const BodyMotion imu(c, Eigen::Vector3d::Zero(), r.frames.front().t);
  const auto [t_begin, t_end] = motion_span(r, m);
  r.gyro = sample_gyro(c, imu, m, t_begin, t_end, rng);
  std::optional<ParallaxScene> near;
  if (c.unmodelled.scene_depth_m > 0) near.emplace(c, m, imu, t_begin, t_end, m.mount * r.nominal.imu_to_camera);
  // The truth is the continuous orientation, sampled densely enough (2 kHz) that slerp
  // between samples is exact to well below a micro-radian.
  std::vector<OrientationTrack::Sample> cam_samples;
  for (double t = t_begin; t <= t_end; t += 5e-4)
    cam_samples.push_back({t, camera_orientation(imu.at(t).q, m.mount * r.nominal.imu_to_camera)});  // Exp(r) R_nominal
  if (c.unmodelled.stabilisation_hz > 0) stabilise(cam_samples, c.unmodelled.stabilisation_hz, c.unmodelled.stabilisation_looks_ahead);
  const OrientationTrack truth(std::move(cam_samples));
  const MatchSetup setup{m.cam, m.time};
  std::uniform_real_distribution<double> u(0, m.cam.width - 1), v(0, m.cam.height - 1), flip(0, 1);
  for (size_t k = 0; k + 1 < r.frames.size(); ++k) {
    const FrameStamp &fa = r.frames[k], &fb = r.frames[k + 1];
    for (int i = 0; i < c.matches_per_pair; ++i) {
      const Eigen::Vector2d a = draw(u, v, rng);
      const auto b = near ? near->predict(fa.t, a, fb.t) : predict_match(setup, truth, fa.t, a, fb.t);
      if (!b || !m.cam.contains(b->pixel, 0.0)) continue;
      const bool outlier = flip(rng) < c.outlier_fraction;
      const Eigen::Vector2d pb = outlier ? draw(u, v, rng) : noisy(b->pixel, c.noise_px, rng);
      r.matches.push_back({fa.frame, noisy(a, c.noise_px, rng), fb.frame, pb});
      out.match_outlier.push_back(outlier);
    }
  }
}

}  // namespace

SimulatedRecording simulate_recording(const SimConfig& cfg) {
  validate(cfg);
  SimulatedRecording out;
  Recording& r = out.rec;
  r.kind = cfg.kind;
  r.nominal = cfg.nominal;
  r.noise_px = cfg.noise_px;
  out.truth = cfg.effects;
  const int n = static_cast<int>(std::floor(cfg.duration_s * cfg.nominal.frame_rate_hz));
  for (int k = 0; k < std::max(n, 2); ++k) r.frames.push_back({k, cfg.start_time_s + k / cfg.nominal.frame_rate_hz});
  r.nominal.time.t0 = r.frames.front().t;
  TrueModel m = true_model(r.nominal, cfg.effects);
  std::mt19937 rng(cfg.seed);
  if (cfg.kind == ObservationKind::Landmarks) simulate_landmarks(cfg, m, out, rng);
  else simulate_matches(cfg, m, out, rng);
  // A clock that jumps: the frames after it are stamped clock_jump_s late (their pictures,
  // taken above, are where the motion really was).
  if (const Unmodelled& u = cfg.unmodelled; u.clock_jump_s != 0)
    for (FrameStamp& f : r.frames)
      if (f.t - r.nominal.time.t0 >= u.clock_jump_at_s) f.t += u.clock_jump_s;
  return out;
}

}  // namespace rsd::dsp
