// The blocked halves (dsp/diagnosis/blocked_halves.hpp, issue 34 point 3): on simulated matches
// whose halves differ in motion, a real effect predicts the half it was not fitted on and both
// halves agree on its value; a clock that jumps half-way makes the clock offset a stand-in the
// halves put 3 ms apart, which the fits on each half, made here, confirm.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "dsp/diagnosis/blocked_halves.hpp"
#include "dsp/diagnosis/fit.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"

using namespace rsd::dsp;

namespace {

// A phone-like matches recording whose rotation swings by `first` rad in its first half and by
// `second` in its second (about one axis, at 1.3 Hz with a harmonic; the swing changes over the
// half second before the middle), 80 matches per pair.
SimConfig two_motions(unsigned seed, double first, double second) {
  SimConfig c = rsd::test::simulation(ObservationKind::Matches, seed, 6.0, 0.5);
  c.matches_per_pair = 80;
  c.motion_source = MotionSource::Samples;
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, 1.0, 0.2).normalized();
  for (double t = c.start_time_s - 1.5; t <= c.start_time_s + c.duration_s + 1.5; t += 1e-3) {
    const double s = std::clamp((t - c.start_time_s - 0.5 * c.duration_s + 0.5) / 0.5, 0.0, 1.0);
    const double amplitude = first + (second - first) * s;
    const double angle = amplitude * (std::sin(2 * M_PI * 1.3 * t) + 0.3 * std::sin(2 * M_PI * 2.9 * t + 1.0));
    PoseSample p;
    p.t = t;
    p.q = Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis));
    p.p = Eigen::Vector3d::Zero();
    c.pose_samples.push_back(p);
  }
  return c;
}

ParamMask only(Param p) {
  ParamMask m;
  m.set(static_cast<size_t>(p));
  return m;
}

// A recording (kept: the model refers to it), its model, 6000 of its observations split in
// time, its nominal parameters and noise.
struct Split {
  SimulatedRecording sim;
  DiagnosisModel m;
  Halves h;
  ModelParams nominal;
  double sigma;
  explicit Split(SimulatedRecording recording)
      : sim(std::move(recording)), m(sim.rec), h(time_halves(m, subsample(rsd::test::every_observation(m), 6000))),
        nominal(nominal_params(sim.rec.nominal)), sigma(0.5 * m.noise_gain()) {}
};

}  // namespace

TEST(BlockedHalves, HalvesThatDifferInMotionAgreeOnARealEffect) {
  SimConfig c = two_motions(41, 0.25, 0.08);
  c.effects.line_delay_s = 2.5e-5;
  const Split s(simulate_recording(c));
  ASSERT_TRUE(s.h.usable());
  const HalvesVerdict v = cross_check(s.m, s.h, {s.nominal, {}}, {s.nominal, only(Param::LineDelay)}, s.sigma, 8);
  std::printf("rolling shutter: drop %.1f, halves %.2f sigmas apart\n", v.drop, v.apart_sigmas);
  EXPECT_GT(v.drop, 0);
  EXPECT_GT(v.apart_sigmas, 0);  // both halves move: each measures it
  EXPECT_LT(v.apart_sigmas, kHalvesAgreeSigmas);
}

TEST(BlockedHalves, AClockThatJumpsPutsTheOffsetApart) {
  SimConfig c = two_motions(42, 0.25, 0.25);
  c.unmodelled.clock_jump_s = 3e-3, c.unmodelled.clock_jump_at_s = 3.0;
  const Split s(simulate_recording(c));
  ASSERT_TRUE(s.h.usable());
  // Each half's own offset, fitted here: the jump between them.
  const double a = fit_params(s.m, s.h.a, s.nominal, only(Param::TimeOffset), s.sigma)[Param::TimeOffset];
  const double b = fit_params(s.m, s.h.b, s.nominal, only(Param::TimeOffset), s.sigma)[Param::TimeOffset];
  EXPECT_NEAR(std::abs(b - a), 3e-3, 3e-4);
  const HalvesVerdict v = cross_check(s.m, s.h, {s.nominal, {}}, {s.nominal, only(Param::TimeOffset)}, s.sigma, 8);
  std::printf("time offset under a clock jump: halves at %.3f and %.3f ms, %.1f sigmas apart (drop %.1f)\n", a * 1e3,
              b * 1e3, v.apart_sigmas, v.drop);
  EXPECT_GT(v.apart_sigmas, 2 * kHalvesAgreeSigmas);
}
