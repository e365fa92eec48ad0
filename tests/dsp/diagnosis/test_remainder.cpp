// The remainder test (dsp/diagnosis/remainder.hpp) against simulations whose truth is known:
// recordings that the model explains exactly (the true parameters given) must come out as
// noise, whatever the motion data's own errors; physics the effect table lacks (parallax in
// matches, a gyro that saturates, a clock that jumps, a smooth field across the image, whole
// frames the model does not predict) must come out as significant structure, located where it
// lives; mismatches scattered over the frames, however many, are not.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "dsp/diagnosis/diagnosis.hpp"
#include "dsp/diagnosis/parallax.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"
#include "tests/dsp/diagnosis/twin_matches.hpp"
#include "tests/support/sanitizer.hpp"

using namespace rsd::dsp;

namespace test_remainder {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

// Like the phone: a 1450 px camera, an irregular gyro with jittered, repeated and missing
// stamps, 10% outliers.
SimConfig phone(unsigned seed, double duration_s = 10) {
  SimConfig c = rsd::test::simulation(ObservationKind::Matches, seed, duration_s, 0.7);
  c.nominal.cam.width = 1920, c.nominal.cam.height = 1080;
  c.nominal.cam.cx = 959.5, c.nominal.cam.cy = 539.5;
  c.nominal.cam.fx = c.nominal.cam.fy = 1450;
  c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2;
  c.nominal.imu_to_camera << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  c.gyro = {20, 200, 0.01, 0.03, 0.0005, 0.002};
  c.matches_per_pair = 120;
  c.outlier_fraction = 0.1;
  return c;
}

// The phone at `noise_px` with a clean gyro and no outliers: at the truth the residual is the
// pixels' noise alone.
SimConfig clean_phone(unsigned seed, double noise_px) {
  SimConfig c = phone(seed);
  c.noise_px = noise_px;
  c.gyro = {200, 200, 0, 0, 0, 0};
  c.outlier_fraction = 0;
  return c;
}

SimConfig target(unsigned seed, double duration_s = 10) { return rsd::test::target_simulation(seed, duration_s, 0.5); }

// The remainder of the nominal model (the truth: no table effect is switched on), over the
// observations the gyro covers, as the diagnosis assesses it (a frame pair inside a gap of the
// phone's gyro, up to 20 samples missing, is not predicted and never fitted).
Remainder at_truth(const SimulatedRecording& sim) {
  const DiagnosisModel m(sim.rec);
  const ModelParams p = nominal_params(sim.rec.nominal);
  const double floor = *sim.rec.noise_px * m.noise_gain();
  std::vector<int> covered;
  for (int i : rsd::test::every_observation(m))
    if (!m.has_gyro() || m.gyro_gap(p, i) <= m.max_gyro_gap()) covered.push_back(i);
  const Remainder r = assess_remainder(m, p, covered, floor, floor);
  std::printf("rms %.3f expected %.3f stated %.3f | spatial ratio %.3f z %.1f | temporal ratio %.3f z %.1f | %s\n",
              r.rms_px, r.expected_rms_px, r.stated_noise_px, r.spatial_ratio, r.spatial_z, r.temporal_ratio,
              r.temporal_z, r.summary.c_str());
  for (const auto& l : r.located) std::printf("  located %s %.3f\n", l.signal.c_str(), l.strength);
  return r;
}

bool located(const Remainder& r, const std::string& signal) {
  for (const auto& l : r.located)
    if (l.signal == signal) return true;
  return false;
}

}  // namespace

TEST(Remainder, NoiseAloneIsNotSignificant) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Remainder lm = at_truth(simulate_recording(target(seed))), mt = at_truth(simulate_recording(phone(seed)));
    EXPECT_FALSE(lm.significant) << "landmarks seed " << seed;
    EXPECT_FALSE(mt.significant) << "matches seed " << seed;
    EXPECT_EQ(mt.lost_frames, 0) << "matches seed " << seed;  // 10% mismatches: none lost whole
  }
}

TEST(Remainder, ExpectedRmsIsTheNoise) {
  const Remainder lm = at_truth(simulate_recording(target(4)));
  EXPECT_NEAR(lm.expected_rms_px, 0.5, 0.03);
  SimConfig clean = phone(4);
  clean.gyro = {200, 200, 0, 0, 0, 0};
  const Remainder mt = at_truth(simulate_recording(clean));
  EXPECT_NEAR(mt.expected_rms_px, 0.7 * std::sqrt(2.0), 0.05);
}

TEST(Remainder, ParallaxInMatchesIsStructureAndTranslation) {
  SimConfig c = phone(5);
  c.unmodelled.scene_depth_m = 3.0;
  c.translation_amplitude_m = 0.1;
  const Remainder r = at_truth(simulate_recording(c));
  EXPECT_TRUE(r.significant);
  EXPECT_TRUE(located(r, "translation"));
}

// Parallax is clear only at the instrument's own bias (instrument.hpp): over thousands of matches
// at 0.01 px of noise a hand's shake past a wall 3 m away of 0.1 mm (its flow beyond a rotation's
// well under 0.03 px) is clear by z and share, as a tracker's own field on an independent
// renderer's pictures was, and is not called a near scene's; thirty times the shake is. What it
// takes beyond the rotation grows with the shake as flow does, thirtyfold (net of noise).
TEST(Remainder, ParallaxUnderTheInstrumentsOwnBiasIsNotClear) {
  auto parallax = [](double shake_m) {
    SimConfig c = clean_phone(26, 0.01);
    c.unmodelled.scene_depth_m = 3.0;
    c.translation_amplitude_m = shake_m;
    const SimulatedRecording sim = simulate_recording(c);
    const DiagnosisModel m(sim.rec);
    const Parallax px = parallax_signal(m, nominal_params(sim.rec.nominal), rsd::test::every_observation(m));
    std::printf("shake %g m: z %.1f share %.3f rms %.4f px\n", shake_m, px.z, px.share, px.rms_px);
    return px;
  };
  const Parallax small = parallax(1e-4), large = parallax(3e-3);
  EXPECT_GT(small.z, 4);
  EXPECT_GT(small.share, 0.05);
  EXPECT_LT(small.rms_px, kInstrumentBiasPx);
  EXPECT_FALSE(small.clear());
  EXPECT_TRUE(large.clear());
  EXPECT_NEAR(large.rms_px / small.rms_px, 30, 3);
}

// Five minutes of the same parallax, 20 matches a pair (180 000): an even 20 000 of them left
// each frame one or two, too few to compare with its neighbours, and the remainder was called
// noise (the suite's walk over ten minutes: 3.01 px against 0.99). Whole runs of frames are
// assessed instead.
TEST(Remainder, ParallaxOverThousandsOfFramesIsStructureToo) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Remainder.ParallaxInMatchesIsStructureAndTranslation (the same remainder over 10 s)");
  SimConfig c = phone(5, 300);
  c.unmodelled.scene_depth_m = 3.0;
  c.translation_amplitude_m = 0.1;
  c.matches_per_pair = 20;
  const SimulatedRecording sim = simulate_recording(c);
  ASSERT_GT(sim.rec.matches.size(), 150000u);
  const Remainder r = at_truth(sim);
  EXPECT_TRUE(r.significant);
  EXPECT_TRUE(located(r, "translation"));
}

TEST(Remainder, SaturatedGyroIsStructure) {
  SimConfig c = phone(6);
  c.unmodelled.gyro_saturation_rad_s = 1.0;
  const Remainder r = at_truth(simulate_recording(c));
  EXPECT_TRUE(r.significant);
  EXPECT_TRUE(r.temporal);
  // Located to the angular rate: the frames of fastest rotation, from the rate it clips at.
  ASSERT_FALSE(r.located.empty());
  EXPECT_EQ(r.located.front().signal, "fast_rotation");
  EXPECT_NE(r.located.front().detail.find("from 1 rad/s"), std::string::npos) << r.located.front().detail;
}

// Whole frames the model does not predict: every match of one frame pair in twelve, in bursts of
// three pairs (a gyro that clips through the fastest part of a swing), displaced by 6-10 px, a
// direction of its own per pair. Those matches all fall outside the inlier rule, so the tests of
// the inliers see nothing; the whole-frames test sees frames that are mostly outliers where the
// 10% of mismatches elsewhere make none.
TEST(Remainder, WholeFramesTheModelDoesNotPredictAreStructure) {
  SimulatedRecording sim = simulate_recording(phone(9));
  int displaced = 0;
  for (int f = 0; f < static_cast<int>(sim.rec.frames.size()); ++f) {
    if (f % 36 >= 3) continue;
    ++displaced;
    const double angle = 2.1 * f, size = 6 + 4 * std::abs(std::sin(0.7 * f));
    for (Match& mt : sim.rec.matches)
      if (mt.frame_a == f) mt.b += size * Eigen::Vector2d(std::cos(angle), std::sin(angle));
  }
  const Remainder r = at_truth(sim);
  std::printf("lost %d of %d frames (%d displaced), %.2f expected, z %.1f, share %.3f\n", r.lost_frames, r.tested_frames,
              displaced, r.lost_expected, r.lost_z, r.lost_share);
  EXPECT_TRUE(r.significant);
  EXPECT_TRUE(r.lost);
  EXPECT_FALSE(r.spatial);
  // Pairs inside the gyro's gaps are not assessed (a fifth of them here); no other pair is lost.
  EXPECT_GE(r.lost_frames, displaced * 3 / 5);
  EXPECT_LE(r.lost_frames, displaced);
  EXPECT_LT(r.lost_expected, 1.0);
  EXPECT_TRUE(located(r, "lost_frames"));
  EXPECT_NE(r.summary.find("mostly outliers"), std::string::npos) << r.summary;
}

// Mismatches in plenty but scattered: 40% of every pair's matches drawn at random. Frames lost by
// chance are as many as the binomial says, and that is noise.
TEST(Remainder, ManyMismatchesScatteredOverTheFramesAreNoise) {
  SimConfig c = phone(10);
  c.outlier_fraction = 0.4;
  const Remainder r = at_truth(simulate_recording(c));
  std::printf("lost %d of %d frames, %.2f expected, z %.1f\n", r.lost_frames, r.tested_frames, r.lost_expected, r.lost_z);
  EXPECT_FALSE(r.lost);
  EXPECT_FALSE(r.significant);
  EXPECT_LT(std::abs(r.lost_frames - r.lost_expected), 4 * std::sqrt(r.lost_expected + 1));
}

TEST(Remainder, ClockJumpIsStructure) {
  for (ObservationKind k : {ObservationKind::Matches, ObservationKind::Landmarks}) {
    SimConfig c = k == ObservationKind::Matches ? phone(7) : target(7);
    c.unmodelled.clock_jump_s = 3e-3, c.unmodelled.clock_jump_at_s = 5;
    const Remainder r = at_truth(simulate_recording(c));
    EXPECT_TRUE(r.significant) << to_string(k);
    EXPECT_TRUE(r.temporal) << to_string(k);
    // Not taken for a gyro that clips: the jump's residual follows the image motion after it.
    ASSERT_FALSE(r.located.empty()) << to_string(k);
    EXPECT_NE(r.located.front().signal, "fast_rotation") << to_string(k);
  }
}

TEST(Remainder, SmoothFieldAcrossTheImageIsSpatial) {
  SimulatedRecording sim = simulate_recording(target(8));
  // A field no effect of the table makes: a ripple across the columns, 0.6 px.
  for (auto& o : sim.rec.observations) o.px.y() += 0.6 * std::sin(2 * M_PI * o.px.x() / 640 * 1.5);
  const Remainder r = at_truth(sim);
  EXPECT_TRUE(r.significant);
  EXPECT_TRUE(r.spatial);
  EXPECT_FALSE(r.temporal);
}

// Issue 34, point 6: a residual 14% above the expected noise (RMS) over thousands of matches is
// structure, not noise; the same field carried by a few hundred matches is not clear (the test's
// significance grows with the observations that carry it: a z-score on their count). Below a
// tenth above the noise (a fifth in variance) no structure is called material, however many
// observations carry it: a gyro's jittered stamps leave fields of that size within each frame.
TEST(Remainder, AFewPercentAboveTheNoiseIsStructureOverThousandsOfMatches) {
  auto with_ripple = [](unsigned seed, double duration_s, int per_pair) {
    SimConfig c = phone(seed, duration_s);
    c.gyro = {200, 200, 0, 0, 0, 0};  // a clean gyro: the expected noise is the pixels' alone
    c.outlier_fraction = 0;
    c.matches_per_pair = per_pair;
    SimulatedRecording sim = simulate_recording(c);
    // Variance A^2 / 4 per coordinate: 31% of the noise's 0.98 px^2 for A = 1.1 px, 14% in RMS.
    for (auto& mt : sim.rec.matches) mt.b.y() += 1.1 * std::sin(2 * M_PI * mt.b.x() / 1920 * 1.5);
    return sim;
  };
  const SimulatedRecording many = with_ripple(21, 10, 120), few = with_ripple(22, 1, 10);
  ASSERT_GT(many.rec.matches.size(), 30000u);
  ASSERT_LT(few.rec.matches.size(), 400u);
  const Remainder r_many = at_truth(many), r_few = at_truth(few);
  EXPECT_NEAR(r_many.rms_px / r_many.expected_rms_px, 1.14, 0.04);
  EXPECT_TRUE(r_many.significant);
  EXPECT_TRUE(r_many.spatial);
  EXPECT_FALSE(r_few.significant);
}

// Structure under the instrument's own bias (instrument.hpp) is said, not called physics: a
// tracker's errors hold a field of about 0.02 px of their own, which pictures tracked to 0.04 px
// (an independent renderer's, docs/diagnosis.md) show clearly over thousands of matches. Here a
// clean recording at 0.02 px of noise a coordinate at each end (0.028 px in a match's residual)
// with a ripple across the columns of amplitude A on v alone (A / 2 per coordinate, RMS): at
// 0.02 px, half the noise's variance, the remainder is noise and says the 0.02 px; at 0.05 px,
// beyond the bias, it is structure.
TEST(Remainder, AFieldUnderTheInstrumentsOwnBiasIsSaidNotCalledPhysics) {
  auto with_ripple = [](double amplitude_px) {
    SimulatedRecording sim = simulate_recording(clean_phone(25, 0.02));
    for (auto& mt : sim.rec.matches) mt.b.y() += amplitude_px * std::sin(2 * M_PI * mt.b.x() / 1920 * 1.5);
    return at_truth(sim);
  };
  const Remainder under = with_ripple(0.04), over = with_ripple(0.10);
  EXPECT_FALSE(under.significant);
  EXPECT_NEAR(under.instrument_px, 0.02, 0.004);
  EXPECT_NE(under.summary.find("own bias"), std::string::npos) << under.summary;
  EXPECT_TRUE(over.significant);
  EXPECT_TRUE(over.spatial);
  EXPECT_NEAR(over.spatial_rms_px, 0.05, 0.008);
  EXPECT_EQ(over.instrument_px, 0.0);
}

// A tracker's corners come in clusters (rsd-extract's rendered checkerboard: most features had a
// twin 8-10 px away, inside the same 21 px window) and a twin's error follows its own: the
// differences between nearest neighbours then understate the noise, and noise reads as a smooth
// field. Here every match has a twin 8 px to its right whose error correlates 0.5 with its own
// (the same variance): the nearest-twin differences would put the noise at 0.71 of the truth
// and the spatial ratio at 2. Measured against neighbours too far apart to share a window, the
// remainder is noise and its expected RMS the noise's.
TEST(Remainder, TwinMatchesWhoseErrorsCorrelateAreNoise) {
  SimConfig c = phone(23);
  c.gyro = {200, 200, 0, 0, 0, 0};  // a clean gyro: at the truth the residual is the pixels' noise
  c.outlier_fraction = 0;
  c.matches_per_pair = 60;
  SimulatedRecording sim = simulate_recording(c);
  const double sigma = rsd::test::add_correlated_twins(sim, 0.5, 5);
  const Remainder rem = at_truth(sim);
  EXPECT_FALSE(rem.significant);
  EXPECT_LT(rem.spatial_ratio, 1.15);
  EXPECT_NEAR(rem.expected_rms_px / sigma, 1.0, 0.06);
}

// A tracker's errors have tails: rsd-sim's 1080p rendering, tracked, erred by 0.049 px (robust
// scale) with an RMS of 0.068 px within the inlier bound. Here every match errs by a mixture
// (three in four at 0.5 px, one in four at 1.5 px): the remainder is noise, what noise alone
// leaves is said in the residual's own units (the RMS within the bound), and the nominal model
// fits within it. With the robust scale as the expectation the report said that the named
// effects had left a quarter of the mismatch unexplained and called it noise in the same breath.
// And a smooth field beneath such noise is found.
TEST(Remainder, HeavyTailedNoiseIsNoiseAndAFieldBeneathItIsFound) {
  SimConfig c = phone(24);
  c.gyro = {200, 200, 0, 0, 0, 0};
  c.outlier_fraction = 0;
  c.matches_per_pair = 60;
  SimulatedRecording sim = simulate_recording(c);
  const std::vector<int> all = rsd::test::every_observation(DiagnosisModel(sim.rec));
  const auto r = DiagnosisModel(sim.rec).residuals(nominal_params(sim.rec.nominal), all);
  std::mt19937 rng(7);
  std::normal_distribution<double> unit(0, 1);
  std::uniform_real_distribution<double> u(0, 1);
  for (size_t k = 0; k < all.size(); ++k) {
    const double s = u(rng) < 0.75 ? 0.5 : 1.5;
    sim.rec.matches[k].b += -r[k] + s * Eigen::Vector2d(unit(rng), unit(rng));
  }
  // Assessed as the diagnosis does when the recording states no noise and nothing is named.
  auto assess = [&](const SimulatedRecording& s) {
    const DiagnosisModel m(s.rec);
    const ModelParams p = nominal_params(s.rec.nominal);
    const double baseline = robust_stats(m.residuals(p, all)).rms_px;
    const Remainder rem = assess_remainder(m, p, all, 0.0, baseline);
    std::printf("rms %.3f expected %.3f | spatial ratio %.3f | %s\n", rem.rms_px, rem.expected_rms_px,
                rem.spatial_ratio, rem.summary.c_str());
    return rem;
  };
  const Remainder rem = assess(sim);
  EXPECT_FALSE(rem.significant);
  EXPECT_TRUE(rem.nothing_to_explain);
  EXPECT_NEAR(rem.rms_px / rem.expected_rms_px, 1.0, 0.05);
  // Both sides of the spatial test are differences of two errors, so the tails cancel from it
  // (set against the scatter about the frame mean the ratio was 0.74), and a ripple across the
  // columns with a third of the noise's variance (A^2 / 4 per coordinate) is found.
  EXPECT_NEAR(rem.spatial_ratio, 1.0, 0.1);
  for (auto& mt : sim.rec.matches) mt.b.y() += 0.8 * std::sin(2 * M_PI * mt.b.x() / 1920 * 1.5);
  const Remainder rippled = assess(sim);
  EXPECT_TRUE(rippled.significant);
  EXPECT_TRUE(rippled.spatial);
}

// A recording that understates its noise (0.3 px stated, 1 px real): BIC at the stated scale
// would take noise for effects. The selection ends at a scale far from the one it started from
// and runs again at the data's own; nothing is named, and the remainder is noise.
TEST(Remainder, UnderstatedNoiseRestartsTheSelectionAtTheDataScale) {
  SimConfig noisy = target(9, 6);
  noisy.noise_px = 1.0;
  SimulatedRecording sim = simulate_recording(noisy);
  sim.rec.noise_px = 0.3;
  const Diagnosis d = diagnose(sim.rec);
  std::printf("sigma %.3f px after %zu restart(s); named %zu\n", d.sigma_px, d.sigma_restarts.size(), d.effects.size());
  ASSERT_FALSE(d.sigma_restarts.empty());
  EXPECT_NEAR(d.sigma_restarts.front(), 0.3, 1e-12);
  EXPECT_NEAR(d.sigma_px, 1.0, 0.05);
  EXPECT_TRUE(d.effects.empty());
  EXPECT_FALSE(d.remainder.significant);
}

}  // namespace test_remainder
