// The blocked halves (dsp/diagnosis/blocked_halves.hpp, issue 34 point 3): on simulated matches
// whose halves differ in motion, a real effect predicts the half it was not fitted on and both
// halves agree on its value; a clock that jumps half-way makes the clock offset a stand-in the
// halves put 3 ms apart, which the fits on each half, made here, confirm; a real effect seen
// through a model that is not quite the camera's keeps its value within the block-clustered
// sigmas; a gross offset the halves put a small share of it apart is kept; a short recording's
// halves have no say on the value; a lens's terms that trade along the same curve agree, a
// lens whose curve differs does not; a half that barely moves has no say on the half that does;
// a drop's margin from its blocks' spread is the algebra's on noise, and covers a drop that two
// blocks decide but not one that every block shows.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <utility>

#include "dsp/diagnosis/blocked_halves.hpp"
#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/uncertainty.hpp"
#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/lens_model.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"

using namespace rsd::dsp;

namespace {

// A phone-like matches recording of 12 s (each half long enough for the values' block-clustered
// sigmas: 24 blocks) whose rotation swings by `first` rad in its first half and by `second` in
// its second (about one axis, at 1.3 Hz with a harmonic; the swing changes over the half second
// before the middle), 80 matches per pair.
SimConfig two_motions(unsigned seed, double first, double second) {
  SimConfig c = rsd::test::simulation(ObservationKind::Matches, seed, 12.0, 0.5);
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
  c.unmodelled.clock_jump_s = 3e-3, c.unmodelled.clock_jump_at_s = 6.0;
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

// A model not quite the camera's: a real 10 ms clock offset, and the camera also translating past
// a wall 1 m away (parallax the hypothesis leaves out). Each half's offset carries a bias that
// follows its motion, and the halves put it over a millisecond apart; the sigmas clustered by
// blocks of a quarter of a second see that spread (wider than those clustered by frame) and the
// offset is kept, as a real effect seen through a model that is not quite right must be.
TEST(BlockedHalves, AModelNotQuiteTheCamerasKeepsARealOffset) {
  SimConfig c = two_motions(43, 0.25, 0.12);
  c.effects.time_offset_s = 0.01;
  c.unmodelled.scene_depth_m = 1.0;
  for (PoseSample& p : c.pose_samples)
    p.p = Eigen::Vector3d(0.05 * std::sin(2 * M_PI * 0.9 * p.t), 0.03 * std::sin(2 * M_PI * 1.1 * p.t), 0);
  const Split s(simulate_recording(c));
  ASSERT_TRUE(s.h.usable());
  const HalvesVerdict v = cross_check(s.m, s.h, {s.nominal, {}}, {s.nominal, only(Param::TimeOffset)}, s.sigma, 8);
  // The same fits, judged with the sigmas clustered by frame.
  const ModelParams a = fit_params(s.m, s.h.a, s.nominal, only(Param::TimeOffset), s.sigma, 8);
  const ModelParams b = fit_params(s.m, s.h.b, s.nominal, only(Param::TimeOffset), s.sigma, 8);
  const auto va = parameter_variances(s.m, a, {Param::TimeOffset}, s.h.a), vb = parameter_variances(s.m, b, {Param::TimeOffset}, s.h.b);
  ASSERT_TRUE(va && vb);
  const double gap = std::abs(a[Param::TimeOffset] - b[Param::TimeOffset]);
  const double by_frame = gap / std::sqrt((*va)[0] + (*vb)[0]);
  std::printf("offset past unmodelled parallax: halves at %.3f and %.3f ms; %.1f frame-clustered sigmas, %.1f "
              "block-clustered sigmas apart (drop %.1f)\n",
              a[Param::TimeOffset] * 1e3, b[Param::TimeOffset] * 1e3, by_frame, v.apart_sigmas, v.drop);
  EXPECT_GT(gap, 1e-3);
  EXPECT_GT(v.apart_sigmas, 0);
  EXPECT_LT(v.apart_sigmas, 0.8 * by_frame);  // the blocks' spread is wider than the frames'
  EXPECT_LT(v.apart_sigmas, kHalvesAgreeSigmas);
  EXPECT_GT(v.drop, 0);
}

// A gross effect whose halves differ by a small share of its size is real, however small its
// sigmas: a walk's halves put a 0.4 s clock offset 2.9 ms apart at sigmas of 0.34 ms (the
// translation nuisance's sigmas understate the scatter), and dropping the offset for that left
// 68 px where the noise floor was 3.6. Here the halves' fits are set 3 ms apart around the true
// 0.4 s: about six of their own sigmas, a hundredth of the offset.
TEST(BlockedHalves, AGrossOffsetIsKeptWhenTheHalvesDifferByASmallShareOfIt) {
  SimConfig c = two_motions(45, 0.25, 0.25);
  c.effects.time_offset_s = 0.4;
  const Split s(simulate_recording(c));
  ASSERT_TRUE(s.h.usable());
  ModelParams a = s.nominal, b = s.nominal;
  a[Param::TimeOffset] = 0.4015, b[Param::TimeOffset] = 0.3985;
  const int block = static_cast<int>(std::lround(kHalvesBlockS * s.sim.rec.nominal.frame_rate_hz));
  const auto va = parameter_variances(s.m, a, {Param::TimeOffset}, s.h.a, block);
  const auto vb = parameter_variances(s.m, b, {Param::TimeOffset}, s.h.b, block);
  ASSERT_TRUE(va && vb);
  const double plain = 3e-3 / std::sqrt((*va)[0] + (*vb)[0]);
  const HalvesVerdict v = cross_check(s.m, s.h, {{s.nominal, s.nominal}}, {}, HalvesFits{{a, b}}, only(Param::TimeOffset), s.sigma);
  std::printf("a 0.4 s offset's halves 3 ms apart: %.1f of their sigmas, %.3f of the test's (drop %.1f)\n", plain,
              v.apart_sigmas, v.drop);
  EXPECT_GT(plain, kHalvesAgreeSigmas);  // the sigmas alone would call them apart
  EXPECT_NEAR(v.apart_sigmas, 3e-3 / (kHalvesSizeFraction * 0.4), 1e-9);
  EXPECT_GT(v.drop, 0);  // and each half's value predicts the other half
}

// Under about 10 s a half has fewer than 20 blocks: its sigmas cannot see errors that persist
// over a block, and the value check has no say (the prediction check still runs).
TEST(BlockedHalves, AShortRecordingsHalvesHaveNoSayOnTheValue) {
  SimConfig c = two_motions(44, 0.25, 0.25);
  c.duration_s = 4.0;
  c.unmodelled.clock_jump_s = 3e-3, c.unmodelled.clock_jump_at_s = 2.0;
  const Split s(simulate_recording(c));
  ASSERT_TRUE(s.h.usable());
  const HalvesVerdict v = cross_check(s.m, s.h, {s.nominal, {}}, {s.nominal, only(Param::TimeOffset)}, s.sigma, 8);
  EXPECT_EQ(v.apart_sigmas, 0);
  EXPECT_LT(v.drop, 0);  // the stand-in still mispredicts the other half
}

namespace {

// A barrel lens (k1 -0.06) on the two-motions recording (0.15 px of noise), and the halves' fits set apart by hand:
// k1 of `a` and `b` dk1 each side of the truth, k2 by `dk2` each side of zero (the other way).
struct LensHalves {
  Split s;
  ModelParams a, b;
  ParamMask lens;
  LensHalves(double dk1, double dk2) : s(simulate_recording(barrel())), a(s.nominal), b(s.nominal) {
    a[Param::K1] = -0.06 + dk1, a[Param::K2] = -dk2;
    b[Param::K1] = -0.06 - dk1, b[Param::K2] = dk2;
    lens.set(static_cast<size_t>(Param::K1)), lens.set(static_cast<size_t>(Param::K2));
  }
  static SimConfig barrel() {
    SimConfig c = two_motions(46, 0.25, 0.25);
    c.effects.k1k2 = Eigen::Vector2d(-0.06, 0);
    c.noise_px = 0.15;  // sigmas small enough that k2 alone is clearly apart
    return c;
  }
  // How far apart the halves put k2 alone, in its block-clustered sigmas (the term-by-term test).
  double k2_sigmas_apart() const {
    const int block = static_cast<int>(std::lround(kHalvesBlockS * s.sim.rec.nominal.frame_rate_hz));
    const auto va = parameter_variances(s.m, a, {Param::K1, Param::K2}, s.h.a, block);
    const auto vb = parameter_variances(s.m, b, {Param::K1, Param::K2}, s.h.b, block);
    return va && vb ? std::abs(a[Param::K2] - b[Param::K2]) / std::sqrt((*va)[1] + (*vb)[1]) : 0;
  }
  // The largest difference of the halves' distorted radii over the field, as a share of the
  // lens's own (the mean's) bending there: computed with distorted_radius, not the test's
  // Jacobian.
  double largest_share_apart() const {
    const NominalModel& n = s.sim.rec.nominal;
    const double widest = widest_ray_angle(n.cam);
    double worst = 0;
    for (int k = 1; k <= 8; ++k) {
      const double theta = widest * k / 8, r = std::tan(theta);
      const double da = distorted_radius(lens_of(n, a), theta), db = distorted_radius(lens_of(n, b), theta);
      worst = std::max(worst, std::abs(da - db) / std::abs(0.5 * (da + db) - r));
    }
    return worst;
  }
};

}  // namespace

// Terms of one lens trade: under a hand-held shake's parallax a walk's halves (split by angular
// rate) put k1 at -0.072 and -0.044 and k2 at +0.020 and -0.027 (truth -0.06 and 0), k2 4.2
// sigmas apart, and the lens was dropped, leaving 5.3 px where the floor was 2.65. Here the
// halves' k1 differ by 0.012 and their k2 the other way so that the two curves meet at the
// image's widest ray: k2 alone is over four of its sigmas apart, the curves within a fifth of
// the lens's bending everywhere, and the test, on the curve, keeps the lens.
TEST(BlockedHalves, TermsOfALensThatTradeAlongTheSameCurveAgree) {
  const double r = std::tan(widest_ray_angle(LensHalves::barrel().nominal.cam));
  const LensHalves l(0.006, 0.006 / (r * r));
  ASSERT_TRUE(l.s.h.usable());
  const HalvesVerdict v = cross_check(l.s.m, l.s.h, {{l.s.nominal, l.s.nominal}}, {}, HalvesFits{{l.a, l.b}}, l.lens, l.s.sigma);
  std::printf("k1 -0.054 / -0.066, k2 %+.4f / %+.4f: k2 %.1f of its sigmas apart, curves up to %.0f%% of the lens apart, "
              "the test %.2f\n", l.a[Param::K2], l.b[Param::K2], l.k2_sigmas_apart(), 100 * l.largest_share_apart(), v.apart_sigmas);
  EXPECT_GT(l.k2_sigmas_apart(), kHalvesAgreeSigmas);  // term by term: apart
  EXPECT_LT(l.largest_share_apart(), 0.21);
  // No more apart than the size floor allows (a tenth of the lens's bending).
  EXPECT_LE(v.apart_sigmas, l.largest_share_apart() / kHalvesSizeFraction + 1e-9);
  EXPECT_LT(v.apart_sigmas, kHalvesAgreeSigmas);
}

// Halves whose curves differ: k1 0.03 apart with k2 held at zero bends the image by half the
// lens's own bending, past what the size floor forgives, and the test calls them apart.
TEST(BlockedHalves, HalvesWhoseLensCurvesDifferAreApart) {
  const LensHalves l(0.015, 0);
  ASSERT_TRUE(l.s.h.usable());
  const HalvesVerdict v = cross_check(l.s.m, l.s.h, {{l.s.nominal, l.s.nominal}}, {}, HalvesFits{{l.a, l.b}}, l.lens, l.s.sigma);
  std::printf("k1 -0.045 / -0.075, k2 0: curves up to %.0f%% of the lens apart, the test %.2f\n",
              100 * l.largest_share_apart(), v.apart_sigmas);
  EXPECT_GT(l.largest_share_apart(), 0.45);
  EXPECT_GT(v.apart_sigmas, kHalvesAgreeSigmas);
}

namespace {

// A focal length 1% long (`first` rad of swing in the first half, 0.25 in the second) and
// each half's fit of it.
struct FocalHalves {
  Split s;
  ModelParams a, b;
  ParamMask focal;
  explicit FocalHalves(double first) : s(simulate_recording(config(first))) {
    focal.set(static_cast<size_t>(Param::Fx)), focal.set(static_cast<size_t>(Param::Fy));
    a = fit_params(s.m, s.h.a, s.nominal, focal, s.sigma);
    b = fit_params(s.m, s.h.b, s.nominal, focal, s.sigma);
  }
  static SimConfig config(double first) {
    SimConfig c = two_motions(47, first, 0.25);
    c.effects.fxfy = Eigen::Vector2d(c.nominal.cam.fx, c.nominal.cam.fy) * 1.01;
    // The first half also translates past a wall 1 m away, which the hypotheses leave out.
    c.unmodelled.scene_depth_m = 1.0;
    const double mid = c.start_time_s + 0.5 * c.duration_s;
    for (PoseSample& p : c.pose_samples) {
      const double fade = std::clamp((mid - p.t) / 0.5, 0.0, 1.0);
      p.p = fade * Eigen::Vector3d(0.05 * std::sin(2 * M_PI * 0.9 * p.t), 0.03 * std::sin(2 * M_PI * 1.1 * p.t), 0);
    }
    return c;
  }
  // The block-clustered sigma of fx on each half, at its value there.
  double sigma_fx(const std::vector<int>& half, const ModelParams& at) const {
    const int block = static_cast<int>(std::lround(kHalvesBlockS * s.sim.rec.nominal.frame_rate_hz));
    const auto v = parameter_variances(s.m, at, {Param::Fx, Param::Fy}, half, block);
    return v ? std::sqrt((*v)[0]) : NAN;
  }
  // What the first half's value costs the second half beyond the nominal model's cost there.
  double cost_to_second_half() const {
    return robust_chi2(s.m.residuals(a, s.h.b), s.sigma) - robust_chi2(s.m.residuals(s.nominal, s.h.b), s.sigma);
  }
  HalvesVerdict verdict() const {
    return cross_check(s.m, s.h, {{s.nominal, s.nominal}}, {}, HalvesFits{{a, b}}, focal, s.sigma);
  }
};

}  // namespace

// Issue 34, point 3: a half that barely moves measures a focal length far less well than one
// that swings, the more so where it also translates past a near wall that the hypotheses leave
// out (a drone's flight beside its pan): its fit lands loose (here 6.7% long where the truth is
// 1%), and would cost the swinging half tens of thousands more than no effect at all, for that
// looseness, not for what the effect is. It has no say there, only on whether the values
// agree, and the swinging half's value must predict it. (Stand-ins that both halves measure keep
// their verdicts: AClockThatJumpsPutsTheOffsetApart.)
TEST(BlockedHalves, AHalfThatBarelyMovesHasNoSayOnTheHalfThatDoes) {
  const FocalHalves still(0.005);
  ASSERT_TRUE(still.s.h.usable());
  const double sa = still.sigma_fx(still.s.h.a, still.a), sb = still.sigma_fx(still.s.h.b, still.b);
  const double truth = 1.01 * still.s.nominal[Param::Fx];
  const HalvesVerdict v = still.verdict();
  std::printf("fx 1%% long, first half still past a wall: fx %.1f +- %.1f and %.1f +- %.1f px (truth %.1f); the first's "
              "costs the second %.0f more than the nominal; drop %.1f, %.2f sigmas apart\n",
              still.a[Param::Fx], sa, still.b[Param::Fx], sb, truth, still.cost_to_second_half(), v.drop, v.apart_sigmas);
  EXPECT_NEAR(still.b[Param::Fx], truth, 3 * sb);
  EXPECT_GT(std::abs(still.a[Param::Fx] - truth), 0.04 * truth);  // loose
  EXPECT_GT(sa, kWeakHalfSigmas * sb);
  EXPECT_GT(still.cost_to_second_half(), 1e4);  // asked, the still half's value would drop the effect
  EXPECT_GT(v.drop, 0);                          // the still half is predicted by the swinging half's value
  EXPECT_LT(v.apart_sigmas, kHalvesAgreeSigmas);
}

namespace {

// Residuals of `blocks` blocks of 50 observations, each coordinate's noise `noise` (sigma 1).
std::vector<Eigen::Vector2d> noise_residuals(int blocks, double noise, unsigned seed, std::vector<int>& block) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, noise);
  std::vector<Eigen::Vector2d> r;
  block.clear();
  for (int b = 0; b < blocks; ++b)
    for (int k = 0; k < 50; ++k) r.emplace_back(n(rng), n(rng)), block.push_back(b);
  return r;
}

double plain_drop(const std::vector<Eigen::Vector2d>& r0, const std::vector<Eigen::Vector2d>& r1) {
  return robust_chi2(r0, 1.0) - robust_chi2(r1, 1.0);
}

}  // namespace

// On independent noise the blocks' spread gives the drop's standard deviation that the algebra
// gives (fit_halves: 2 sqrt(sum |d|^2) noise / sigma^2 for a change d within the loss's quadratic
// core), so the margin is three of those.
TEST(BlockedHalves, TheBlocksStandardErrorOfADropOnNoiseIsTheAnalyticOne) {
  std::vector<int> block;
  const double noise = 0.3;
  const std::vector<Eigen::Vector2d> r0 = noise_residuals(400, noise, 5, block);
  std::vector<Eigen::Vector2d> r1 = r0;
  double d2 = 0;
  for (size_t k = 0; k < r1.size(); ++k) {
    const Eigen::Vector2d d(0.05 * std::cos(0.01 * k), 0.05 * std::sin(0.01 * k));
    r1[k] += d, d2 += d.squaredNorm();
  }
  const double se = (block_margined_drop(block, r0, r1, 1.0) - plain_drop(r0, r1)) / 3;
  const double analytic = 2 * noise * std::sqrt(d2);
  std::printf("a drop's standard error from 400 blocks %.3f, the algebra's %.3f\n", se, analytic);
  EXPECT_NEAR(se, analytic, 0.12 * analytic);
}

// A drop that two blocks of 24 decide (structure the model lacks, beyond the loss's core, which
// the change makes worse) is within its margin; the same drop spread over every block, as a
// stand-in's, is not; and fewer than kMinClusters blocks give no margin.
TEST(BlockedHalves, ADropThatTwoBlocksDecideIsWithinItsMarginOneThatEveryBlockShowsIsNot) {
  std::vector<int> block;
  const std::vector<Eigen::Vector2d> r0 = noise_residuals(24, 0.3, 6, block);
  std::vector<Eigen::Vector2d> local = r0, spread = r0;
  for (size_t k = 0; k < r0.size(); ++k)
    if (block[k] < 2) local[k] += Eigen::Vector2d(3, 0);
  const double lost = plain_drop(r0, local);
  for (size_t k = 0; k < r0.size(); ++k) spread[k] *= std::sqrt(1 - lost / robust_chi2(r0, 1.0));
  std::printf("two blocks' drop %.1f -> margined %.1f; spread over all %.1f -> margined %.1f\n", lost,
              block_margined_drop(block, r0, local, 1.0), plain_drop(r0, spread), block_margined_drop(block, r0, spread, 1.0));
  EXPECT_LT(lost, -100);
  EXPECT_NEAR(plain_drop(r0, spread), lost, 0.1 * std::abs(lost));
  EXPECT_GT(block_margined_drop(block, r0, local, 1.0), 0);
  EXPECT_LT(block_margined_drop(block, r0, spread, 1.0), 0);
  std::vector<int> few(block.size());
  for (size_t k = 0; k < block.size(); ++k) few[k] = block[k] % (kMinClusters - 1);
  EXPECT_EQ(block_margined_drop(few, r0, local, 1.0), -std::numeric_limits<double>::infinity());
}
