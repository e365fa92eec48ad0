// rsd-diagnose's dsp core against the simulator's ground truth: small landmarks recordings
// (640x480, 1 s at 30 fps, a 5x6 target, 0.5 px noise) with known effects switched on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "dsp/diagnosis/diagnosis.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"

using namespace rsd::dsp;
using rsd::test::find;
using rsd::test::names;
using rsd::test::param;

namespace {

SimConfig small_landmarks(unsigned seed) {
  SimConfig c = rsd::test::simulation(ObservationKind::Landmarks, seed, 1.0, 0.5);
  rsd::test::small_target(c);
  return c;
}

}  // namespace

TEST(Diagnosis, RobustStatsIgnoreOutliersAndCountThem) {
  std::vector<Eigen::Vector2d> r(100, Eigen::Vector2d(0.5, -0.5));
  r.push_back(Eigen::Vector2d(100, 0));
  r.push_back(Eigen::Vector2d(NAN, NAN));
  const RobustStats s = robust_stats(r);
  EXPECT_EQ(s.observations, 102);
  EXPECT_EQ(s.outliers, 2);
  EXPECT_NEAR(s.rms_px, 0.5, 1e-12);
}

TEST(Diagnosis, NominalModelReproducesNoiseFreeData) {
  SimConfig c = small_landmarks(1);
  c.noise_px = 0;
  const SimulatedRecording sim = simulate_recording(c);
  const DiagnosisModel m(sim.rec);
  std::vector<int> all(m.size());
  for (int i = 0; i < m.size(); ++i) all[i] = i;
  ASSERT_GT(m.size(), 500);
  EXPECT_LT(robust_stats(m.residuals(nominal_params(sim.rec.nominal), all)).rms_px, 1e-6);
}

TEST(Diagnosis, NoEffectNamesNothing) {
  const SimulatedRecording sim = simulate_recording(small_landmarks(2));
  const Diagnosis d = diagnose(sim.rec);
  EXPECT_TRUE(d.effects.empty()) << names(d);
  EXPECT_NEAR(d.baseline.rms_px, 0.5, 0.05);
  EXPECT_NEAR(d.heldout_final_rms_px, 0.5, 0.08);
}

TEST(Diagnosis, RollingShutterAloneWithinThreePercent) {
  SimConfig c = small_landmarks(3);
  const double truth = 5e-5;  // 24 ms readout
  c.effects.line_delay_s = truth;
  const Diagnosis d = diagnose(simulate_recording(c).rec);
  ASSERT_EQ(d.effects.size(), 1u) << names(d);
  ASSERT_EQ(d.effects[0].name, "rolling_shutter");
  const double got = param(&d.effects[0], "line_delay_s");
  std::printf("rolling_shutter: line_delay_s %.4g (truth %.4g), baseline %.3f px, final %.3f px\n", got, truth,
              d.baseline.rms_px, d.final_rms_px);
  EXPECT_NEAR(got, truth, 0.03 * truth);
  EXPECT_NEAR(param(&d.effects[0], "frame_readout_s"), truth * 480, 0.03 * truth * 480);
  // Chosen by the held-out frames too: the effect must predict them better than the nominal model.
  EXPECT_GT(d.effects[0].heldout_drop, 100.0);
  EXPECT_GT(d.baseline.rms_px, 2.0);
  EXPECT_LT(d.final_rms_px, 0.6);
  EXPECT_LT(d.heldout_final_rms_px, 0.65);
  ASSERT_FALSE(d.located.empty());
  EXPECT_EQ(d.located[0].signal, "row");
  // Rows, not columns, are read at different times.
  for (const auto& l : d.located) EXPECT_NE(l.signal, "column") << l.strength;
}

void expect_offset(double truth, unsigned seed) {
  SimConfig c = small_landmarks(seed);
  c.effects.time_offset_s = truth;
  const Diagnosis d = diagnose(simulate_recording(c).rec);
  ASSERT_EQ(d.effects.size(), 1u) << names(d);
  ASSERT_EQ(d.effects[0].name, "time_offset");
  const double got = param(&d.effects[0], "time_offset_s");
  std::printf("time_offset: %.6f s (truth %.6f), final %.3f px\n", got, truth, d.final_rms_px);
  EXPECT_NEAR(got, truth, 5e-4);
  EXPECT_LT(d.heldout_final_rms_px, 0.65);
}

TEST(Diagnosis, SmallTimeOffsetWithinHalfMillisecond) { expect_offset(0.004, 4); }
TEST(Diagnosis, LargeTimeOffsetFoundByGlobalSearch) { expect_offset(0.3, 5); }

TEST(Diagnosis, RollingShutterAndTimeOffsetTogether) {
  SimConfig c = small_landmarks(6);
  c.effects.line_delay_s = 4e-5;
  c.effects.time_offset_s = -0.01;
  const Diagnosis d = diagnose(simulate_recording(c).rec);
  EXPECT_EQ(d.effects.size(), 2u) << names(d);
  const NamedEffect* rs = find(d, "rolling_shutter");
  const NamedEffect* to = find(d, "time_offset");
  ASSERT_TRUE(rs && to) << names(d);
  std::printf("together: line_delay_s %.4g (truth 4e-05), time_offset_s %.6f (truth -0.01)\n",
              param(rs, "line_delay_s"), param(to, "time_offset_s"));
  EXPECT_NEAR(param(rs, "line_delay_s"), 4e-5, 0.03 * 4e-5);
  EXPECT_NEAR(param(to, "time_offset_s"), -0.01, 5e-4);
  EXPECT_LT(d.final_rms_px, 0.6);
}
