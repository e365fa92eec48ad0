// A video stabilised in the camera (dsp/diagnosis/stabiliser.hpp): the gyro smoothed as the
// pictures' orientation is, against analytic gains and a brute-force mean of orientations; and
// whole diagnoses, where a stabiliser's gain is not named as a gyro scale and a real scale under
// one still is.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "dsp/diagnosis/diagnosis.hpp"
#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/selector.hpp"
#include "dsp/diagnosis/stabiliser.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"
#include "tests/support/sanitizer.hpp"

using namespace rsd::dsp;
using rsd::test::names;
using rsd::test::said;
using rsd::test::shaken;
using rsd::test::show;
using rsd::dsp::selection::Selector;
using rsd::dsp::selection::State;

namespace {

// Rates about x of a turn a sin(2 pi f t), sampled regularly at 200 Hz or at random intervals
// of 5 to 50 ms (a phone's gyro with gaps).
std::vector<GyroSample> sine(double f, bool irregular) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> step(0.005, 0.05);
  std::vector<GyroSample> g;
  for (double t = 0; t < 10; t += irregular ? step(rng) : 0.005)
    g.push_back({t, Eigen::Vector3d(0.25 * 2 * M_PI * f * std::cos(2 * M_PI * f * t), 0, 0)});
  return g;
}

// The least-squares gain of `out` on `in` over the middle half (away from the ends' clamping).
double gain(const std::vector<GyroSample>& in, const std::vector<GyroSample>& out) {
  double num = 0, den = 0;
  for (size_t k = in.size() / 4; k < 3 * in.size() / 4; ++k) num += out[k].w.x() * in[k].w.x(), den += in[k].w.squaredNorm();
  return num / den;
}

// A coning camera: turned about x and y at once, 90 degrees apart in phase, so that its body
// rates and the rates of its orientation in the world differ by the angle times the rate.
Eigen::Matrix3d coning(double t) {
  const double a = 0.3, w = 2 * M_PI * 1.5;
  return exp_so3(Eigen::Vector3d(a * std::sin(w * t), 0, 0)) * exp_so3(Eigen::Vector3d(0, a * std::cos(w * t), 0));
}

// Body rates of `coning` by central differences at 200 Hz.
std::vector<GyroSample> coning_rates() {
  std::vector<GyroSample> g;
  for (double t = 0; t < 4; t += 0.005) {
    const double h = 1e-5;
    g.push_back({t, log_so3(coning(t - h).transpose() * coning(t + h)) / (2 * h)});
  }
  return g;
}

// The Gaussian-weighted Karcher mean of coning's orientations around t, on a 500 Hz grid,
// iterated (three Gauss-Newton steps, converged to well under a microradian): the smoothed
// orientation by its definition.
Eigen::Matrix3d mean_orientation(double t, double sigma) {
  Eigen::Matrix3d M = coning(t);
  for (int it = 0; it < 3; ++it) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double weight = 0;
    for (double d = -4 * sigma; d <= 4 * sigma; d += 2e-3) {
      const double w = std::exp(-0.5 * d * d / (sigma * sigma));
      sum += w * log_so3(M.transpose() * coning(t + d)), weight += w;
    }
    M = M * exp_so3(sum / weight);
  }
  return M;
}

// The largest difference, over 33 ms steps in the middle of the record, between the turn the
// rates `g` integrate to (trapezoids on their samples) and the brute-force smoothed orientation's.
double worst_turn_error(const std::vector<GyroSample>& g, double sigma) {
  std::vector<Eigen::Matrix3d> R(g.size(), Eigen::Matrix3d::Identity());
  for (size_t k = 0; k + 1 < g.size(); ++k) R[k + 1] = R[k] * exp_so3(0.5 * (g[k].w + g[k + 1].w) * (g[k + 1].t - g[k].t));
  double worst = 0;
  for (size_t k = 200; k + 207 < g.size(); k += 21) {
    const Eigen::Matrix3d turn = R[k].transpose() * R[k + 7];
    const Eigen::Matrix3d truth = mean_orientation(g[k].t, sigma).transpose() * mean_orientation(g[k + 7].t, sigma);
    worst = std::max(worst, log_so3(turn.transpose() * truth).norm());
  }
  return worst;
}


}  // namespace

// A Gaussian of sigma passes a sine of frequency f at exp(-(2 pi f sigma)^2 / 2), however the
// gyro is sampled (the kernel is integrated on its own grid, not over the samples).
TEST(Stabiliser, SmoothedRatesPassASineAtTheKernelsGain) {
  for (bool irregular : {false, true})
    for (double sigma : {0.01, 0.04, 0.1}) {
      const std::vector<GyroSample> g = sine(1.0, irregular);
      const double expected = std::exp(-0.5 * std::pow(2 * M_PI * sigma, 2));
      EXPECT_NEAR(gain(g, smoothed_rates(g, sigma)), expected, irregular ? 0.005 : 0.002)
          << (irregular ? "irregular" : "regular") << " sampling, sigma " << sigma;
    }
  EXPECT_THROW(smoothed_rates(sine(1.0, false), 0), std::invalid_argument);
}

// Smoothing part of the record (what a test that looks at part of a recording asks for) leaves
// the rest as it was and gives, 4 sigma inside the part's edges, what smoothing the whole gives.
TEST(Stabiliser, APartOfTheRecordIsSmoothedAsTheWholeIs) {
  const double sigma = 0.04;
  const std::vector<GyroSample> g = sine(1.3, true);
  const std::vector<GyroSample> whole = smoothed_rates(g, sigma), part = smoothed_rates(g, sigma, 3.0, 6.0);
  int inside = 0;
  for (size_t k = 0; k < g.size(); ++k) {
    if (g[k].t < 3.0 || g[k].t > 6.0) {
      EXPECT_EQ(part[k].w, g[k].w) << "t = " << g[k].t;
    } else if (g[k].t > 3.0 + 4 * sigma && g[k].t < 6.0 - 4 * sigma) {
      EXPECT_LT((part[k].w - whole[k].w).norm(), 1e-9) << "t = " << g[k].t;
      ++inside;
    }
  }
  EXPECT_GT(inside, 50);
}

// The stabiliser smooths where the camera points. Under a coning motion the body rates smoothed
// as three signals integrate to turns 3 mrad off the smoothed orientation's over 33 ms (the
// angle times the rate); smoothed_rates' stay within a fiftieth of that.
TEST(Stabiliser, SmoothedRatesTurnAsTheSmoothedOrientationDoes) {
  const double sigma = 0.05;
  const std::vector<GyroSample> g = coning_rates();
  std::vector<GyroSample> naive(g);  // each axis's rate smoothed on its own
  for (size_t k = 0; k < g.size(); ++k) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double weight = 0;
    for (const GyroSample& s : g) {
      const double d = s.t - g[k].t, w = std::exp(-0.5 * d * d / (sigma * sigma));
      sum += w * s.w, weight += w;
    }
    naive[k].w = sum / weight;
  }
  const double body = worst_turn_error(naive, sigma), ours = worst_turn_error(smoothed_rates(g, sigma), sigma);
  std::printf("turns over 33 ms against the smoothed orientation: body rates smoothed %.3g rad, ours %.3g rad\n", body, ours);
  EXPECT_GT(body, 1e-4) << "the coning must tell the two apart";
  EXPECT_LT(ours, 0.02 * body);
}

// The pictures follow the orientation smoothed by a 5 Hz stabiliser (zero phase), the gyro the
// real one: under a 0.7 Hz shake a gyro scale of about 0.98 imitates it. Nothing is named; the
// remainder is significant and lives first in the stabilisation, at the smoothing's sigma (the
// stabiliser's 5 Hz corner is a Gaussian's 45 ms where their gains agree to second order).
TEST(Stabiliser, AStabilisedVideoNamesNoGainInItsStead) {
  SimConfig c = shaken(41);
  c.motion_frequency_hz = 0.7;
  c.unmodelled.stabilisation_hz = 5;
  const Diagnosis d = diagnose(simulate_recording(c).rec);
  show(d);
  EXPECT_EQ(names(d), "");
  EXPECT_TRUE(said(d, "gyro_scale not named: it stands in for a video stabilised in the camera"));
  EXPECT_TRUE(d.remainder.significant) << d.remainder.summary;
  EXPECT_TRUE(d.remainder.stabilised);
  EXPECT_NEAR(d.remainder.stabiliser_sigma_s, std::sqrt(2.0) / (2 * M_PI * 5), 0.005);
  ASSERT_FALSE(d.remainder.located.empty());
  EXPECT_EQ(d.remainder.located.front().signal, "stabilisation");
}

// A gyro reading 2-3% high on every axis (a scale under one everywhere, as a stabiliser's gain
// is) on a video that is not stabilised: the smoothing cannot give one gain at every frequency
// and a gain of each axis's own, and the scale is named.
TEST(Stabiliser, ARealScaleUnderOneIsStillNamed) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Stabiliser.AStabilisedVideoNamesNoGainInItsStead (the same check)");
  SimConfig c = shaken(42);
  c.effects.gyro_scale = Eigen::Vector3d(0.97, 0.975, 0.98);
  const Diagnosis d = diagnose(simulate_recording(c).rec);
  show(d);
  EXPECT_EQ(names(d), "gyro_scale ");
  const NamedEffect* s = rsd::test::find(d, "gyro_scale");
  ASSERT_NE(s, nullptr);
  EXPECT_NEAR(rsd::test::param(s, "sx"), 0.97, 0.003);
}

// A stabiliser that does not look ahead (the forward pass alone) lags the motion: under a 0.7 Hz
// shake a 5 Hz first-order low-pass delays it by atan(0.7 / 5) / (2 pi 0.7) = 31.6 ms, which the
// clock offset takes up (the pictures are late on the gyro), and the rest is the smoothing. The
// offset is named at the lag, the stabilisation said, and the summary says the offset may be the
// stabiliser's delay rather than the clocks'.
TEST(Stabiliser, AStabiliserThatLagsIsSaidBesideTheOffsetItsDelayMakes) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("Stabiliser.AStabilisedVideoNamesNoGainInItsStead (the same check)");
  SimConfig c = shaken(41);
  c.motion_frequency_hz = 0.7;
  c.unmodelled.stabilisation_hz = 5;
  c.unmodelled.stabilisation_looks_ahead = false;
  const Diagnosis d = diagnose(simulate_recording(c).rec);
  show(d);
  EXPECT_EQ(names(d), "time_offset ");
  const NamedEffect* t = rsd::test::find(d, "time_offset");
  ASSERT_NE(t, nullptr);
  const double lag = std::atan(0.7 / 5) / (2 * M_PI * 0.7);
  EXPECT_NEAR(rsd::test::param(t, "time_offset_s"), -lag, 0.002);
  EXPECT_TRUE(d.remainder.stabilised) << d.remainder.summary;
  EXPECT_TRUE(d.remainder.offset_beside_stabiliser);
  EXPECT_NE(d.remainder.summary.find("may be the stabiliser's delay"), std::string::npos) << d.remainder.summary;
  ASSERT_FALSE(d.remainder.located.empty());
  EXPECT_EQ(d.remainder.located.front().signal, "stabilisation");
}

// The check after a selection (stabiliser_after_selection), on the true model: a video
// stabilised at 5 Hz over the 0.7 Hz shake follows the gyro smoothed over about 45 ms; the same
// shake unstabilised, whose residuals are noise, is not called stabilised.
TEST(Stabiliser, TheCheckAfterASelectionSaysAStabiliserAndOnlyThen) {
  for (bool stabilised : {true, false}) {
    SimConfig c = shaken(43);
    c.motion_frequency_hz = 0.7;
    if (stabilised) c.unmodelled.stabilisation_hz = 5;
    const SimulatedRecording s = simulate_recording(c);
    const DiagnosisModel m(s.rec);
    std::vector<int> all(m.size()), search;
    for (int i = 0; i < m.size(); ++i) all[i] = i;
    for (int i = 0; i < m.size(); i += 4) search.push_back(i);
    const std::optional<double> sigma =
        stabiliser_after_selection(m, search, all, nominal_params(s.rec.nominal), 0.5 * std::sqrt(2.0), 10);
    if (stabilised) {
      ASSERT_TRUE(sigma.has_value());
      EXPECT_NEAR(*sigma, std::sqrt(2.0) / (2 * M_PI * 5), 0.005);
    } else {
      EXPECT_FALSE(sigma.has_value()) << *sigma;
    }
  }
}

// A stabiliser found by the check after a selection is the bar of the selection run again
// (SelectionOptions::stabilised_s): an effect that gives the motion no gain, which the Selector
// asks to beat the smoothing only once it has found a stabiliser itself, is asked from the first
// round. On the 5 Hz stabilised shake a principal point fitted to the nominal model is refused
// as the smoothing's stand-in with the bar set, and not asked without it.
TEST(Stabiliser, AStabiliserFoundAfterASelectionIsTheBarOfTheNext) {
  SimConfig c = shaken(41);
  c.motion_frequency_hz = 0.7;
  c.unmodelled.stabilisation_hz = 5;
  const SimulatedRecording s = simulate_recording(c);
  const DiagnosisModel m(s.rec);
  std::vector<int> fit, held, screen;
  for (int i = 0; i < m.size(); ++i) (i % 2 ? held : fit).push_back(i);
  for (size_t k = 0; k < fit.size(); k += 4) screen.push_back(fit[k]);
  const double sigma = 0.5 * std::sqrt(2.0);
  const ModelParams nominal = nominal_params(s.rec.nominal);
  const LensModel lens = s.rec.nominal.cam.dist.model;
  const State poorer{{}, nominal};
  const State richer{{Effect::PrincipalPoint},
                     fit_params(m, fit, nominal, mask_of({Effect::PrincipalPoint}, lens), sigma, 20)};
  for (const std::optional<double> bar : {std::optional<double>{}, std::optional<double>{0.045}}) {
    SelectionOptions o;
    o.stabilised_s = bar;
    const Selector sel(m, fit, held, screen, nominal, nominal, sigma, o);
    const std::string why = sel.stands_in_for_a_stabiliser_because(poorer, richer, {Effect::PrincipalPoint});
    if (bar) {
      EXPECT_NE(why.find("it stands in for a video stabilised in the camera"), std::string::npos) << why;
    } else {
      EXPECT_EQ(why, "");
    }
  }
}
