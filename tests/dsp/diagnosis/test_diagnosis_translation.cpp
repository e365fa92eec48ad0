// The translation nuisance of matches (dsp/diagnosis/translation.hpp) against simulated flights:
// it takes out the parallax a near scene gives, facing the camera or tilted as a ground ahead
// is (at the true model the noise is left), it cannot
// take up what a clock offset leaves (a free translation per frame pair took up most of it),
// a forward flight with a pan yields its clock offset, and a hand-held phone 4 m from a wall its
// focal length, lens, mount, clock offset and shutter (issue 34, point 2); a hand-held shake
// faster than the default knots gets finer ones, and a focal length under it is named alone.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "dsp/diagnosis/diagnosis.hpp"
#include "dsp/diagnosis/parallax.hpp"
#include "dsp/diagnosis/robust_stats.hpp"
#include "dsp/sim/flight_path.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"
#include "tests/support/sanitizer.hpp"

namespace rsd::test {
namespace {

using namespace rsd::dsp;

// A drone flying forward at 8 m/s past a scene `depth_m` ahead (a plane facing each frame pair's
// first camera), panning by 0.8 rad over the 2 s from 4 s on (flight_path.hpp); 10 s of the VGA
// camera, 0.5 px noise.
SimConfig forward_flight(unsigned seed, double depth_m) {
  SimConfig c = simulation(ObservationKind::Matches, seed, 10.0, 0.5);
  c.motion_source = MotionSource::Samples;
  c.pose_samples = flight_poses(FlightPath{}, c.start_time_s, c.start_time_s - 3, c.start_time_s + c.duration_s + 3);
  c.unmodelled.scene_depth_m = depth_m;
  c.gyro.noise_rad_s = 0.002;
  return c;
}

ModelParams with_offset(const SimulatedRecording& sim, double offset_s, bool nuisance) {
  ModelParams p = nominal_params(sim.rec.nominal);
  p[Param::TimeOffset] = offset_s;
  p.translation_nuisance = nuisance;
  return p;
}

// A ground ahead of the drone, as a tilted plane: its inverse depth grows towards the image's
// bottom (and a little to the right), from 0.4 to 1.6 times the depth's at the image's top and
// bottom rows (VGA, f 500 px).
const Eigen::Vector2d kGround(0.3, 1.25);

TEST(Translation, AtTheTrueModelTheVelocitySplineLeavesTheNoise) {
  struct Case {
    double depth;
    Eigen::Vector2d slope;
  };
  for (const Case& k : {Case{40.0, Eigen::Vector2d::Zero()}, Case{15.0, Eigen::Vector2d::Zero()}, Case{15.0, kGround}}) {
    const double depth = k.depth;
    SimConfig c = forward_flight(8, depth);
    c.unmodelled.scene_slope = k.slope;
    c.effects.time_offset_s = 0.01;
    const SimulatedRecording sim = simulate_recording(c);
    const DiagnosisModel m(sim.rec);
    const auto all = every_observation(m);
    const double noise = 0.5 * m.noise_gain();
    const RobustStats plain = robust_stats(m.residuals(with_offset(sim, 0.01, false), all));
    const RobustStats taken = robust_stats(m.residuals(with_offset(sim, 0.01, true), all));
    EXPECT_GT(plain.rms_px, 2 * noise) << "depth " << depth;  // the parallax is there
    EXPECT_NEAR(taken.rms_px, noise, 0.03 * noise) << "depth " << depth << " slope " << k.slope.transpose();
  }
}

// The part of `d` (residual differences, by observation) that a free translation per frame
// pair explains: the old nuisance's fit, by least squares per pair.
double share_a_free_translation_takes(const DiagnosisModel& m, const std::vector<int>& idx,
                                      const std::vector<Eigen::Vector2d>& d) {
  const CameraModel& cam = m.recording().nominal.cam;
  double total = 0, left = 0;
  for (size_t b = 0, e = 0; b < idx.size(); b = e) {
    for (e = b; e < idx.size() && m.frame_rank(idx[e]) == m.frame_rank(idx[b]); ++e) {
    }
    Eigen::MatrixXd A(2 * (e - b), 3);
    Eigen::VectorXd y(2 * (e - b));
    for (size_t k = b; k < e; ++k)
      A.block<2, 3>(2 * (k - b), 0) = translation_flow(cam, m.observed(idx[k])), y.segment<2>(2 * (k - b)) = d[k];
    left += (y - A * A.colPivHouseholderQr().solve(y)).squaredNorm();
    total += y.squaredNorm();
  }
  return 1 - left / total;
}

TEST(Translation, TheVelocitySplineCannotTakeUpAClockOffset) {
  // Noise-free: what a 10 ms clock offset changes in the residuals, over the pan. A free
  // translation per pair takes up nearly all of it (a sideways translation over one depth moves
  // the image as a pan does); the velocity spline, smooth in world axes, leaves most of it.
  SimConfig c = forward_flight(9, 15.0);
  c.noise_px = 0, c.gyro.noise_rad_s = 0;
  const SimulatedRecording sim = simulate_recording(c);
  const DiagnosisModel m(sim.rec);
  std::vector<int> pan;
  for (int i = 0; i < m.size(); ++i)
    if (m.frame_time(i) - sim.rec.frames.front().t > 4.2 && m.frame_time(i) - sim.rec.frames.front().t < 5.8) pan.push_back(i);
  ASSERT_GT(pan.size(), 1000u);
  const auto plain_true = m.residuals(with_offset(sim, 0, false), pan), plain_off = m.residuals(with_offset(sim, 0.01, false), pan);
  const auto taken_true = m.residuals(with_offset(sim, 0, true), pan), taken_off = m.residuals(with_offset(sim, 0.01, true), pan);
  std::vector<Eigen::Vector2d> change(pan.size());
  double before = 0, after = 0;
  for (size_t k = 0; k < pan.size(); ++k) {
    change[k] = plain_off[k] - plain_true[k];
    before += change[k].squaredNorm();
    after += (taken_off[k] - taken_true[k]).squaredNorm();
  }
  ASSERT_GT(before / pan.size(), 0.01);  // the offset moves the pan's matches by over 0.1 px
  EXPECT_GT(share_a_free_translation_takes(m, pan, change), 0.8);
  EXPECT_GT(after / before, 0.6);
}

TEST(Translation, AForwardFlightWithAPanYieldsItsClockOffset) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Translation.AtTheTrueModelTheVelocitySplineLeavesTheNoise (the nuisance, over the ground too)");
  // Far (40 m) and near (15 m) scenes, a long lens (f = 1200 px: the pan's flow is nearly a
  // shift, as a sideways translation's is), and the ground ahead (a tilted plane).
  struct Case {
    unsigned seed;
    double depth_m, focal_px;
    Eigen::Vector2d slope = Eigen::Vector2d::Zero();
  };
  for (const Case& k : {Case{11, 40.0, 500.0}, Case{12, 15.0, 500.0}, Case{13, 40.0, 1200.0}, Case{14, 15.0, 500.0, kGround}}) {
    SimConfig c = forward_flight(k.seed, k.depth_m);
    c.unmodelled.scene_slope = k.slope;
    c.nominal.cam.fx = c.nominal.cam.fy = k.focal_px;
    c.effects.time_offset_s = 0.01;
    const SimulatedRecording sim = simulate_recording(c);
    const Diagnosis d = diagnose(DiagnosisModel(sim.rec));
    EXPECT_TRUE(d.parallax.clear()) << k.depth_m;
    EXPECT_EQ(names(d), "time_offset ") << "depth " << k.depth_m << " focal " << k.focal_px;
    EXPECT_NEAR(param(find(d, "time_offset"), "time_offset_s"), 0.01, 1e-3) << "depth " << k.depth_m << " focal " << k.focal_px;
  }
}

// Issue 34's hand-held phone, simulated: 1080p, its nominal focal length 12% short (1330 px
// for 1510), a lens's distortion, the camera turned 1.2 degrees on its mount, a clock offset and
// a rolling shutter, hand-held 4 m from a wall (parallax in every pair). A free fy stood in for
// the shutter's vertical stretch (fx and fy 5% apart, refused), and a gyro scale 8% off came
// within 1% of the distortion and, winning, ended the selection: nothing named, 10 px left.
TEST(Translation, AHandHeldPhoneUnderParallaxYieldsItsFocalLengthLensAndMount) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Translation.AtTheTrueModelTheVelocitySplineLeavesTheNoise and TheVelocitySplineCannotTakeUpAClockOffset (the nuisance)");
  SimConfig c = simulation(ObservationKind::Matches, 5, 10.0, 1.5);
  c.nominal.cam.width = 1920, c.nominal.cam.height = 1080;
  c.nominal.cam.fx = c.nominal.cam.fy = 1330, c.nominal.cam.cx = 959.5, c.nominal.cam.cy = 539.5;
  c.nominal.imu_to_camera << 0, -1, 0, -1, 0, 0, 0, 0, -1;  // a phone's gyro axes
  c.start_time_s = 1000;
  c.rotation_amplitude_rad = 0.15, c.translation_amplitude_m = 0.03;
  c.matches_per_pair = 46, c.outlier_fraction = 0.05;
  c.gyro.noise_rad_s = 0.003, c.gyro.jitter_s = 0.0002;
  c.unmodelled.scene_depth_m = 4.0;
  c.effects.line_delay_s = 0.022 / 1080;
  c.effects.time_offset_s = 0.03;
  c.effects.fxfy = Eigen::Vector2d(1510, 1510);
  c.effects.k1k2 = Eigen::Vector2d(0.06, -0.02);
  c.effects.mount_rotation = Eigen::Vector3d(0.015, -0.012, 0.008);
  const SimulatedRecording sim = simulate_recording(c);
  const Diagnosis d = diagnose(DiagnosisModel(sim.rec));
  EXPECT_TRUE(d.parallax.clear());
  EXPECT_EQ(names(d), "focal_length lens_distortion mount_rotation rolling_shutter time_offset ");
  EXPECT_NEAR(param(find(d, "focal_length"), "fx"), 1510, 0.015 * 1510);
  EXPECT_DOUBLE_EQ(param(find(d, "focal_length"), "fx"), param(find(d, "focal_length"), "fy"));
  EXPECT_NEAR(param(find(d, "rolling_shutter"), "frame_readout_s"), 0.022, 0.002);
  EXPECT_NEAR(param(find(d, "time_offset"), "time_offset_s"), 0.03, 0.004);
  const Eigen::Vector3d r(param(find(d, "mount_rotation"), "rx"), param(find(d, "mount_rotation"), "ry"),
                          param(find(d, "mount_rotation"), "rz"));
  // The turn's size within 20%; its roll about the optical axis is the least held (a roll of the
  // whole image is what the motion's own roll does), so its direction within 0.4 degrees.
  EXPECT_NEAR(r.norm(), c.effects.mount_rotation->norm(), 0.2 * c.effects.mount_rotation->norm());
  EXPECT_LT((r - *c.effects.mount_rotation).norm(), 0.007);
  // The parallax left is said, and the held-out frames are predicted near the noise.
  EXPECT_TRUE(d.remainder.significant);
  EXPECT_LT(d.heldout_final_rms_px, 1.15 * 1.5 * std::sqrt(2.0));
}

// The suite's `outside: parallax` rig (rsd-diagnose-suite, matches): a hand-held 1080p camera
// (f 1450 px, an irregular gyro on a phone's axes, 10% outliers) 4 m from a wall, shaken by
// 5 cm with terms up to about 2.7 Hz, 20 s: a velocity spline with knots every 0.5 s cannot
// follow the shake. The seeds are the suite's `parallax + focal_length` case's on seed shifts 1 and 2.
constexpr unsigned kShakeSeeds[] = {759513, 759514};
SimConfig hand_held_shake(unsigned seed) {
  SimConfig c = simulation(ObservationKind::Matches, seed, 20.0, 0.7);
  c.nominal.cam.width = 1920, c.nominal.cam.height = 1080;
  c.nominal.cam.fx = c.nominal.cam.fy = 1450, c.nominal.cam.cx = 959.5, c.nominal.cam.cy = 539.5;
  c.nominal.imu_to_camera << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  c.start_time_s = 1000;
  c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2, c.translation_amplitude_m = 0.05;
  c.gyro = {20, 200, 0.01, 0.03, 0.0005, 0.002};
  c.matches_per_pair = 120, c.outlier_fraction = 0.1;
  c.unmodelled.scene_depth_m = 4.0;
  return c;
}

TEST(Translation, AShakeFasterThanTheKnotsGetsFinerKnotsAndAFlightKeepsItsOwn) {
  // At the true model the chosen spline leaves the noise (within 10%: the gyro's gaps and
  // jitter), the default one three times as much.
  for (unsigned seed : kShakeSeeds) {
    const SimulatedRecording sim = simulate_recording(hand_held_shake(seed));
    const DiagnosisModel m(sim.rec);
    const auto all = every_observation(m);
    const double noise = 0.7 * m.noise_gain();
    ModelParams truth = nominal_params(sim.rec.nominal);
    truth.translation_nuisance = true;
    const double knots = translation_knot_spacing(m, all, truth);
    EXPECT_LT(knots, kTranslationKnotS) << "seed " << seed;
    EXPECT_GT(robust_stats(m.residuals(truth, all)).rms_px, 2 * noise) << "seed " << seed;
    truth.translation_knot_s = knots;
    EXPECT_NEAR(robust_stats(m.residuals(truth, all)).rms_px, noise, 0.1 * noise) << "seed " << seed << " knots " << knots;
  }
  // A vehicle's velocity changes over seconds: the default spline already leaves the noise.
  const SimulatedRecording flight = simulate_recording(forward_flight(8, 15.0));
  const DiagnosisModel m(flight.rec);
  EXPECT_EQ(translation_knot_spacing(m, every_observation(m), with_offset(flight, 0, true)), kTranslationKnotS);
}

// A focal length 1.8% long under that shake: the default spline left the shake to a mount
// rotation of 2 degrees, named beside the focal length (the first seed), or named nothing (the
// second: a gyro scale won the round and was dropped by the blocked halves).
TEST(Translation, AFocalLengthUnderAHandHeldShakeIsNamedAlone) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Translation.AShakeFasterThanTheKnotsGetsFinerKnotsAndAFlightKeepsItsOwn (the knots)");
  for (unsigned seed : kShakeSeeds) {
    SimConfig c = hand_held_shake(seed);
    c.effects.fxfy = Eigen::Vector2d(1476, 1476);
    const Diagnosis d = diagnose(DiagnosisModel(simulate_recording(c).rec));
    EXPECT_TRUE(d.parallax.clear()) << "seed " << seed;
    ASSERT_EQ(names(d), "focal_length ") << "seed " << seed;
    EXPECT_NEAR(param(find(d, "focal_length"), "fx"), 1476, 0.004 * 1476) << "seed " << seed;
    EXPECT_TRUE(d.remainder.significant) << "seed " << seed;
  }
}

// The suite's fifth seed of that shake: under the translation nuisance a gyro scale (about the
// pan's axes, like a focal length 2% long) beat the focal length by a BIC of 30, held on the
// blocked halves, and, with the camera's translation left in, predicted the held-out frames 13%
// worse than the nominal model: the final check then named nothing. Each round's winner is now
// asked that too (a paired test over the frame pairs): the gyro scale and a lens are refused,
// the focal length is named.
TEST(Translation, AStandInThatPredictsWorseWithTheParallaxInIsRefused) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Translation.AFocalLengthUnderAHandHeldShakeIsNamedAlone (the same fits)");
  SimConfig c = hand_held_shake(759516);
  c.effects.fxfy = Eigen::Vector2d(1476, 1476);
  std::vector<std::string> progress;
  DiagnosisOptions opt;
  opt.progress = [&](const std::string& p) { progress.push_back(p); };
  const Diagnosis d = diagnose(DiagnosisModel(simulate_recording(c).rec), opt);
  for (const std::string& p : progress) std::printf("  %s\n", p.c_str());
  ASSERT_EQ(names(d), "focal_length ");
  EXPECT_NEAR(param(find(d, "focal_length"), "fx"), 1476, 0.006 * 1476);
  EXPECT_TRUE(std::any_of(progress.begin(), progress.end(), [](const std::string& p) {
    return p.find("gyro_scale not named: with the camera's translation left in") != std::string::npos;
  }));
  EXPECT_LE(d.heldout_final_rms_px, d.heldout_baseline_rms_px);
}

}  // namespace
}  // namespace rsd::test
