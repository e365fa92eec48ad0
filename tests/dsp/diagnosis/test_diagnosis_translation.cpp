// The translation nuisance of matches (dsp/diagnosis/translation.hpp) against simulated flights,
// its parts: it takes out the parallax a near scene gives, facing the camera or tilted as a
// ground ahead is (at the true model the noise is left); it cannot take up what a clock offset
// leaves (a free translation per frame pair took up most of it); a hand-held shake faster than
// the default knots gets finer ones, a flight keeps the default; a phone's readout has each
// match's velocity taken at its own rows' time; a Jacobian step with the
// translation's inliers and slope held agrees with the translation fitted again, and is linear
// for the parameters that leave the frame pairs' turns, and the uncertainties' Jacobian holds
// them too; a jittered gyro's frame pairs shift in
// time and take up what the jitter adds, a gyro sampled on time's do not; a hand-held camera's
// wall is met by a plane fixed in the world, a flight's scene that keeps its distance by one
// before each pair's camera; one plane's scene gives no match a depth of its own. Whole
// diagnoses under it: test_translation_diagnoses.cpp.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>
#include <utility>

#include "dsp/diagnosis/diagnosis.hpp"
#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/gyro.hpp"
#include "dsp/diagnosis/translation.hpp"
#include "dsp/diagnosis/parallax.hpp"
#include "dsp/diagnosis/robust_stats.hpp"
#include "dsp/diagnosis/uncertainty.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"
#include "tests/dsp/diagnosis/translation_cases.hpp"
#include "tests/support/sanitizer.hpp"

namespace rsd::test {
namespace {

using namespace rsd::dsp;

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

// A flight over a tilted ground with a 10 ms clock offset, its residuals under the nuisance at
// the true offset, and what they settled on (the two tests of the fits' Jacobian steps below).
struct GroundFlight {
  static SimConfig config() {
    SimConfig c = forward_flight(8, 15.0);
    c.unmodelled.scene_slope = kGround;
    c.effects.time_offset_s = 0.01;
    return c;
  }
  const SimulatedRecording sim = simulate_recording(config());
  const DiagnosisModel m{sim.rec};
  const std::vector<int> all = every_observation(m);
  const ModelParams p = with_offset(sim, 0.01, true);
  DiagnosisModel::Settled taken;
  const std::vector<Eigen::Vector2d> base = m.residuals(p, all, taken);
};

// A fit's finite-difference Jacobian under the nuisance steps with the translation's inliers and
// slope held as they settled at the point (DiagnosisModel::residuals_near): at the point itself
// that is the same residual, and a step's change agrees with the one the translation fitted
// again from scratch gives (four passes: a different code path) to within what the held slope
// leaves out. For a clock offset and a line delay that is a percent or two of the column; a
// rotation (a gyro bias, a mount) moves the image as a translation over the tilted ground does,
// the refitted slope takes up part of it, and the held one misses up to a fifth of the rotation
// model's whole change (the fit's trial steps use the exact residuals: that costs iterations,
// not accuracy).
TEST(Translation, AJacobianStepWithTheInliersHeldMatchesTheTranslationFittedAgain) {
  GroundFlight f;
  auto& [sim, m, all, p, taken, base] = f;
  ASSERT_TRUE(taken.translation.state);
  const auto again = m.residuals_near(p, all, taken);
  double worst = 0;
  for (size_t k = 0; k < all.size(); ++k)
    if (base[k].allFinite()) worst = std::max(worst, (again[k] - base[k]).norm());
  EXPECT_LT(worst, 1e-9);
  struct Step {
    Param q;
    double h;
    double of_column, of_rotation;  // limits on the difference over the refitted and the rotation-only change
  };
  ModelParams p_plain = p;
  p_plain.translation_nuisance = false;
  const auto raw_p = m.residuals(p_plain, all);
  for (const Step st : {Step{Param::TimeOffset, 1e-4, 0.05, 0.05}, Step{Param::LineDelay, 1e-8, 0.05, 0.05},
                        Step{Param::BiasY, 1e-4, 1.0, 0.25}, Step{Param::MountZ, 1e-4, 0.25, 0.1}}) {
    ModelParams q = p;
    q[st.q] += st.h;
    ModelParams q_plain = q;
    q_plain.translation_nuisance = false;
    const auto held = m.residuals_near(q, all, taken), fitted = m.residuals(q, all), raw_q = m.residuals(q_plain, all);
    double diff = 0, column = 0, rotation = 0;
    for (size_t k = 0; k < all.size(); ++k) {
      if (!base[k].allFinite() || !held[k].allFinite() || !fitted[k].allFinite() || base[k].norm() > 5) continue;
      diff += (held[k] - fitted[k]).squaredNorm(), column += (fitted[k] - base[k]).squaredNorm();
      rotation += (raw_q[k] - raw_p[k]).squaredNorm();
    }
    ASSERT_GT(rotation, 0) << static_cast<int>(st.q);
    EXPECT_GT(std::sqrt(column / rotation), 0.2) << static_cast<int>(st.q);  // the translation leaves some of it
    EXPECT_LT(std::sqrt(diff / column), st.of_column) << static_cast<int>(st.q);
    EXPECT_LT(std::sqrt(diff / rotation), st.of_rotation) << static_cast<int>(st.q);
  }
  // Residuals of other observations than the fit's are refused, not misread.
  std::vector<Eigen::Vector2d> fewer(base.begin(), base.end() - 1);
  const std::vector<int> idx(all.begin(), all.end() - 1);
  const GyroTrack track(m.recording().gyro, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), 1.0);
  EXPECT_THROW(remove_fitted_translation(m, idx, fewer, track, TimeModel{}, Eigen::Matrix3d::Identity(), kTranslationKnotS,
                                         taken.translation),
               std::invalid_argument);
}

// The held pass's column for a step h of q (translation_out_of_columns of the rotation model's
// change) against the change of residuals_near there: the largest difference over the
// observations and the largest change, {diff, size}.
std::pair<double, double> held_column_against_near(const DiagnosisModel& m, const std::vector<int>& all,
                                                   const ModelParams& p, const DiagnosisModel::Settled& taken,
                                                   const std::vector<Eigen::Vector2d>& base, Param q, double h) {
  ModelParams p_plain = p;
  p_plain.translation_nuisance = false;
  const auto raw_p = m.residuals(p_plain, all);
  ModelParams at = p;
  at[q] += h;
  ModelParams at_plain = at;
  at_plain.translation_nuisance = false;
  const auto raw_q = m.residuals(at_plain, all), near = m.residuals_near(at, all, taken);
  Eigen::MatrixXd cols = Eigen::MatrixXd::Zero(2 * static_cast<Eigen::Index>(all.size()), 1);
  for (size_t k = 0; k < all.size(); ++k) cols.block<2, 1>(2 * k, 0) = raw_q[k] - raw_p[k];
  m.translation_out_of_columns(at, all, cols, taken);
  double diff = 0, size = 0;
  for (size_t k = 0; k < all.size(); ++k) {
    if (!base[k].allFinite() || !near[k].allFinite() || !raw_q[k].allFinite()) continue;
    const Eigen::Vector2d change = near[k] - base[k];
    diff = std::max(diff, (cols.block<2, 1>(2 * k, 0) - change).norm()), size = std::max(size, change.norm());
  }
  return {diff, size};
}

// Where a parameter leaves the frame pairs' turns (the line delay, the intrinsics, the lens), the
// held translation pass is linear in the residuals: the change it makes of the rotation model's
// change is the change of residuals_near, to the rolling-shutter rows' settling (1e-8 of it; the
// fits' Jacobian takes these columns so, all with one factorisation). A parameter that moves the turns (the clock's offset) does
// not pass through it so, as moves_translation_pass says.
TEST(Translation, TheHeldPassTakesAColumnThatLeavesThePairsTurnsLinearly) {
  GroundFlight f;
  auto& [sim, m, all, p, taken, base] = f;
  struct Step {
    Param q;
    double h;
  };
  for (const Step st : {Step{Param::LineDelay, 1e-7}, Step{Param::Fx, 2.0}, Step{Param::K1, 1e-3}, Step{Param::Cy, 2.0},
                        Step{Param::TimeOffset, 1e-3}}) {
    const auto [diff, size] = held_column_against_near(m, all, p, taken, base, st.q, st.h);
    ASSERT_GT(size, 1e-3) << param_name(st.q);
    if (DiagnosisModel::moves_translation_pass(st.q)) EXPECT_GT(diff, 1e-3 * size) << param_name(st.q);
    else EXPECT_LT(diff, 1e-6 * size) << param_name(st.q);
  }
  for (Param q : {Param::Fx, Param::Fy, Param::Cx, Param::Cy, Param::K1, Param::K2, Param::K3, Param::K4})
    EXPECT_FALSE(DiagnosisModel::moves_translation_pass(q)) << param_name(q);
  for (Param q : {Param::LineDelay, Param::TimeOffset, Param::Drift, Param::MountX, Param::BiasY, Param::ScaleZ})
    EXPECT_TRUE(DiagnosisModel::moves_translation_pass(q)) << param_name(q);
  Eigen::MatrixXd wrong = Eigen::MatrixXd::Zero(2 * static_cast<Eigen::Index>(all.size()) - 2, 1);
  EXPECT_THROW(m.translation_out_of_columns(p, all, wrong, taken), std::invalid_argument);
}

// The uncertainties' Jacobian (residual_jacobian) steps as the fits' Jacobian does, the
// translation's inliers, slope and own depths held as they settled at the point: each column is
// the held residuals' central difference at half its step (the two differ by the step's square:
// here by 3e-7 of the column at most).
// Taken afresh at each step, as it was before, a rotation's column over a tilted ground is off
// by a large part (the refitted slope takes some of it up: the test above), and a match that
// crosses an inlier's or an own depth's bound between the steps jumps into the column: the
// independent generator's drone had its clock offset's sigma at 0.0056 ms where it is 0.72 ms.
TEST(Translation, TheUncertaintiesJacobianHoldsTheTranslationAsItSettled) {
  GroundFlight f;
  auto& [sim, m, all, p, taken, base] = f;
  const NominalModel& n = m.recording().nominal;
  const std::vector<Param> free{Param::TimeOffset, Param::BiasY, Param::MountZ};
  const Eigen::MatrixXd J = residual_jacobian(m, p, free, all);
  ASSERT_EQ(J.rows(), 2 * static_cast<Eigen::Index>(all.size()));
  for (size_t j = 0; j < free.size(); ++j) {
    const double h = 0.5e-2 * param_scale(free[j], n);
    ModelParams hi = p, lo = p;
    set_param(hi, free[j], p[free[j]] + h, n);
    set_param(lo, free[j], p[free[j]] - h, n);
    const auto held_hi = m.residuals_near(hi, all, taken), held_lo = m.residuals_near(lo, all, taken);
    const auto fresh_hi = m.residuals(hi, all), fresh_lo = m.residuals(lo, all);
    Eigen::VectorXd held = Eigen::VectorXd::Zero(J.rows()), afresh = held;
    for (size_t k = 0; k < all.size(); ++k) {
      const Eigen::Vector2d a = (held_hi[k] - held_lo[k]) / (2 * h), b = (fresh_hi[k] - fresh_lo[k]) / (2 * h);
      const auto row = 2 * static_cast<Eigen::Index>(k);
      if (a.allFinite()) held.segment<2>(row) = a;
      if (b.allFinite()) afresh.segment<2>(row) = b;
    }
    ASSERT_GT(held.norm(), 0) << param_name(free[j]);
    EXPECT_LT((J.col(static_cast<Eigen::Index>(j)) - held).norm(), 1e-4 * held.norm()) << param_name(free[j]);
    // This flight tells the two apart: 2% of the offset's column, 12% and 55% of the rotations'.
    EXPECT_GT((afresh - held).norm(), 1e-2 * held.norm()) << param_name(free[j]);
  }
}

// A gyro sampled on time shows no stamps' spread: its pairs do not shift, and the residuals are
// those without shifts, exactly.
TEST(Translation, AGyroSampledOnTimeLeavesThePairsUnshifted) {
  SimConfig c = forward_flight(8, 15.0);
  c.effects.time_offset_s = 0.01;
  const SimulatedRecording sim = simulate_recording(c);
  const DiagnosisModel m(sim.rec);
  EXPECT_EQ(pair_shift_sd(m), 0.0);
  const auto all = every_observation(m);
  ModelParams with = with_offset(sim, 0.01, true), without = with;
  without.translation_pair_shifts = false;
  const auto a = m.residuals(with, all), b = m.residuals(without, all);
  for (size_t k = 0; k < all.size(); ++k) {
    if (!a[k].allFinite() && !b[k].allFinite()) continue;
    ASSERT_EQ(a[k], b[k]) << k;
  }
}

// The hand-held shake's gyro, its stamps 0.5 ms off at random: the rates' corrections leave each
// pair's rotation off by the rate's change over a shift of its own. Without the pixels' noise
// and outliers, at the true model, what the jitter adds to the residual is measured against the
// same recording with the stamps on time (the same draws of everything else: a different
// simulation, not the model): the pairs' shifts take up most of it (a tenth to a third of a
// jittered pair's rotation error lies off the angular acceleration, test_gyro_stamps), and on
// time there are none. (They take up part of what is left on time too, the gyro's noise and the
// spline's misfit of the shake where these lie along the rate's change: half of it here.)
// The held pass with the shifts in stays linear in the residuals (the fits' Jacobian columns).
TEST(Translation, AJitteredGyrosPairsShiftInTimeAndTakeUpWhatTheJitterAdds) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Translation.AGyroSampledOnTimeLeavesThePairsUnshifted (the shifts' switch)");
  auto mean_square = [](const SimConfig& c, bool shifts, double* sd) {
    const SimulatedRecording sim = simulate_recording(c);
    const DiagnosisModel m(sim.rec);
    *sd = pair_shift_sd(m);
    ModelParams p = nominal_params(sim.rec.nominal);
    p.translation_nuisance = true, p.translation_knot_s = 0.125, p.translation_pair_shifts = shifts;
    const double rms = robust_stats(m.residuals(p, every_observation(m))).rms_px;
    return rms * rms;
  };
  for (unsigned seed : kShakeSeeds) {
    SimConfig jittered = hand_held_shake(seed);
    jittered.noise_px = 0, jittered.outlier_fraction = 0;
    SimConfig on_time = jittered;
    on_time.gyro.jitter_s = 0;
    double sd = 0, sd_on_time = 0;
    const double floor = mean_square(on_time, true, &sd_on_time), plain = mean_square(jittered, false, &sd),
                 shifted = mean_square(jittered, true, &sd);
    std::printf("seed %u: shift sd %.3f ms (on time %.3f); mean square on time %.5f, jittered %.5f, with shifts %.5f px^2\n",
                seed, 1e3 * sd, 1e3 * sd_on_time, floor, plain, shifted);
    EXPECT_GT(sd, 0.2e-3);
    EXPECT_LT(sd, 0.45e-3);
    EXPECT_EQ(sd_on_time, 0.0);
    ASSERT_GT(plain - floor, floor);  // the jitter shows
    EXPECT_LT(shifted - floor, 0.35 * (plain - floor));
  }
  // The held pass: linear for a column that leaves the turns, with the shifts eliminated too.
  const SimulatedRecording sim = simulate_recording(hand_held_shake(kShakeSeeds[0]));
  const DiagnosisModel m(sim.rec);
  const std::vector<int> all = every_observation(m);
  ModelParams p = nominal_params(sim.rec.nominal);
  p.translation_nuisance = true, p.translation_knot_s = 0.125;
  DiagnosisModel::Settled taken;
  const auto base = m.residuals(p, all, taken);
  for (Param q : {Param::Fx, Param::K1}) {
    const auto [diff, size] = held_column_against_near(m, all, p, taken, base, q, q == Param::Fx ? 2.0 : 1e-3);
    ASSERT_GT(size, 1e-3) << param_name(q);
    EXPECT_LT(diff, 1e-6 * size) << param_name(q);
  }
}

TEST(Translation, AShakeFasterThanTheKnotsGetsFinerKnotsAndAFlightKeepsItsOwn) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Translation.AtTheTrueModelTheVelocitySplineLeavesTheNoise and TheVelocitySplineCannotTakeUpAClockOffset (the nuisance)");
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

// A hand-held camera stays before its wall: it moves by a small share of the wall's distance
// over the recording. A drone flying at 8 m/s past a scene 40 m or 15 m ahead (one that keeps
// its distance, as a landscape does) travels 5 s x 8 m/s from the middle pair's time to either
// end, along the middle pair's optical axis (0.4 rad into the pan) by cos 0.4 of it: 0.92 and
// 2.46 of the scene's depth. The first is seen before a plane fixed in the world, the second not.
TEST(Translation, AHandHeldCameraStaysBeforeItsWallAndAFlightTravelsPastItsScene) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Translation.AWallFixedInTheWorldIsMetByThePlaneFixedInTheWorld (the world plane)");
  for (double depth : {40.0, 15.0}) {
    const SimulatedRecording flight = simulate_recording(forward_flight(8, depth));
    const DiagnosisModel m(flight.rec);
    const double travel = translation_travel(m, every_observation(m), with_offset(flight, 0, true));
    const double expected = 5 * 8 / depth * std::cos(0.4);
    EXPECT_NEAR(travel, expected, 0.1 * expected) << "depth " << depth;
    EXPECT_GT(travel, kWorldPlaneTravel) << "depth " << depth;
  }
  for (bool fixed : {false, true}) {
    SimConfig c = hand_held_shake(kShakeSeeds[0]);
    c.unmodelled.scene_fixed_in_world = fixed;
    const SimulatedRecording shake = simulate_recording(c);
    const DiagnosisModel m(shake.rec);
    ModelParams truth = nominal_params(shake.rec.nominal);
    truth.translation_nuisance = true;
    truth.translation_knot_s = kTranslationKnotsS[2];
    // The shake's terms of 5 cm, at 4 m: the velocity over depth the spline follows, integrated
    // over the 20 s, moves the wall by 0.15 of its distance at most (what the spline's errors
    // add up to included), a third of the bound.
    const double travel = translation_travel(m, every_observation(m), truth);
    EXPECT_GT(travel, 0.01) << "fixed " << fixed;
    EXPECT_LT(travel, 0.2) << "fixed " << fixed;
  }
}

// A tilted wall fixed in the world, a camera 4 m before it turning by up to 0.3 rad and moving by
// 20 cm, slowly (0.3 Hz: the spline follows the velocity), a gyro without error: the wall's tilt
// in each pair's camera follows the turn. At the true model the plane fixed in the world leaves
// the noise and the plane before each pair's camera the tilt's change; over a scene that lies
// the same way before each pair's camera (the simulator's own, a landscape keeping its distance)
// the other way about.
TEST(Translation, AWallFixedInTheWorldIsMetByThePlaneFixedInTheWorld) {
  for (bool fixed : {true, false}) {
    SimConfig c = hand_held_shake(kShakeSeeds[0]);
    c.rotation_amplitude_rad = 0.3, c.translation_amplitude_m = 0.2, c.motion_frequency_hz = 0.3;
    c.gyro = {200, 200, 0, 0, 0, 0};
    c.noise_px = 0.1, c.outlier_fraction = 0;
    c.unmodelled.scene_fixed_in_world = fixed;
    c.unmodelled.scene_slope = Eigen::Vector2d(0.4, -0.3);
    const SimulatedRecording sim = simulate_recording(c);
    const DiagnosisModel m(sim.rec);
    const auto all = every_observation(m);
    const double noise = c.noise_px * m.noise_gain();
    ModelParams truth = nominal_params(sim.rec.nominal);
    truth.translation_nuisance = true;
    truth.translation_knot_s = kTranslationKnotsS[2];
    const double camera = robust_stats(m.residuals(truth, all)).rms_px;
    truth.translation_world_plane = true;
    const double world = robust_stats(m.residuals(truth, all)).rms_px;
    std::printf("wall %s: the plane before each pair's camera leaves %.3f px, the plane fixed in the world %.3f px (noise %.3f px)\n",
                fixed ? "fixed in the world" : "before each pair's camera", camera, world, noise);
    EXPECT_NEAR(fixed ? world : camera, noise, 0.1 * noise) << "fixed " << fixed;
    EXPECT_GT(fixed ? camera : world, 1.3 * noise) << "fixed " << fixed;
  }
}

// One plane (a wall, a ground ahead of a flight, a wall behind a hand's shake) is the scene: no
// match gets a depth of its own. The excess along the translation's flow is noise, within a few
// standard errors, and the spread under kMinDepthSpread. (Points at many depths, which rsd's
// simulator does not draw: the independent generator's drone, cli_diagnose_independent_drone,
// whose scene measures 0.55 at 34 standard errors.)
TEST(Translation, OnePlanesSceneGivesNoMatchADepthOfItsOwn) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Translation.AtTheTrueModelTheVelocitySplineLeavesTheNoise (the nuisance)");
  for (const Eigen::Vector2d& slope : {Eigen::Vector2d::Zero().eval(), kGround}) {
    SimConfig c = forward_flight(8, 15.0);
    c.unmodelled.scene_slope = slope;
    const SimulatedRecording flight = simulate_recording(c);
    const DiagnosisModel m(flight.rec);
    EXPECT_EQ(translation_depth_spread(m, every_observation(m), with_offset(flight, 0, true)), 0.0) << slope.transpose();
  }
  const SimulatedRecording shake = simulate_recording(hand_held_shake(kShakeSeeds[0]));
  const DiagnosisModel m(shake.rec);
  ModelParams truth = nominal_params(shake.rec.nominal);
  truth.translation_nuisance = true;
  truth.translation_knot_s = kTranslationKnotsS[2];
  EXPECT_EQ(translation_depth_spread(m, every_observation(m), truth), 0.0);
}

// The knots need two pairs an interval where there are pairs: the same number of a shake's frame
// pairs (75 of 600) chosen one in eight, four a second, cannot hold knots finer than the default
// (a spline finer than its pairs is a free translation per pair), in three runs of 25
// consecutive pairs they hold the finer knots the shake needs (the penalty bridges the gaps).
TEST(Translation, FramesInRunsHoldFinerKnotsThanAsManySpreadOneByOne) {
  const SimulatedRecording sim = simulate_recording(hand_held_shake(kShakeSeeds[0]));
  const DiagnosisModel m(sim.rec);
  ModelParams truth = nominal_params(sim.rec.nominal);
  truth.translation_nuisance = true;
  std::vector<int> spread, runs;
  std::set<int> spread_pairs, run_pairs;
  for (int i : every_observation(m)) {
    const int rank = m.frame_rank(i);
    if (rank % 8 == 0 && rank < 600) spread.push_back(i), spread_pairs.insert(rank);
    if (rank % 250 < 25) runs.push_back(i), run_pairs.insert(rank);
  }
  ASSERT_EQ(spread_pairs.size(), 75u);
  ASSERT_EQ(run_pairs.size(), 75u);
  EXPECT_EQ(translation_knot_spacing(m, spread, truth), kTranslationKnotS);
  EXPECT_LT(translation_knot_spacing(m, runs, truth), kTranslationKnotS);
}

// Under the nuisance a focal length's sigma is the sandwich's clustered by blocks of ten frames
// when that is the larger (uncertainty.hpp): the spline shares the pairs' errors over its knots.
// On a shake past a wall it is, by over a tenth; without the nuisance the frame pairs' alone.
TEST(Translation, UnderTheNuisanceTheSigmaIsClusteredByBlocksOfFramesToo) {
  SimConfig c = hand_held_shake(kShakeSeeds[0]);
  c.duration_s = 10;
  const double f = 1476;
  c.effects.fxfy = Eigen::Vector2d(f, f);
  const SimulatedRecording sim = simulate_recording(c);
  const DiagnosisModel m(sim.rec);
  const auto all = every_observation(m);
  ModelParams p = nominal_params(sim.rec.nominal);
  p[Param::Fx] = p[Param::Fy] = f;
  p.translation_nuisance = true, p.translation_knot_s = 0.125;
  const std::vector<NamedEffect> named = {{"focal_length", {{"fx", f, ""}, {"fy", f, ""}}, "", 0, 0, 0, 0, 0, {}}};
  auto reported = [&](const ModelParams& at) {
    for (const ParamUncertainty& u : effect_uncertainties(m, named, at, all))
      if (u.param == "fx" && u.sigma) return *u.sigma;
    return std::nan("");
  };
  const auto by_pair = parameter_variances(m, p, {Param::Fx}, all), by_block = parameter_variances(m, p, {Param::Fx}, all, kNuisanceClusterFrames);
  ASSERT_TRUE(by_pair && by_block);
  EXPECT_GT((*by_block)[0], 1.2 * (*by_pair)[0]);
  EXPECT_NEAR(reported(p), std::sqrt((*by_block)[0]), 1e-9 * f);
  ModelParams plain = p;
  plain.translation_nuisance = false;
  const auto plain_pair = parameter_variances(m, plain, {Param::Fx}, all);
  ASSERT_TRUE(plain_pair);
  EXPECT_NEAR(reported(plain), std::sqrt((*plain_pair)[0]), 1e-9 * f);
}

// A phone's 25 ms readout spreads a frame pair's matches over a tenth of a hand's shake: each
// match sees the camera move at its own rows' time (translation.hpp). At the true model the
// velocity spline then leaves the noise; taken at one time per pair it left a flow that grows
// down the image, which a principal point and a mount's pitch took up in the suite's walk.
TEST(Translation, AShakesVelocityIsTakenAtEachMatchsRowsTime) {
  SimConfig c = hand_held_shake(kShakeSeeds[0]);
  c.duration_s = 8;
  c.nominal.time.line_delay_s = 0.025 / 1080;
  c.gyro = GyroSampling{};  // 200 Hz on time, no noise: the gyro's own errors apart
  const SimulatedRecording sim = simulate_recording(c);
  const DiagnosisModel m(sim.rec);
  const auto all = every_observation(m);
  const double noise = 0.7 * m.noise_gain();
  ModelParams truth = nominal_params(sim.rec.nominal);
  truth.translation_nuisance = true, truth.translation_knot_s = 0.125;
  const double rms = robust_stats(m.residuals(truth, all)).rms_px;
  EXPECT_NEAR(rms, noise, 0.03 * noise);
}

}  // namespace
}  // namespace rsd::test
