// The clock's offset window by window (dsp/diagnosis/clock_shape.hpp) on simulated matches: a
// clock that jumps by 3 ms steps by that much where it jumped, though a drift fitted over the
// whole recording stands in for most of it; a real drift grows along a line at its rate, also
// when the camera translates past a near wall that the rotation-only model leaves out.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "dsp/diagnosis/clock_shape.hpp"
#include "dsp/diagnosis/fit.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"

using namespace rsd::dsp;

namespace {

// The clock's shape over 12 s of VGA matches, with p's clock drift fitted to the whole recording
// first (as the selection would have it when it names clock_drift).
struct Shaped {
  SimulatedRecording sim;
  DiagnosisModel m;
  double drift_ppm;
  ClockShape shape;
  explicit Shaped(SimulatedRecording recording) : sim(std::move(recording)), m(sim.rec) {
    const double sigma = 0.5 * m.noise_gain();
    const std::vector<int> idx = rsd::test::every_observation(m);
    ParamMask drift;
    drift.set(static_cast<size_t>(Param::Drift));
    const ModelParams p = fit_params(m, idx, nominal_params(sim.rec.nominal), drift, sigma);
    drift_ppm = p[Param::Drift];
    shape = clock_shape(m, p, idx, sigma);
  }
  // The windows' verdict, for the log.
  void print(const char* what) const {
    const LineOrStep& v = shape.verdict;
    std::printf("%s: drift fitted %.1f ppm; %zu windows: a line of %.1f ppm, chi2 %.1f; a step of %.2f ms at %.2f s, "
                "chi2 %.1f\n",
                what, drift_ppm, shape.windows.size(), v.line.slope * 1e6, v.line.chi2, (v.step.after - v.step.before) * 1e3,
                v.step.at - sim.rec.nominal.time.t0, v.step.chi2);
  }
};

SimConfig twelve_seconds(unsigned seed) {
  SimConfig c = rsd::test::simulation(ObservationKind::Matches, seed, 12.0, 0.5);
  c.matches_per_pair = 60;
  return c;
}

}  // namespace

TEST(ClockShape, AClockThatJumpsSteps) {
  SimConfig c = twelve_seconds(61);
  c.unmodelled.clock_jump_s = 3e-3, c.unmodelled.clock_jump_at_s = 7.0;
  const Shaped s(simulate_recording(c));
  const LineOrStep& v = s.shape.verdict;
  s.print("clock jump");
  EXPECT_GT(std::abs(s.drift_ppm), 100);  // a drift does stand in for it
  EXPECT_GE(s.shape.windows.size(), 10u);
  EXPECT_TRUE(v.is_step);
  // Frames stamped 3 ms late: the motion clock runs 3 ms behind their stamps from the jump on.
  EXPECT_NEAR(v.step.after - v.step.before, -3e-3, 3e-4);
  EXPECT_NEAR(v.step.at - s.sim.rec.nominal.time.t0, 7.0, 1.0);
}

TEST(ClockShape, ADriftGrowsAlongALine) {
  SimConfig c = twelve_seconds(62);
  c.effects.drift_ppm = 300;
  const Shaped s(simulate_recording(c));
  const LineOrStep& v = s.shape.verdict;
  s.print("clock drift 300 ppm");
  EXPECT_FALSE(v.is_step);
  EXPECT_NEAR(v.line.slope * 1e6, 300, 30);
}

TEST(ClockShape, ADriftPastAnUnmodelledWallIsStillALine) {
  SimConfig c = twelve_seconds(63);
  c.effects.drift_ppm = 300;
  c.unmodelled.scene_depth_m = 1.0;
  c.motion_source = MotionSource::Samples;
  for (double t = c.start_time_s - 1.5; t <= c.start_time_s + c.duration_s + 1.5; t += 1e-3) {
    PoseSample p;
    p.t = t;
    p.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.2 * std::sin(2 * M_PI * 1.3 * t), Eigen::Vector3d(0.3, 1, 0.2).normalized()));
    p.p = Eigen::Vector3d(0.05 * std::sin(2 * M_PI * 0.9 * t), 0.03 * std::sin(2 * M_PI * 1.1 * t), 0);
    c.pose_samples.push_back(p);
  }
  const Shaped s(simulate_recording(c));
  const LineOrStep& v = s.shape.verdict;
  s.print("clock drift 300 ppm past a wall 1 m away");
  EXPECT_FALSE(v.is_step);
}
