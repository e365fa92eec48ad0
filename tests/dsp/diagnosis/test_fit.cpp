// dsp::fit_params (fit.hpp): the Levenberg-Marquardt fit must end at the minimum of the robust
// cost, checked against a different code path: robust_chi2 on DiagnosisModel::residuals along
// each free parameter's axis, a parabola through three points a sigma apart. A guard for any
// cheaper Jacobian: one by Broyden's secant updates, the fit stopping on it, ended 1 to 7.5
// sigmas off here (the focal length 7 px short of its 15 px move, k1 a fifth of the way).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "dsp/diagnosis/effects.hpp"
#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/offset_search.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"
#include "tests/dsp/diagnosis/translation_cases.hpp"
#include "tests/dsp/diagnosis/twin_matches.hpp"

using namespace rsd::dsp;

namespace {

// A 640x480 camera with a 29 ms readout, a 4 ms clock offset, a focal length 3% long and barrel
// distortion, all of which the nominal model lacks: the fit starts tens of sigmas away.
struct Case {
  SimulatedRecording sim;
  std::vector<int> all;
  ParamMask free;
  double sigma = 0;
};

Case far_start() {
  SimConfig c = rsd::test::simulation(ObservationKind::Matches, 11, 3.0, 0.5);
  c.start_time_s = 1000;
  c.matches_per_pair = 60;
  c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2;
  c.effects.line_delay_s = 6e-5;
  c.effects.time_offset_s = 4e-3;
  c.effects.fxfy = Eigen::Vector2d(515, 515);
  c.effects.k1k2 = Eigen::Vector2d(-0.05, 0);
  Case k{simulate_recording(c), {}, {}, 0};
  for (size_t i = 0; i < k.sim.rec.matches.size(); ++i) k.all.push_back(static_cast<int>(i));
  const LensModel lens = k.sim.rec.nominal.cam.dist.model;
  for (Effect e : {Effect::RollingShutter, Effect::TimeOffset, Effect::FocalLength, Effect::LensDistortion})
    k.free |= effect_params(e, lens);
  return k;
}

// Where the robust chi-square is least along p's axis through `at`, in sigmas of p from `at`:
// the vertex of the parabola through the cost at -s, 0 and +s, s the sigma the curvature gives
// (found from a first probe). Also returns that sigma.
std::pair<double, double> vertex_in_sigmas(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& at,
                                           Param p, double probe, double sigma_px) {
  auto cost = [&](double d) {
    ModelParams q = at;
    set_param(q, p, at[p] + d, m.recording().nominal);
    return robust_chi2(m.residuals(q, idx), sigma_px);
  };
  const double c0 = cost(0);
  // chi2(d) ~ c0 + g d + d^2 / sigma^2 (a sigma's move costs one): the probe gives sigma, a
  // parabola through +-sigma the vertex.
  auto curvature = [&](double s) { return (cost(s) + cost(-s) - 2 * c0) / (s * s); };  // 2 / sigma^2
  const double sigma = std::sqrt(2.0 / curvature(probe));
  const double cp = cost(sigma), cm = cost(-sigma);
  const double vertex = -((cp - cm) / (2 * sigma)) / ((cp + cm - 2 * c0) / (sigma * sigma));
  return {vertex / sigma, sigma};
}

}  // namespace

TEST(Fit, EndsAtTheRobustCostsMinimumFromFarAway) {
  const Case k = far_start();
  const DiagnosisModel m(k.sim.rec);
  const double sigma_px = std::sqrt(2.0) * 0.5;
  const ModelParams start = nominal_params(k.sim.rec.nominal);
  const ModelParams fitted = fit_params(m, k.all, start, k.free, sigma_px, 50);
  EXPECT_NEAR(fitted[Param::LineDelay], 6e-5, 3e-6);
  EXPECT_NEAR(fitted[Param::TimeOffset], 4e-3, 3e-4);
  for (auto [p, probe] : {std::pair{Param::LineDelay, 1e-7}, std::pair{Param::TimeOffset, 1e-5}, std::pair{Param::Fx, 0.5},
                          std::pair{Param::K1, 1e-4}}) {
    const auto [vertex, sigma] = vertex_in_sigmas(m, k.all, fitted, p, probe, sigma_px);
    std::printf("%s: start %.6g, fitted %.9g, sigma %.3g; the cost's least %.4f sigma away\n", param_name(p), start[p],
                fitted[p], sigma, vertex);
    EXPECT_GT(std::abs(fitted[p] - start[p]), 10 * sigma) << param_name(p);  // the start is far
    EXPECT_LT(std::abs(vertex), 0.05) << param_name(p);
  }
}

// FitEnd's contract, which the selection's memory of fits relies on (selector.hpp,
// `remembered`): a fit that converged in fewer iterations than its cap is the fit any larger cap
// gives from the same start, to the bit; one stopped by its cap says so.
TEST(Fit, AConvergedFitIsTheFitOfAnyLargerCap) {
  const Case k = far_start();
  const DiagnosisModel m(k.sim.rec);
  const double sigma_px = std::sqrt(2.0) * 0.5;
  const ModelParams start = nominal_params(k.sim.rec.nominal);
  FitEnd capped, whole, wider;
  const ModelParams two = fit_params(m, k.all, start, k.free, sigma_px, 2, &capped);
  EXPECT_FALSE(capped.converged);  // tens of sigmas away: two steps do not get there
  EXPECT_EQ(capped.iterations, 2);
  const ModelParams fitted = fit_params(m, k.all, start, k.free, sigma_px, 50, &whole);
  ASSERT_TRUE(whole.converged);
  ASSERT_LT(whole.iterations, 50);
  EXPECT_NE(two.v, fitted.v);
  const ModelParams again = fit_params(m, k.all, start, k.free, sigma_px, whole.iterations + 1, &wider);
  EXPECT_TRUE(wider.converged);
  EXPECT_EQ(wider.iterations, whole.iterations);
  EXPECT_EQ(again.v, fitted.v);  // bit for bit
  FitEnd none;
  fit_params(m, k.all, start, ParamMask{}, sigma_px, 1, &none);
  EXPECT_TRUE(none.converged);  // nothing free: any cap gives the start
}

// settle_time_offset: between the gross grid and the local fits, the offset within two frame
// periods of the start, at the noise's scale. A start 40 ms off the simulator's offset (what the
// gross grid left on a drone's forward flight whose clock only a closing pan shows) is out of
// refine_time_offset's reach (+-5 ms) and settles to the truth; a start at the truth stays.
TEST(Fit, TheOffsetSettlesFromFortyMillisecondsOffWhereTheRefineCannotReach) {
  SimConfig c = rsd::test::simulation(ObservationKind::Matches, 23, 3.0, 0.5);
  c.matches_per_pair = 40;
  c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2;
  c.effects.time_offset_s = 0.04;
  const SimulatedRecording sim = simulate_recording(c);
  const DiagnosisModel m(sim.rec);
  std::vector<int> all(sim.rec.matches.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  const double sigma_px = std::sqrt(2.0) * 0.5;
  const ModelParams start = nominal_params(sim.rec.nominal);  // offset 0
  const double refined = refine_time_offset(m, all, start, sigma_px), settled = settle_time_offset(m, all, start, sigma_px);
  std::printf("from 0: refined %.5f s, settled %.5f s (truth 0.04)\n", refined, settled);
  EXPECT_LE(std::abs(refined), 5e-3 + 1e-9);
  EXPECT_NEAR(settled, 0.04, 5e-4);
  ModelParams at_truth = start;
  at_truth[Param::TimeOffset] = 0.04;
  EXPECT_NEAR(settle_time_offset(m, all, at_truth, sigma_px), 0.04, 5e-4);
}

// profile_time_offset: the vertex of a quadratic through the robust chi-square at nine offsets a
// step apart, the translation taken out afresh at each. A forward flight past a wall 40 m ahead
// (a pan at 4 s; the translation nuisance on) with a 10 ms clock offset: about the truth the
// vertex is the truth; about a point three steps off it is the truth again, not the point (a
// sign error would double the distance); a step of zero gives the point back.
TEST(Fit, TheOffsetsProfileUnderTheTranslationHasItsMinimumAtTheTruth) {
  SimConfig c = rsd::test::forward_flight(5, 40.0);
  c.effects.time_offset_s = 0.01;
  const SimulatedRecording sim = simulate_recording(c);
  const DiagnosisModel m(sim.rec);
  const std::vector<int> all = rsd::test::every_observation(m);
  const double sigma_px = std::sqrt(2.0) * 0.5, step = 1e-3;
  const ModelParams at_truth = rsd::test::with_offset(sim, 0.01, true);
  ModelParams off = at_truth;
  off[Param::TimeOffset] = 0.01 + 3 * step;
  const double about_truth = profile_time_offset(m, all, at_truth, sigma_px, step),
               about_off = profile_time_offset(m, all, off, sigma_px, step);
  std::printf("profile's minimum about the truth %.3f ms, about 13 ms %.3f ms (truth 10)\n", about_truth * 1e3,
              about_off * 1e3);
  EXPECT_NEAR(about_truth, 0.01, 0.3 * step);
  EXPECT_NEAR(about_off, 0.01, 0.5 * step);
  EXPECT_EQ(profile_time_offset(m, all, off, sigma_px, 0.0), off[Param::TimeOffset]);
}

// design_effect (fit.hpp) against its definition, Var(sum of the residuals) / (n var), from the
// correlations the simulation gives the residuals: independent errors give 1, twins with
// independent errors 1, and every match with a twin inside its window whose error correlates
// 0.5 with its own 1 + 1 x 0.5 (rsd-extract's detector makes such twins: docs/diagnosis.md, "The
// noise the remainder is measured against"). Measured on the twins' own pairs: the frame means
// alone count them too, as a part the frame shares, but from one number a frame (1.33 here).
TEST(DesignEffect, CountsWhatTwinFeaturesShare) {
  SimConfig c = rsd::test::simulation(ObservationKind::Matches, 12, 6.0, 0.5);
  c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2;
  c.gyro = {200, 200, 0, 0, 0, 0};  // a clean gyro: at the truth the residual is the pixels' noise
  c.matches_per_pair = 30;
  const SimulatedRecording plain = simulate_recording(c);
  auto effect = [](const SimulatedRecording& sim, double sigma) {
    const DiagnosisModel m(sim.rec);
    return design_effect(m, nominal_params(sim.rec.nominal), rsd::test::every_observation(m), sigma);
  };
  SimulatedRecording independent = plain, shared = plain;
  const double sigma = rsd::test::add_correlated_twins(independent, 0.0, 3);
  rsd::test::add_correlated_twins(shared, 0.5, 3);
  const double d_plain = effect(plain, sigma), d_independent = effect(independent, sigma),
               d_shared = effect(shared, sigma);
  std::printf("design effect: plain %.3f, independent twins %.3f, twins correlated 0.5 %.3f\n", d_plain, d_independent,
              d_shared);
  EXPECT_NEAR(d_plain, 1.0, 0.1);
  EXPECT_NEAR(d_independent, 1.0, 0.1);
  EXPECT_NEAR(d_shared, 1.5, 0.1);
}
