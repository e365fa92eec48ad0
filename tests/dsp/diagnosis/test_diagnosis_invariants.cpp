// The invariants every diagnosis keeps (issue 34), each against a recording built to break it:
// (a) the final model predicts the held-out frames no worse than the nominal model, else nothing
// is named and the remainder says why; (b) no named value is implausible for real hardware or
// sits on its fit's bound; (c) each named effect, given the others, improves the held-out
// prediction on its own; and no effect is named that moves the predictions less than an
// instrument's own bias. Ground truth: the simulator's hidden physics, and a recording whose
// held-out frames were made with other physics than the frames the fit sees.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "dsp/diagnosis/diagnosis.hpp"
#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/select.hpp"
#include "dsp/diagnosis/uncertainty.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"
#include "tests/support/sanitizer.hpp"

using namespace rsd::dsp;
using rsd::test::names;
using rsd::test::said;
using rsd::test::shaken;
using rsd::test::show;

namespace {

// `sim`'s recording with the matches of its held-out frames (every fifth frame_a, as the
// diagnosis holds them out) taken from `other` instead: frames no fit sees, made with other
// physics.
void hold_out_other_physics(SimulatedRecording& sim, const SimulatedRecording& other, int from_frame = 0) {
  std::set<int> held_frames;
  {
    const DiagnosisModel m(sim.rec);
    for (int i = 0; i < m.size(); ++i)
      if (held_out(m, i, kHeldoutEvery) && sim.rec.matches[i].frame_a >= from_frame) held_frames.insert(sim.rec.matches[i].frame_a);
  }
  ASSERT_GT(held_frames.size(), 10u);
  std::vector<Match> mixed;
  for (const Match& mt : sim.rec.matches)
    if (!held_frames.count(mt.frame_a)) mixed.push_back(mt);
  for (const Match& mt : other.rec.matches)
    if (held_frames.count(mt.frame_a)) mixed.push_back(mt);
  sim.rec.matches = mixed;
}

// Diagnosed, nothing is named, the fitted model is the nominal one, and the remainder says why
// (`why`, a part of the reason).
void expect_withdrawn_saying(const SimulatedRecording& sim, const std::string& why) {
  const Diagnosis d = diagnose(sim.rec);
  show(d);
  EXPECT_EQ(names(d), "");
  EXPECT_TRUE(said(d, why)) << "the remainder must say why: " << why;
  EXPECT_EQ(d.fitted[Param::TimeOffset], sim.rec.nominal.time.time_offset_s);
  EXPECT_EQ(d.heldout_final_rms_px, d.heldout_baseline_rms_px);
}

}  // namespace

// A gyro reading 1.6 times the true rates: a scale of 0.625 (37.5% off, and a focal length as
// far off could stand in for it): no MEMS gyro or lens is that wrong, so neither is named, and
// the remainder says why.
TEST(DiagnosisInvariants, AnImplausibleScaleIsNeverNamedNorAStandInForIt) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("DiagnosisMountScale.ConcealedMountRotationInLandmarks (the same mount and scale parameters)");
  SimConfig c = shaken(31);
  c.effects.gyro_scale = Eigen::Vector3d::Constant(0.625);
  const Diagnosis d = diagnose(simulate_recording(c).rec);
  show(d);
  EXPECT_EQ(names(d).find("gyro_scale"), std::string::npos);
  EXPECT_EQ(names(d).find("focal_length"), std::string::npos);
  EXPECT_TRUE(said(d, "gyro_scale not named: a gyro scale")) << "the remainder must say why";
  EXPECT_NE(d.remainder.summary.find("not named"), std::string::npos) << d.remainder.summary;
  EXPECT_LE(d.heldout_final_rms_px, d.heldout_baseline_rms_px);
}

// The fit's frames hide a clock offset of +8 ms; the held-out frames (every fifth) were made
// with -8 ms. The offset the fitting frames show predicts the held-out frames worse than the
// nominal model: nothing is named, the fitted model is the nominal one, and the remainder says
// why. (Each selection round asks the held-out frames; the final model is asked again.)
TEST(DiagnosisInvariants, EffectsThatPredictTheHeldOutFramesWorseAreWithdrawn) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("DiagnosisMatches.NoEffectNamesNothingDespiteOutliersAndIrregularGyro (the same fits)");
  SimConfig a = shaken(32), b = shaken(32);
  a.effects.time_offset_s = 0.008;
  b.effects.time_offset_s = -0.008;
  SimulatedRecording sim = simulate_recording(a);
  hold_out_other_physics(sim, simulate_recording(b));
  expect_withdrawn_saying(sim, "the held-out frames worse");
}

// Invariant (a) half by half: the fitting frames and the held-out frames of the first half in
// time hide a clock offset of 8 ms, the held-out frames of the second half one of 3 ms. The offset
// fitted predicts the held-out frames better in all (the first half's gain outweighs the second's
// loss) but the second half worse than the nominal model: it describes part of the recording
// only, nothing is named, and the remainder says which half.
TEST(DiagnosisInvariants, EffectsThatPredictOneHalfOfTheHeldOutFramesWorseAreWithdrawn) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("DiagnosisMatches.NoEffectNamesNothingDespiteOutliersAndIrregularGyro (the same fits and checks)");
  SimConfig a = shaken(34), b = shaken(34);
  a.effects.time_offset_s = 0.008;
  b.effects.time_offset_s = 0.003;
  SimulatedRecording sim = simulate_recording(a);
  std::vector<int> frames;
  for (const Match& mt : sim.rec.matches) frames.push_back(mt.frame_a);
  std::nth_element(frames.begin(), frames.begin() + frames.size() / 2, frames.end());
  hold_out_other_physics(sim, simulate_recording(b), frames[frames.size() / 2]);
  // Measured: the second half 0.82 -> 0.98 px, 6.9 standard errors over its 12 frame pairs.
  expect_withdrawn_saying(sim, "second half in time worse");
}

// Invariant (c): each named effect, given the others, improves the held-out prediction on its
// own. The fit's frames hide a rolling shutter and a lens distortion; the held-out frames the
// same rolling shutter through a lens without distortion. A selection naming both (both hold on
// the blocked halves, which are cut from the fitting frames) keeps the rolling shutter, which
// predicts the held-out frames better, and withholds the distortion, saying why.
TEST(DiagnosisInvariants, AnEffectThatAddsNothingHeldOutGivenTheOthersIsWithheld) {
  SimConfig a = shaken(33), b = shaken(33);
  a.effects.line_delay_s = b.effects.line_delay_s = 4e-5;
  a.effects.k1k2 = Eigen::Vector2d(0.15, 0.0);
  SimulatedRecording sim = simulate_recording(a);
  hold_out_other_physics(sim, simulate_recording(b));
  const DiagnosisModel m(sim.rec);
  std::vector<int> fit, held;
  for (int i = 0; i < m.size(); ++i) (held_out(m, i, kHeldoutEvery) ? held : fit).push_back(i);
  const ModelParams nominal = nominal_params(sim.rec.nominal);
  const double sigma = 0.5 * m.noise_gain();
  const LensModel lens = sim.rec.nominal.cam.dist.model;
  Selection chosen;
  chosen.params = fit_params(m, fit, nominal, effect_params(Effect::RollingShutter, lens) | effect_params(Effect::LensDistortion, lens), sigma);
  ASSERT_NEAR(chosen.params[Param::K1], 0.15, 0.02);
  chosen.effects = {{Effect::RollingShutter, 0, 0, 0, {}}, {Effect::LensDistortion, 0, 0, 0, {}}};
  const Selection s = hold_on_blocked_halves(m, fit, held, subsample(fit, 5000), nominal, nominal, sigma, SelectionOptions{}, chosen);
  for (const std::string& w : s.withheld) std::printf("  withheld: %s\n", w.c_str());
  ASSERT_EQ(s.effects.size(), 1u);
  EXPECT_EQ(s.effects[0].effect, Effect::RollingShutter);
  EXPECT_GT(s.effects[0].heldout_given_others, 0);
  EXPECT_NEAR(s.params[Param::LineDelay], 4e-5, 0.1 * 4e-5);
  EXPECT_EQ(s.params[Param::K1], nominal[Param::K1]);
  ASSERT_EQ(s.withheld.size(), 1u);
  EXPECT_NE(s.withheld[0].find("lens_distortion not named: given the others it does not improve the held-out prediction"), std::string::npos)
      << s.withheld[0];
}

// A round's winner the held-out frames refuse does not end the selection: the fitting frames
// hide a strong lens distortion and a rolling shutter, the held-out frames only the rolling
// shutter. The distortion wins the first round on the fitting frames and is refused; the round
// asked again without it names the rolling shutter, which the held-out frames confirm.
TEST(DiagnosisInvariants, ARefusedWinnerDoesNotHideAnEffectTheDataHold) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("DiagnosisInvariants.AnEffectThatAddsNothingHeldOutGivenTheOthersIsWithheld (the same recording)");
  SimConfig a = shaken(33), b = shaken(33);
  a.effects.line_delay_s = b.effects.line_delay_s = 2e-5;
  a.effects.k1k2 = Eigen::Vector2d(0.3, 0.0);
  SimulatedRecording sim = simulate_recording(a);
  hold_out_other_physics(sim, simulate_recording(b));
  std::vector<std::string> progress;
  DiagnosisOptions opt;
  opt.progress = [&](const std::string& p) { progress.push_back(p); };
  const Diagnosis d = diagnose(sim.rec, opt);
  show(d);
  EXPECT_EQ(names(d), "rolling_shutter ");
  EXPECT_TRUE(said(d, "lens_distortion not named")) << "the remainder must say why";
  EXPECT_NEAR(d.fitted[Param::LineDelay], 2e-5, 0.1 * 2e-5);
  EXPECT_LT(d.heldout_final_rms_px, d.heldout_baseline_rms_px);
  // The order: the distortion refused before the rolling shutter was named.
  auto at = [&](const std::string& what) {
    for (size_t k = 0; k < progress.size(); ++k)
      if (progress[k].find(what) != std::string::npos) return static_cast<int>(k);
    return -1;
  };
  ASSERT_GE(at("lens_distortion not named: it fits the fitting frames"), 0);
  EXPECT_LT(at("lens_distortion not named: it fits the fitting frames"), at("named rolling_shutter"));
}

// Blocked halves revised (issue 34, point 3): a rolling shutter the whole recording shows, in a
// recording whose first half turns and whose second half stands still (a drone that hovers), so
// that the still half cannot show the readout at all. Fitted on the moving half, it leaves the
// still half's predictions as they were (a drop of exactly zero there, which the rule before
// refused); it must be kept, since it does not degrade that half, with the line delay the
// moving half measures.
TEST(DiagnosisInvariants, AnEffectOneHalfShowsWeaklyIsKept) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("DiagnosisInvariants.AnEffectThatAddsNothingHeldOutGivenTheOthersIsWithheld");
  SimConfig c = shaken(34);
  c.duration_s = 6.0;
  c.effects.line_delay_s = 2.5e-5;
  c.motion_source = MotionSource::Samples;
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, 1.0, 0.2).normalized();
  for (double t = c.start_time_s - 1.5; t <= c.start_time_s + c.duration_s + 1.5; t += 1e-3) {
    // The amplitude falls from 0.25 rad to nothing over the half second that ends half a
    // second before the middle.
    const double s = std::clamp((t - c.start_time_s - 0.5 * c.duration_s + 1.0) / 0.5, 0.0, 1.0);
    const double amplitude = 0.25 * (1 - s);
    const double angle = amplitude * std::sin(2 * M_PI * 1.3 * t) + 0.3 * amplitude * std::sin(2 * M_PI * 2.9 * t + 1.0);
    PoseSample p;
    p.t = t;
    p.q = Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis));
    p.p = Eigen::Vector3d::Zero();
    c.pose_samples.push_back(p);
  }
  const Diagnosis d = diagnose(simulate_recording(c).rec);
  show(d);
  EXPECT_EQ(names(d), "rolling_shutter ");
  EXPECT_NEAR(d.fitted[Param::LineDelay], 2.5e-5, 0.1 * 2.5e-5);
  EXPECT_LT(d.heldout_final_rms_px, d.heldout_baseline_rms_px);
  // Held out, half by half in time: the moving half predicted better, the still half as before.
  const auto& h = d.heldout_halves;
  EXPECT_EQ(h[0].observations + h[1].observations, d.heldout_observations);
  EXPECT_LT(h[0].final_rms_px, 0.95 * h[0].baseline_rms_px);
  EXPECT_NEAR(h[1].final_rms_px, h[1].baseline_rms_px, 0.01 * h[1].baseline_rms_px);
}

// A rolling shutter throughout, and the matches of the image's left `width` (a near object's
// parallax, cars passing under a drone) displaced by 6 px, far beyond the noise, in every frame
// pair, held out or not: the diagnosis and its progress lines.
struct DisplacedPart {
  Diagnosis d;
  std::vector<std::string> progress;
  bool said(const std::string& what) const {
    return std::any_of(progress.begin(), progress.end(), [&](const std::string& p) { return p.find(what) != std::string::npos; });
  }
};
DisplacedPart shutter_with_left_part_displaced(double width) {
  SimConfig c = shaken(34);
  c.effects.line_delay_s = 3e-5;
  SimulatedRecording sim = simulate_recording(c);
  size_t moved = 0;
  for (Match& mt : sim.rec.matches)
    if (mt.a.x() < width * sim.rec.nominal.cam.width) mt.b.x() += 6.0, ++moved;
  EXPECT_GT(moved, static_cast<size_t>(0.8 * width * static_cast<double>(sim.rec.matches.size())));
  DisplacedPart out;
  DiagnosisOptions opt;
  opt.progress = [&](const std::string& p) { out.progress.push_back(p); };
  out.d = diagnose(sim.rec, opt);
  show(out.d);
  for (const std::string& p : out.progress)
    if (p.find("not named") != std::string::npos) std::printf("  %s\n", p.c_str());
  return out;
}

// Structure in the tail only, the image's left 15% displaced. A gyro bias bends the model
// towards that tail: it lowers the whole robust chi-square and the held-out one (the tail is
// there too) while every other residual grows. It is refused for fitting the outliers at the
// bulk's cost; the rolling shutter, whose structure runs through every residual, is named.
TEST(DiagnosisInvariants, AnEffectThatFitsOnlyTheOutliersIsNotNamed) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("DiagnosisInvariants.AnEffectThatAddsNothingHeldOutGivenTheOthersIsWithheld");
  const DisplacedPart r = shutter_with_left_part_displaced(0.15);
  EXPECT_EQ(names(r.d), "rolling_shutter ");
  EXPECT_NEAR(r.d.fitted[Param::LineDelay], 3e-5, 0.1 * 3e-5);
  EXPECT_TRUE(r.said("not named: it fits the outliers"));
}

// An instrument's own bias: OpenCV's checkerboard detector puts corners 0.005-0.03 px off,
// depending on the view. A clean landmarks recording (0.016 px of noise, as corners found on a
// rendered board) whose every corner sits (0.01, 0.01) px off, beside a true rolling shutter: a
// lever arm of microns or a principal point a hundredth of a pixel off explains the bias at a
// BIC drop in the thousands, and neither is named; what was refused says why.
TEST(DiagnosisInvariants, AnEffectSmallerThanTheInstrumentsOwnBiasIsNotNamed) {
  SimConfig c = rsd::test::target_simulation(5, 4.0, 0.016);
  c.effects.line_delay_s = 3e-5;
  SimulatedRecording sim = simulate_recording(c);
  for (LandmarkObservation& o : sim.rec.observations) o.px += Eigen::Vector2d(0.01, 0.01);
  const Diagnosis d = diagnose(sim.rec);
  show(d);
  EXPECT_EQ(names(d), "rolling_shutter ");
  EXPECT_NEAR(d.fitted[Param::LineDelay], 3e-5, 0.01 * 3e-5);
  EXPECT_TRUE(said(d, "too small to tell from the instrument"));
}

// The same with the image's left quarter displaced (issue 34, point 2): before any effect is in,
// the shutter's shear beside the displaced quarter looks like parallax; under the translation
// nuisance a translation over a tilted scene takes up part of the shear, a clock drift and a
// gyro bias stand in for it and fail the blocked halves, and nothing was named. Nothing named
// there, the selection without the nuisance is made again and kept, its residuals showing no
// parallax: the shutter is named, the gyro bias refused for fitting the outliers.
TEST(DiagnosisInvariants, AQuarterDisplacedIsNotTakenForParallaxOnceTheShutterIsIn) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("DiagnosisInvariants.AnEffectThatAddsNothingHeldOutGivenTheOthersIsWithheld");
  const DisplacedPart r = shutter_with_left_part_displaced(0.25);
  EXPECT_TRUE(r.said("parallax in the matches"));
  EXPECT_TRUE(r.said("nothing named with the translation taken out: selecting again without it"));
  EXPECT_EQ(names(r.d), "rolling_shutter ");
  EXPECT_NEAR(r.d.fitted[Param::LineDelay], 3e-5, 0.1 * 3e-5);
  EXPECT_TRUE(r.said("gyro_bias not named: it fits the outliers"));
  EXPECT_LT(r.d.heldout_final_rms_px, 0.5 * r.d.heldout_baseline_rms_px);
}

// A clock that jumps by 3 ms at 4.5 s of 12: the screening observations' halves split near
// 6 s, so one half holds the jump and each half's drift carries that half's offset, and the
// halves agree: clock_drift was named (held out 0.871 -> 0.733 px). The clock's offset window by
// window steps (select.cpp, drift_is_a_rate): no drift is named, and nothing in its place; the
// remainder says the clock is not explained.
TEST(DiagnosisInvariants, AClockThatJumpsIsNotNamedADrift) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Remainder.ClockJumpIsStructure and ClockShape.AClockThatJumpsSteps (the same jump)");
  SimConfig c = shaken(35);
  c.duration_s = 12;
  c.unmodelled.clock_jump_s = 3e-3, c.unmodelled.clock_jump_at_s = 4.5;
  const Diagnosis d = diagnose(simulate_recording(c).rec);
  show(d);
  EXPECT_EQ(names(d), "");
  EXPECT_TRUE(said(d, "clock_drift not named: the clock's offset")) << "the remainder must say why";
  EXPECT_TRUE(d.remainder.significant) << d.remainder.summary;
  EXPECT_EQ(d.heldout_final_rms_px, d.heldout_baseline_rms_px);
}
