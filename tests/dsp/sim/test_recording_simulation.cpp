// Simulated recordings: without effects they follow the nominal model exactly; each effect
// makes the nominal model wrong while the true parameters still explain the data.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "dsp/sim/recording_simulation.hpp"

using namespace rsd::dsp;
using Eigen::Vector3d;

namespace {

SimConfig base(ObservationKind kind) {
  SimConfig c;
  c.kind = kind;
  c.nominal.cam.width = 640, c.nominal.cam.height = 480;
  c.nominal.cam.fx = c.nominal.cam.fy = 500, c.nominal.cam.cx = 319.5, c.nominal.cam.cy = 239.5;
  c.nominal.time.line_delay_s = 1.0 / (480 * 30);
  c.duration_s = 1.0;
  c.noise_px = 0.0;
  return c;
}

// Nominal-model residual RMS of a landmarks recording.
double landmark_rms(const Recording& r, const LandmarkSetup& s) {
  std::vector<SampledTrajectory::Sample> samples;
  for (const auto& p : r.trajectory) samples.push_back({p.t, p.q, p.p});
  const SampledTrajectory traj(samples);
  double sum = 0;
  int n = 0;
  for (const auto& o : r.observations) {
    const auto p = predict_landmark(s, traj, r.frames[o.frame].t, r.points[o.id].X);
    if (!p) continue;
    sum += (p->pixel - o.px).squaredNorm();
    ++n;
  }
  return std::sqrt(sum / n);
}

}  // namespace

TEST(RecordingSimulation, LandmarksFollowTheNominalModelWithoutEffects) {
  const SimulatedRecording s = simulate_recording(base(ObservationKind::Landmarks));
  ASSERT_GT(s.rec.observations.size(), 1000u);
  EXPECT_EQ(s.rec.frames.size(), 30u);
  EXPECT_NEAR(s.rec.nominal.time.t0, 100.0, 1e-12);
  EXPECT_LT(landmark_rms(s.rec, {s.rec.nominal.cam, s.rec.nominal.time, s.rec.nominal.lever_arm}), 1e-6);
}

TEST(RecordingSimulation, EachEffectBreaksTheNominalModelButNotTheTrueOne) {
  SimConfig c = base(ObservationKind::Landmarks);
  c.effects.time_offset_s = 0.004;
  c.effects.k1k2 = Eigen::Vector2d(-0.05, 0.01);
  c.effects.lever_arm = Vector3d(0.02, 0, 0.01);
  const SimulatedRecording s = simulate_recording(c);
  const NominalModel& n = s.rec.nominal;
  EXPECT_GT(landmark_rms(s.rec, {n.cam, n.time, n.lever_arm}), 0.5);
  LandmarkSetup truth{n.cam, n.time, Vector3d(0.02, 0, 0.01)};
  truth.time.time_offset_s = 0.004;
  truth.cam.dist.k1 = -0.05, truth.cam.dist.k2 = 0.01;
  EXPECT_LT(landmark_rms(s.rec, truth), 1e-6);
  const auto names = s.truth.names();
  EXPECT_EQ(names, (std::vector<std::string>{"time_offset", "lens_distortion", "lever_arm"}));
}

// A fisheye behind a pinhole nominal (the lens_model effect), and a fisheye nominal whose k3, k4
// differ (lens_distortion of pinhole-equi): the observations follow the true lens, not the nominal.
TEST(RecordingSimulation, ALensOfTheOtherFamilyAndEquidistantTermsAreRenderedAsTrue) {
  SimConfig c = base(ObservationKind::Landmarks);
  c.effects.lens = Distortion::equidistant(0.02, -0.01, 0.004, -0.001);
  const SimulatedRecording s = simulate_recording(c);
  const NominalModel& n = s.rec.nominal;
  EXPECT_EQ(n.cam.dist.model, LensModel::PinholeRadtan);
  EXPECT_GT(landmark_rms(s.rec, {n.cam, n.time, n.lever_arm}), 0.5);
  LandmarkSetup truth{n.cam, n.time, n.lever_arm};
  truth.cam.dist = *c.effects.lens;
  EXPECT_LT(landmark_rms(s.rec, truth), 1e-6);
  EXPECT_EQ(s.truth.names(), std::vector<std::string>{"lens_model"});

  SimConfig f = base(ObservationKind::Landmarks);
  f.nominal.cam.dist = Distortion::equidistant(0.02, -0.01, 0, 0);
  f.effects.k1k2 = Eigen::Vector2d(0.02, -0.01);
  f.effects.k3k4 = Eigen::Vector2d(0.05, -0.02);
  const SimulatedRecording fs = simulate_recording(f);
  LandmarkSetup ftruth{fs.rec.nominal.cam, fs.rec.nominal.time, fs.rec.nominal.lever_arm};
  ftruth.cam.dist = Distortion::equidistant(0.02, -0.01, 0.05, -0.02);
  EXPECT_LT(landmark_rms(fs.rec, ftruth), 1e-6);
  EXPECT_GT(landmark_rms(fs.rec, {fs.rec.nominal.cam, fs.rec.nominal.time, fs.rec.nominal.lever_arm}), 0.01);  // 0.016 px: k3, k4 act far off the axis
  EXPECT_EQ(fs.truth.names(), std::vector<std::string>{"lens_distortion"});
}

TEST(RecordingSimulation, MatchesHaveOutliersAndIrregularGyro) {
  SimConfig c = base(ObservationKind::Matches);
  c.outlier_fraction = 0.1;
  c.gyro.rate_min_hz = 20, c.gyro.rate_max_hz = 200;
  c.gyro.repeat_probability = 0.05;
  c.gyro.gap_probability = 0.02;
  c.effects.gyro_bias = Vector3d(0.002, -0.001, 0.0015);
  const SimulatedRecording s = simulate_recording(c);
  ASSERT_GT(s.rec.matches.size(), 2000u);
  size_t outliers = 0;
  for (bool o : s.match_outlier) outliers += o;
  EXPECT_NEAR(double(outliers) / s.match_outlier.size(), 0.1, 0.02);
  int repeats = 0;
  double longest = 0;
  for (size_t i = 1; i < s.rec.gyro.size(); ++i) {
    const double dt = s.rec.gyro[i].t - s.rec.gyro[i - 1].t;
    repeats += dt == 0;
    longest = std::max(longest, dt);
    ASSERT_GE(dt, 0);
  }
  EXPECT_GT(repeats, 5);
  EXPECT_GT(longest, 5.0 / 200);
}

TEST(RecordingSimulation, InlierMatchesFollowTheTrueModel) {
  // A regular 200 Hz gyro, integrated after removing the true bias, explains every inlier.
  SimConfig c = base(ObservationKind::Matches);
  c.outlier_fraction = 0.1;
  c.effects.gyro_bias = Vector3d(0.002, -0.001, 0.0015);
  c.effects.time_offset_s = 0.02;
  const SimulatedRecording s = simulate_recording(c);
  const OrientationTrack imu = integrate_gyro(s.rec.gyro, *c.effects.gyro_bias);
  std::vector<OrientationTrack::Sample> cam;
  for (double t = imu.t_begin(); t <= imu.t_end(); t += 1e-3)
    cam.push_back({t, camera_orientation(imu.at(t), s.rec.nominal.imu_to_camera)});
  const OrientationTrack track(cam);
  MatchSetup m{s.rec.nominal.cam, s.rec.nominal.time};
  m.time.time_offset_s = 0.02;
  double worst = 0;
  int n = 0;
  for (size_t i = 0; i < s.rec.matches.size(); ++i) {
    if (s.match_outlier[i]) continue;
    const Match& mt = s.rec.matches[i];
    const auto b = predict_match(m, track, s.rec.frames[mt.frame_a].t, mt.a, s.rec.frames[mt.frame_b].t);
    ASSERT_TRUE(b.has_value());
    worst = std::max(worst, (b->pixel - mt.b).norm());
    ++n;
  }
  EXPECT_GT(n, 2000);
  EXPECT_LT(worst, 0.03);  // 200 Hz samples of a 1-3 Hz motion: integration, not the model
}

// In-camera stabilisation (Unmodelled::stabilisation_hz): the pictures follow the orientation
// through a zero-phase low-pass, |H(f)|^2 = 1 / (1 + (f / fc)^2), the gyro the real one. The
// shake's frequencies lie in [0.5, 1.5] x 1.2 Hz, so the frame-to-frame image motion keeps a
// share of its RMS between the gains at 1.8 and at 0.6 Hz (the same matches, seed for seed); a
// stabiliser that does not look ahead passes it once, at the square root of those gains.
TEST(RecordingSimulation, AStabilisedVideoMovesByTheLowPassOfTheShake) {
  SimConfig c = base(ObservationKind::Matches);
  c.duration_s = 6.0;
  c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2;
  c.gyro = {200, 200, 0, 0, 0, 0};
  auto motion_rms = [](const SimulatedRecording& s) {
    double sum = 0;
    for (const Match& m : s.rec.matches) sum += (m.b - m.a).squaredNorm();
    return std::sqrt(sum / static_cast<double>(s.rec.matches.size()));
  };
  const SimulatedRecording plain = simulate_recording(c);
  for (double fc : {5.0, 0.5}) {
    SimConfig st = c;
    st.unmodelled.stabilisation_hz = fc;
    const SimulatedRecording s = simulate_recording(st);
    ASSERT_EQ(s.rec.gyro.size(), plain.rec.gyro.size());
    for (size_t k = 0; k < s.rec.gyro.size(); ++k) ASSERT_EQ(s.rec.gyro[k].w, plain.rec.gyro[k].w) << "the gyro is the real one";
    const double gain = motion_rms(s) / motion_rms(plain);
    auto h2 = [&](double f) { return 1 / (1 + (f / fc) * (f / fc)); };
    std::printf("stabilised at %.1f Hz: the image motion keeps %.3f of its RMS (band %.3f..%.3f)\n", fc, gain, h2(1.8), h2(0.6));
    EXPECT_GT(gain, 0.97 * h2(1.8)) << fc;
    EXPECT_LT(gain, 1.03 * h2(0.6)) << fc;
    // Without looking ahead, the forward pass alone: |H(f)| = 1 / sqrt(1 + (f / fc)^2).
    st.unmodelled.stabilisation_looks_ahead = false;
    const double lagging = motion_rms(simulate_recording(st)) / motion_rms(plain);
    std::printf("  forward pass only: %.3f (band %.3f..%.3f)\n", lagging, std::sqrt(h2(1.8)), std::sqrt(h2(0.6)));
    EXPECT_GT(lagging, 0.97 * std::sqrt(h2(1.8))) << fc;
    EXPECT_LT(lagging, 1.03 * std::sqrt(h2(0.6))) << fc;
  }
}

TEST(RecordingSimulation, RejectsBadConfigNamingTheField) {
  SimConfig c = base(ObservationKind::Landmarks);
  c.nominal.frame_rate_hz = 0;
  try {
    simulate_recording(c);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("frame_rate_hz"), std::string::npos);
  }
  SimConfig w = base(ObservationKind::Matches);
  w.unmodelled.scene_fixed_in_world = true;  // a wall, and no depth for it
  try {
    simulate_recording(w);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("scene_fixed_in_world"), std::string::npos);
  }
}

// A wall fixed in the world (Unmodelled::scene_fixed_in_world), approached along the optical
// axis at v without turning, no rolling shutter: a feature at x_a in frame_a is at x_b = x_a
// Z_a / (Z_a - v dt) in frame_b, so each pair's depth is Z_a = v dt r / (r - 1), r = x_b / x_a.
// The wall stays put: Z_a + v t_a is the same for every pair (the depth falls as the camera
// nears it). Before each frame_a instead, Z_a is the configured depth in every pair.
TEST(RecordingSimulation, AWallFixedInTheWorldComesNearerAsTheCameraApproachesIt) {
  const double v = 1.0, depth = 4.0;
  for (bool fixed : {false, true}) {
    SimConfig c = base(ObservationKind::Matches);
    c.duration_s = 2.0;
    c.nominal.time.line_delay_s = 0;
    c.outlier_fraction = 0;
    c.gyro = {200, 200, 0, 0, 0, 0};
    c.motion_source = MotionSource::Constant;
    c.constant_velocity = Vector3d(0, 0, v);
    c.unmodelled.scene_depth_m = depth;
    c.unmodelled.scene_fixed_in_world = fixed;
    const SimulatedRecording s = simulate_recording(c);
    const CameraModel& cam = s.rec.nominal.cam;
    double lo = INFINITY, hi = -INFINITY, z_lo = INFINITY, z_hi = -INFINITY;
    int n = 0;
    for (const Match& m : s.rec.matches) {
      const double xa = (m.a.x() - cam.cx) / cam.fx, xb = (m.b.x() - cam.cx) / cam.fx;
      if (std::abs(xa) < 0.2) continue;  // the ratio is held by features off the axis
      const double ta = s.rec.frames[m.frame_a].t, dt = s.rec.frames[m.frame_b].t - ta, r = xb / xa;
      const double za = v * dt * r / (r - 1);
      lo = std::min(lo, za + v * ta), hi = std::max(hi, za + v * ta);
      z_lo = std::min(z_lo, za), z_hi = std::max(z_hi, za);
      ++n;
    }
    ASSERT_GT(n, 100);
    std::printf("wall %s: depth %.4f..%.4f m, depth + distance travelled %.4f..%.4f m\n",
                fixed ? "fixed in the world" : "before each frame_a", z_lo, z_hi, lo, hi);
    if (fixed) {
      EXPECT_LT(hi - lo, 1e-4);
      EXPECT_GT(z_hi - z_lo, 0.9 * v * c.duration_s);
    } else {
      EXPECT_NEAR(z_lo, depth, 1e-4);
      EXPECT_NEAR(z_hi, depth, 1e-4);
    }
  }
}
