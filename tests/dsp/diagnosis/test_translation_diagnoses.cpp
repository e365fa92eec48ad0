// Whole diagnoses under the translation nuisance (dsp/diagnosis/translation.hpp), each a minute
// or so on two cores (the complete suite's, label slow): a forward flight with a pan yields its
// clock offset over far, near and tilted scenes; a hand-held phone 4 m from a wall its focal
// length, lens, mount, clock offset and shutter (issue 34, point 2), also where the focal length
// and the lens stand in for each other alone; a focal length under a
// shake faster than the default knots is named alone; a stand-in that predicts the held-out
// frames worse with the parallax in is refused (the phone's lens alone).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "dsp/diagnosis/diagnosis.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"
#include "tests/dsp/diagnosis/translation_cases.hpp"
#include "tests/support/sanitizer.hpp"

namespace rsd::test {
namespace {

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
    const DiagnosisModel m(sim.rec);
    const Diagnosis d = diagnose(m);
    EXPECT_TRUE(d.parallax.clear()) << k.depth_m;
    EXPECT_EQ(names(d), "time_offset ") << "depth " << k.depth_m << " focal " << k.focal_px;
    // The held-out comparison takes each held-out pair's translation out, as the offset was
    // fitted; with the parallax in (the rotation model's own residuals) the same frames leave more.
    EXPECT_TRUE(d.heldout_nominal.translation_nuisance);
    EXPECT_DOUBLE_EQ(robust_stats(m.residuals(d.fitted, d.heldout_indices)).rms_px, d.heldout_with_parallax_final_rms_px);
    EXPECT_LT(d.heldout_final_rms_px, d.heldout_baseline_rms_px);
    EXPECT_LT(d.heldout_final_rms_px, 0.8 * d.heldout_with_parallax_final_rms_px) << "depth " << k.depth_m;
    const double offset = param(find(d, "time_offset"), "time_offset_s"), s = sigma(d, "time_offset", "time_offset_s");
    std::printf("depth %.0f m, focal %.0f px: offset %.4f ms +- %.4f ms\n", k.depth_m, k.focal_px, offset * 1e3, s * 1e3);
    EXPECT_NEAR(offset, 0.01, 1e-3) << "depth " << k.depth_m << " focal " << k.focal_px;
    // The sigma it reports is the fit's, with the translation taken out as the offset was
    // fitted: the truth within it, and it no wider than the millisecond asked (with the
    // parallax left in, a drone's came out ten times its seeds' scatter).
    EXPECT_NEAR(offset, 0.01, 4 * s) << "depth " << k.depth_m << " focal " << k.focal_px;
    EXPECT_LT(s, 0.5e-3) << "depth " << k.depth_m << " focal " << k.focal_px;
  }
}

// Issue 34's hand-held phone, simulated: 1080p, its nominal focal length 12% short (1330 px
// for 1510), a lens's distortion, the camera turned 1.2 degrees on its mount, a clock offset and
// a rolling shutter, hand-held 4 m from a wall (parallax in every pair). A free fy stood in for
// the shutter's vertical stretch (fx and fy 5% apart, refused), and a gyro scale 8% off came
// within 1% of the distortion and, winning, ended the selection: nothing named, 10 px left.
void expect_a_hand_held_phone_under_parallax(bool wall_fixed_in_world) {
  SimConfig c = simulation(ObservationKind::Matches, 5, 10.0, 1.5);
  c.nominal.cam.width = 1920, c.nominal.cam.height = 1080;
  c.nominal.cam.fx = c.nominal.cam.fy = 1330, c.nominal.cam.cx = 959.5, c.nominal.cam.cy = 539.5;
  c.nominal.imu_to_camera << 0, -1, 0, -1, 0, 0, 0, 0, -1;  // a phone's gyro axes
  c.start_time_s = 1000;
  c.rotation_amplitude_rad = 0.15, c.translation_amplitude_m = 0.03;
  c.matches_per_pair = 46, c.outlier_fraction = 0.05;
  c.gyro.noise_rad_s = 0.003, c.gyro.jitter_s = 0.0002;
  c.unmodelled.scene_depth_m = 4.0;
  c.unmodelled.scene_fixed_in_world = wall_fixed_in_world;
  c.effects.line_delay_s = 0.022 / 1080;
  c.effects.time_offset_s = 0.03;
  c.effects.fxfy = Eigen::Vector2d(1510, 1510);
  c.effects.k1k2 = Eigen::Vector2d(0.06, -0.02);
  c.effects.mount_rotation = Eigen::Vector3d(0.015, -0.012, 0.008);
  const SimulatedRecording sim = simulate_recording(c);
  const Diagnosis d = diagnose(DiagnosisModel(sim.rec));
  EXPECT_TRUE(d.parallax.clear());
  EXPECT_EQ(names(d), "focal_length lens_distortion mount_rotation rolling_shutter time_offset ");
  std::printf("wall %s: fx %.2f px (truth 1510), held out %.3f px\n", wall_fixed_in_world ? "fixed in the world" : "before each frame_a",
              param(find(d, "focal_length"), "fx"), d.heldout_final_rms_px);
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
  // The parallax left is said, and the held-out frames are predicted near the noise, the
  // parallax in.
  EXPECT_TRUE(d.remainder.significant);
  EXPECT_LT(d.heldout_with_parallax_final_rms_px, 1.15 * 1.5 * std::sqrt(2.0));
}

TEST(Translation, AHandHeldPhoneUnderParallaxYieldsItsFocalLengthLensAndMount) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Translation.AtTheTrueModelTheVelocitySplineLeavesTheNoise and TheVelocitySplineCannotTakeUpAClockOffset (the nuisance)");
  expect_a_hand_held_phone_under_parallax(false);
}

// The same before a wall fixed in the world, as a real one is: the nuisance's plane lies the
// same way before every frame_a, the wall's tilt in the camera follows the camera's turns (up
// to 0.15 rad here), so the nuisance does not meet it by construction.
TEST(Translation, AHandHeldPhoneBeforeAWallFixedInTheWorldYieldsItsFocalLengthLensAndMount) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("RecordingSimulation.AWallFixedInTheWorldComesNearerAsTheCameraApproachesIt (the wall) and Translation.AtTheTrueModelTheVelocitySplineLeavesTheNoise (the nuisance)");
  expect_a_hand_held_phone_under_parallax(true);
}

// The suite's hand-held phone (`outside: parallax + phone`), 12 s of it: its focal length 15%
// long and a barrel lens, a clock offset, a rolling shutter and a turned mount, under a 1.2 Hz
// shake past a wall 4 m away. Alone, the focal length stands in for the lens (about 30% off:
// refused as implausible) and the lens without it predicts the held-out frames worse with the
// parallax in (refused): each round ended with both refused, and neither was named (the named
// set was the mount, the shutter and the offset). The two are judged together (forward_selection.cpp,
// forward_pair), in the round that refused both, before the weaker winner of that round (the
// mount: named first, a gyro bias came in beside it as a stand-in before the pair, to go again
// later). The lens alone is still refused so:
// a stand-in that predicts the held-out frames worse with the parallax in. (That refusal was
// first shown on a gyro scale beating a focal length under the shake, seed 759519; since the
// frame pairs shift in time under a jittered gyro's stamps, no gyro scale wins on seeds
// 759505-759535, and the test moved here.)
TEST(Translation, AFocalLengthAndALensThatStandInForEachOtherAreNamedTogether) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Translation.AtTheTrueModelTheVelocitySplineLeavesTheNoise (the nuisance) and "
                              "DiagnosisInvariants.AnEffectThatAddsNothingHeldOutGivenTheOthersIsWithheld (the "
                              "selection's rounds); the pair step itself runs only here");
  SimConfig c = hand_held_shake(7);
  c.duration_s = 12.0;
  const double f = 1450 * 1.15;
  c.effects.fxfy = Eigen::Vector2d(f, f);
  c.effects.k1k2 = Eigen::Vector2d(-0.06, 0.0);
  c.effects.line_delay_s = 0.025 / 1080;
  c.effects.time_offset_s = 0.4;
  c.effects.mount_rotation = Eigen::Vector3d(0.6, -0.48, 0.64).normalized() * (M_PI / 180);
  std::vector<std::string> progress;
  DiagnosisOptions opt;
  opt.progress = [&](const std::string& p) { progress.push_back(p); };
  const Diagnosis d = diagnose(DiagnosisModel(simulate_recording(c).rec), opt);
  EXPECT_TRUE(d.parallax.clear());
  ASSERT_EQ(names(d), "focal_length lens_distortion mount_rotation rolling_shutter time_offset ");
  EXPECT_TRUE(std::any_of(progress.begin(), progress.end(), [](const std::string& p) {
    return p.find("lens_distortion not named: with the camera's translation left in") != std::string::npos;
  }));
  // The pair, far the stronger structure, is named in the round that refused both, before the
  // weaker mount that round had won (which, named first, left the pair for two rounds later).
  auto at = [&](const std::string& what) {
    return std::find_if(progress.begin(), progress.end(), [&](const std::string& p) { return p.find(what) == 0; }) -
           progress.begin();
  };
  EXPECT_LT(at("lens_distortion and focal_length, each refused alone, hold together"), at("named mount_rotation"));
  // Nor does a weak stand-in for part of the pair come in meanwhile (a gyro bias at 23, gone
  // again once the pair was in).
  EXPECT_EQ(std::count_if(progress.begin(), progress.end(),
                          [](const std::string& p) { return p.find("named in an earlier round") != std::string::npos; }),
            0);
  EXPECT_LE(d.heldout_final_rms_px, d.heldout_baseline_rms_px);
  const double fx = param(find(d, "focal_length"), "fx"), s = sigma(d, "focal_length", "fx");
  const Eigen::Vector3d r(param(find(d, "mount_rotation"), "rx"), param(find(d, "mount_rotation"), "ry"),
                          param(find(d, "mount_rotation"), "rz"));
  std::printf("focal %.2f px +- %.2f (truth %.2f); k1 %.4f; offset %.3f ms; mount error %.2f mrad\n", fx, s, f,
              param(find(d, "lens_distortion"), "k1"), param(find(d, "time_offset"), "time_offset_s") * 1e3,
              (r - *c.effects.mount_rotation).norm() * 1e3);
  EXPECT_NEAR(fx, f, 4 * s);
  EXPECT_LT(s, 0.005 * f);
  EXPECT_NEAR(param(find(d, "lens_distortion"), "k1"), -0.06, 0.006);
  EXPECT_NEAR(param(find(d, "rolling_shutter"), "frame_readout_s"), 0.025, 0.0025);
  EXPECT_NEAR(param(find(d, "time_offset"), "time_offset_s"), 0.4, 0.5e-3);
  EXPECT_LT((r - *c.effects.mount_rotation).norm(), 0.004);
}

// A focal length 1.8% long under that shake: the default spline left the shake to a mount
// rotation of 2 degrees, named beside the focal length (the first seed), or named nothing (the
// second: a gyro scale won the round and was dropped by the blocked halves). Before a wall fixed
// in the world, as a hand-held camera's is: the nuisance's plane is fixed in the world there,
// and with the gyro's orientation carried across its gaps (the irregular gyro drops samples for
// up to a second) whole frames' planes were off by pixels and a mount of 7 mrad was named beside
// the focal length on the first seed.
TEST(Translation, AFocalLengthUnderAHandHeldShakeIsNamedAlone) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Translation.AtTheTrueModelTheVelocitySplineLeavesTheNoise and TheVelocitySplineCannotTakeUpAClockOffset (the nuisance)");
  for (unsigned seed : kShakeSeeds) {
    SimConfig c = hand_held_shake(seed);
    c.effects.fxfy = Eigen::Vector2d(1476, 1476);
    c.unmodelled.scene_fixed_in_world = true;
    const Diagnosis d = diagnose(DiagnosisModel(simulate_recording(c).rec));
    EXPECT_TRUE(d.parallax.clear()) << "seed " << seed;
    ASSERT_EQ(names(d), "focal_length ") << "seed " << seed;
    EXPECT_NEAR(param(find(d, "focal_length"), "fx"), 1476, 0.004 * 1476) << "seed " << seed;
    EXPECT_TRUE(d.remainder.significant) << "seed " << seed;
  }
}

}  // namespace
}  // namespace rsd::test
