// The online estimator against the simulator's ground truth (issue goals, docs/online-calibration.md):
// a VGA camera shaken by hand with a 200 Hz gyro, true time offset 15 ms, line delay 20% above
// the nominal one, gyro bias 0.01 rad/s on each axis; the matches and the gyro are fed as a
// running camera delivers them, one update a second.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <functional>
#include <map>
#include <utility>

#include "dsp/online/online_estimator.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/dsp/online/online_figure.hpp"
#include "tests/support/sanitizer.hpp"

using namespace rsd::dsp;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

constexpr double kNominalLineDelay = 5e-5;  // 24 ms of the 33 ms frame period

SimConfig hand_held(unsigned seed, double duration_s) {
  SimConfig c = rsd::test::simulation(ObservationKind::Matches, seed, duration_s, 0.3);
  c.nominal.time.line_delay_s = kNominalLineDelay;
  c.nominal.imu_to_camera << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  c.rotation_amplitude_rad = 0.2, c.motion_frequency_hz = 1.0;
  c.matches_per_pair = 80;
  c.outlier_fraction = 0.05;
  c.gyro.noise_rad_s = 0.003;
  c.effects.time_offset_s = 0.015;
  c.effects.line_delay_s = 1.2 * kNominalLineDelay;
  c.effects.gyro_bias = Vector3d::Constant(0.01);
  return c;
}

// The same camera with every row read at once, and nobody told the line delay (0).
SimConfig global_shutter(unsigned seed, double duration_s) {
  SimConfig c = hand_held(seed, duration_s);
  c.nominal.time.line_delay_s = 0;
  c.effects.line_delay_s = 0.0;
  return c;
}

OnlineCalibration nominal_start() { return {0.0, kNominalLineDelay, Vector3d::Zero()}; }
OnlineCalibration true_calibration(double offset) { return {offset, 1.2 * kNominalLineDelay, Vector3d::Constant(0.01)}; }

// RSD_FIGURES_DIR=docs: docs/online-calibration.md's figures.
void figure(const char* name, const char* title, const rsd::test::OnlineTrace& trace, const rsd::test::OnlineTruth& truth) {
  if (const char* dir = getenv("RSD_FIGURES_DIR")) rsd::test::plot_online_trace(std::string(dir) + "/" + name, title, trace, truth);
}

// Feeds the recording frame by frame: the gyro up to each frame's end on the IMU clock (plus a
// margin, as it arrives), the frame pair's matches, and an update after every `per_update`
// frames; `seen` is called with each update's camera time and estimate.
void stream(const Recording& rec, OnlineEstimator& e, int per_update,
            const std::function<void(double, const OnlineEstimate&)>& seen) {
  std::map<int, double> t;
  for (const FrameStamp& f : rec.frames) t[f.frame] = f.t;
  std::map<std::pair<int, int>, std::pair<std::vector<Vector2d>, std::vector<Vector2d>>> pairs;
  for (const Match& m : rec.matches) {
    auto& p = pairs[{m.frame_a, m.frame_b}];
    p.first.push_back(m.a), p.second.push_back(m.b);
  }
  size_t g = 0;
  int frames = 0;
  for (const auto& [ab, p] : pairs) {
    const double tb = t.at(ab.second);
    for (; g < rec.gyro.size() && rec.gyro[g].t <= tb + 0.1; ++g) e.add_gyro(rec.gyro[g].t, rec.gyro[g].w);
    e.add_matches(t.at(ab.first), tb, p.first, p.second);
    if (++frames % per_update == 0) seen(tb, e.update());
  }
}

// RSD_VERBOSE=1: each update's estimate, one line.
void show(double t, const OnlineEstimate& est) {
  if (!getenv("RSD_VERBOSE")) return;
  std::printf("%6.2f %-10s off %8.3f ms (%.3f)  ld %.4f (%.4f)  bias %7.4f %7.4f %7.4f (%.4f)  in %d/%d  %.3f px rate %.2f %s\n",
              t, to_string(est.state), est.value.time_offset_s * 1e3, est.sigma.time_offset_s * 1e3,
              est.value.line_delay_s / kNominalLineDelay, est.sigma.line_delay_s / kNominalLineDelay, est.value.gyro_bias.x(),
              est.value.gyro_bias.y(), est.value.gyro_bias.z(), est.sigma.gyro_bias.maxCoeff(), est.window.inliers,
              est.window.fitted, est.window.residual_px, est.window.rate_rms_rad_s, est.reason.c_str());
}

}  // namespace

TEST(OnlineEstimator, ConvergesWithinTenSecondsToTheIssueTolerances) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("OnlineEstimator.AGlobalShutterLearnsTheOffsetAndTheBias");
  const SimConfig c = hand_held(7, 12);
  const SimulatedRecording sim = simulate_recording(c);
  OnlineEstimator e(c.nominal, nominal_start());
  double converged_at = -1;
  rsd::test::OnlineTrace trace;
  stream(sim.rec, e, 30, [&](double t, const OnlineEstimate& est) {
    show(t - c.start_time_s, est);
    trace.t.push_back(t - c.start_time_s), trace.est.push_back(est);
    if (converged_at < 0 && est.state == OnlineState::Converged) converged_at = t - c.start_time_s;
  });
  figure("online-calibration-converge.png", "hand-held: offset 15 ms, line delay +20%, gyro bias 0.01 rad/s", trace,
         {true_calibration(0.015), true_calibration(0.015), -1, kNominalLineDelay});
  const OnlineEstimate& est = e.estimate();
  ASSERT_EQ(est.state, OnlineState::Converged) << est.reason;
  EXPECT_GT(converged_at, 0);
  EXPECT_LE(converged_at, 10.0);
  EXPECT_NEAR(est.value.time_offset_s, 0.015, 0.5e-3);
  EXPECT_NEAR(est.value.line_delay_s / (1.2 * kNominalLineDelay), 1.0, 0.03);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(est.value.gyro_bias[i], 0.01, 0.002) << "axis " << i;
  // The sigmas are honest: the errors within 4 of them.
  EXPECT_LE(std::abs(est.value.time_offset_s - 0.015), 4 * est.sigma.time_offset_s + 1e-5);
  EXPECT_LE(std::abs(est.value.line_delay_s - 1.2 * kNominalLineDelay), 4 * est.sigma.line_delay_s + 1e-7);
  EXPECT_GT(est.window.inliers, est.window.fitted * 8 / 10);
  EXPECT_LT(est.value.mount_rotation.norm(), 2e-3);  // none hidden: none found
  // No drift hidden: none beyond its sigma (ten seconds hold it to tens of ppm, not yet learned).
  EXPECT_LE(std::abs(est.value.drift_ppm), 4 * est.sigma.drift_ppm);
  EXPECT_NE(est.notes.drift.status, ValueStatus::Learned);
}

// Issue 36: the camera clock runs 100 ppm fast against the IMU's (a crystal's rate error within
// its specification): over a minute the offset walks by 6 ms. The offset is filtered alone
// until it walks away from its estimate (here at 14 s; a slower drift waits for 30 s of fits);
// a line through the fits so far takes the walk (a step would not fit it: FollowsAStep... stays a
// step), and from then on the estimator carries the drift as a rate beside the offset: the
// offset stays on the truth without a step, and the drift is learned to a few ppm. Without the
// drift the offset trailed the walk by up to 0.6 ms and restarted in a step every 15 s.
TEST(OnlineEstimator, LearnsTheClockDriftAsARateAndFollowsIt) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("OnlineEstimator.AGlobalShutterLearnsTheOffsetAndTheBias (the same windows, fits and filter)");
  SimConfig c = hand_held(11, 60);
  c.effects.drift_ppm = 100;
  const SimulatedRecording sim = simulate_recording(c);
  const double t0 = sim.rec.frames.front().t;  // the time model's T0
  auto truth = [&](double t) { return 0.015 + 100e-6 * (t - t0); };
  OnlineEstimator e(c.nominal, nominal_start());
  int steps = 0;
  double worst_before = 0, worst = 0;
  stream(sim.rec, e, 30, [&](double t, const OnlineEstimate& est) {
    show(t - c.start_time_s, est);
    const double err = std::abs(est.value.time_offset_s - truth(est.value.offset_at_s));
    if (t - t0 > 10 && t - t0 < 30) worst_before = std::max(worst_before, err);
    if (t - t0 < 40) return;
    steps += est.reason.find("a step") != std::string::npos;
    if (est.state == OnlineState::Converged) worst = std::max(worst, err);
  });
  const OnlineEstimate& est = e.estimate();
  std::printf("drift %.2f +- %.2f ppm (true 100), offset %.3f ms at %.1f s (true %.3f); worst offset error 10-30 s %.3f ms, "
              "after 40 s %.3f ms\n",
              est.value.drift_ppm, est.sigma.drift_ppm, est.value.time_offset_s * 1e3, est.value.offset_at_s - t0,
              truth(est.value.offset_at_s) * 1e3, worst_before * 1e3, worst * 1e3);
  ASSERT_EQ(est.state, OnlineState::Converged) << est.reason;
  EXPECT_EQ(steps, 0);
  EXPECT_LT(worst, 0.3e-3);
  EXPECT_NEAR(est.value.drift_ppm, 100, 10);
  EXPECT_LE(std::abs(est.value.drift_ppm - 100), 4 * est.sigma.drift_ppm + 0.5);
  EXPECT_EQ(est.notes.drift.status, ValueStatus::Learned);
}

// The same hand-held camera behind a 120-degree fisheye (pinhole-equi, its own calibration):
// the estimator's model goes through the lens (issue 35), so it converges to the same
// tolerances as through the pinhole.
TEST(OnlineEstimator, ConvergesThroughAFisheyeLens) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("OnlineEstimator.AGlobalShutterLearnsTheOffsetAndTheBias (the same fits through the pinhole)");
  SimConfig c = hand_held(17, 12);
  c.nominal.cam.fx = c.nominal.cam.fy = 320;  // 640 px wide: 60 degrees either side of the axis
  c.nominal.cam.dist = Distortion::equidistant(0.03, -0.01, 0.002, -0.0005);
  const SimulatedRecording sim = simulate_recording(c);
  OnlineEstimator e(c.nominal, nominal_start());
  stream(sim.rec, e, 30, [&](double t, const OnlineEstimate& est) { show(t - c.start_time_s, est); });
  const OnlineEstimate& est = e.estimate();
  ASSERT_EQ(est.state, OnlineState::Converged) << est.reason;
  EXPECT_NEAR(est.value.time_offset_s, 0.015, 0.5e-3);
  EXPECT_NEAR(est.value.line_delay_s / (1.2 * kNominalLineDelay), 1.0, 0.03);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(est.value.gyro_bias[i], 0.01, 0.002) << "axis " << i;
  EXPECT_LE(std::abs(est.value.time_offset_s - 0.015), 4 * est.sigma.time_offset_s + 1e-5);
}

// The IMU turned by about a degree on its mount beyond the nominal: the hand-held motion turns
// about every axis, so the mount shows, and is learned with the rest.
TEST(OnlineEstimator, LearnsTheMountRotationWhenTheMotionShowsIt) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("OnlineEstimator.AGlobalShutterLearnsTheOffsetAndTheBias (the same estimator, fitting the mount there too)");
  SimConfig c = hand_held(11, 12);
  const Vector3d mount(0.012, -0.009, 0.006);
  c.effects.mount_rotation = mount;
  const SimulatedRecording sim = simulate_recording(c);
  OnlineEstimator e(c.nominal, nominal_start());
  stream(sim.rec, e, 30, [&](double t, const OnlineEstimate& est) { show(t - c.start_time_s, est); });
  const OnlineEstimate& est = e.estimate();
  ASSERT_EQ(est.state, OnlineState::Converged) << est.reason;
  EXPECT_TRUE(est.mount_known);
  EXPECT_LT((est.value.mount_rotation - mount).norm(), 2e-3) << est.value.mount_rotation.transpose();
  EXPECT_NEAR(est.value.time_offset_s, 0.015, 0.5e-3);
  EXPECT_NEAR(est.value.line_delay_s / (1.2 * kNominalLineDelay), 1.0, 0.03);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(est.value.gyro_bias[i], 0.01, 0.002) << "axis " << i;
}

// Two recordings one after the other: the second's time offset 5 ms larger (its frames go on
// where the first's end; its frame numbers and gyro follow the first's).
Recording with_step(const SimulatedRecording& first, const SimulatedRecording& second) {
  Recording r = first.rec;
  const double t_join = second.rec.frames.front().t;
  for (FrameStamp f : second.rec.frames) f.frame += 1000000, r.frames.push_back(f);
  for (Match m : second.rec.matches) m.frame_a += 1000000, m.frame_b += 1000000, r.matches.push_back(m);
  r.gyro.erase(std::remove_if(r.gyro.begin(), r.gyro.end(), [&](const GyroSample& g) { return g.t >= t_join; }), r.gyro.end());
  for (const GyroSample& g : second.rec.gyro)
    if (g.t >= t_join) r.gyro.push_back(g);
  return r;
}

TEST(OnlineEstimator, FollowsAStepOfFiveMillisecondsWithinTenSeconds) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("OnlineEstimator.AGlobalShutterLearnsTheOffsetAndTheBias (the same windows and fits)");
  SimConfig a = hand_held(9, 12), b = hand_held(10, 14);
  b.start_time_s = a.start_time_s + 12 + 1 / a.nominal.frame_rate_hz;
  b.effects.time_offset_s = 0.020;
  const Recording rec = with_step(simulate_recording(a), simulate_recording(b));
  OnlineEstimator e(a.nominal, nominal_start());
  double before = 0, followed_at = -1;
  rsd::test::OnlineTrace trace;
  stream(rec, e, 30, [&](double t, const OnlineEstimate& est) {
    show(t - a.start_time_s, est);
    trace.t.push_back(t - a.start_time_s), trace.est.push_back(est);
    if (t < b.start_time_s) before = est.value.time_offset_s;
    else if (followed_at < 0 && std::abs(est.value.time_offset_s - 0.020) < 0.5e-3 && est.converged)
      followed_at = t - b.start_time_s;
  });
  figure("online-calibration-step.png", "the time offset steps by 5 ms at 12 s", trace,
         {true_calibration(0.015), true_calibration(0.020), b.start_time_s - a.start_time_s, kNominalLineDelay});
  EXPECT_NEAR(before, 0.015, 0.5e-3);
  EXPECT_GE(followed_at, 0) << "never followed the step";
  EXPECT_LE(followed_at, 10.0);
  EXPECT_NEAR(e.estimate().value.time_offset_s, 0.020, 0.5e-3);
}

// A glitch of the gyro shorter than a window (0.3 s of rates 0.2 rad/s off on every axis: a
// bad bus read) reaches the windows that overlap it; their fits lie far from the estimate, but
// no window a whole window later confirms a step: a converged estimate holds through them and
// stays converged, instead of restarting from a glitched fit.
TEST(OnlineEstimator, AGlitchShorterThanAWindowDoesNotRestartAConvergedEstimate) {
  const SimConfig c = hand_held(11, 16);
  Recording rec = simulate_recording(c).rec;
  const double t0 = c.start_time_s + 10;
  int glitched = 0;
  for (GyroSample& g : rec.gyro)
    if (g.t >= t0 && g.t < t0 + 0.3) g.w += Vector3d(0.2, -0.2, 0.2), ++glitched;
  ASSERT_GT(glitched, 50);
  OnlineEstimator e(c.nominal, nominal_start());
  bool converged_before = false;
  int updates_after = 0, held = 0, restarted = 0, unconverged = 0;
  stream(rec, e, 30, [&](double t, const OnlineEstimate& est) {
    show(t - c.start_time_s, est);
    if (t < t0) {
      converged_before = est.converged;  // the last update before the glitch
      return;
    }
    ++updates_after;
    held += est.reason.rfind("a fit far from the estimate", 0) == 0;
    restarted += est.reason.rfind("a step", 0) == 0;
    unconverged += !est.converged;
    EXPECT_NEAR(est.value.time_offset_s, 0.015, 0.5e-3) << t - c.start_time_s;
  });
  ASSERT_TRUE(converged_before);
  EXPECT_GE(updates_after, 5);
  EXPECT_GE(held, 1);  // the glitch reached the fits: the check is not vacuous
  EXPECT_EQ(restarted, 0);
  EXPECT_EQ(unconverged, 0);
}

// Issue 36: a user's first configuration gives no line delay (0: nobody measured it). The
// estimator still learns the offset and the bias, and asks whether the rows are read at
// different times at all: here they are (the same rolling shutter as above, 60 us a row), so
// the line delay is learned from 0 to the same tolerance.
TEST(OnlineEstimator, WithNoLineDelayGivenItFindsTheRowsRollingAndLearnsTheLineDelay) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("OnlineEstimator.AGlobalShutterLearnsTheOffsetAndTheBias (the same fits, the line delay given)");
  SimConfig c = hand_held(7, 14);
  c.nominal.time.line_delay_s = 0;
  const SimulatedRecording sim = simulate_recording(c);
  OnlineEstimator e(c.nominal, {0.0, 0.0, Vector3d::Zero()});
  EXPECT_EQ(e.estimate().shutter, Shutter::Unknown);
  EXPECT_EQ(e.estimate().rows, RowsSeen::Undecided);
  stream(sim.rec, e, 30, [&](double t, const OnlineEstimate& est) { show(t - c.start_time_s, est); });
  const OnlineEstimate& est = e.estimate();
  ASSERT_EQ(est.state, OnlineState::Converged) << est.reason;
  EXPECT_EQ(est.rows, RowsSeen::Rolling);
  EXPECT_NEAR(est.value.line_delay_s / (1.2 * kNominalLineDelay), 1.0, 0.03);
  EXPECT_LE(std::abs(est.value.line_delay_s - 1.2 * kNominalLineDelay), 4 * est.sigma.line_delay_s + 1e-7);
  EXPECT_NEAR(est.value.time_offset_s, 0.015, 0.5e-3);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(est.value.gyro_bias[i], 0.01, 0.002) << "axis " << i;
  EXPECT_EQ(est.notes.line_delay.status, ValueStatus::Learned) << est.notes.line_delay.why;
  EXPECT_EQ(est.notes.time_offset.status, ValueStatus::Learned);
  EXPECT_EQ(est.notes.gyro_bias.status, ValueStatus::Learned);
}

// The same unknown shutter on a camera whose rows are all read at once: the offset and the bias
// are learned, and the line delay is found to be 0 within its tolerance (a row's share of the
// frame period, 0.8 %), so the rows are said global.
TEST(OnlineEstimator, WithNoLineDelayGivenAGlobalShutterIsFoundGlobal) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("OnlineEstimator.AGlobalShutterLearnsTheOffsetAndTheBias (the same fits, the line delay fixed)");
  const SimConfig c = global_shutter(9, 12);
  const SimulatedRecording sim = simulate_recording(c);
  OnlineEstimator e(c.nominal, {0.0, 0.0, Vector3d::Zero()});
  stream(sim.rec, e, 30, [&](double t, const OnlineEstimate& est) { show(t - c.start_time_s, est); });
  const OnlineEstimate& est = e.estimate();
  ASSERT_EQ(est.state, OnlineState::Converged) << est.reason;
  EXPECT_EQ(est.rows, RowsSeen::Global);
  const double row_period = 1.0 / (c.nominal.frame_rate_hz * c.nominal.cam.height);
  EXPECT_LT(est.value.line_delay_s, 0.03 * row_period);  // readout under 1 ms of the 33 ms frame
  EXPECT_NEAR(est.value.time_offset_s, 0.015, 0.5e-3);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(est.value.gyro_bias[i], 0.01, 0.002) << "axis " << i;
  EXPECT_EQ(est.notes.time_offset.status, ValueStatus::Learned);
}

// A camera configured as global shutter: no line delay is fitted or reported (0, exactly, its
// note says why), the offset and the bias are learned as from a rolling shutter.
TEST(OnlineEstimator, AGlobalShutterLearnsTheOffsetAndTheBias) {
  const SimConfig c = global_shutter(11, 10);
  const SimulatedRecording sim = simulate_recording(c);
  OnlineEstimatorOptions o;
  o.global_shutter = true;
  OnlineEstimator e(c.nominal, {0.0, 0.0, Vector3d::Zero()}, o);
  EXPECT_EQ(e.estimate().shutter, Shutter::Global);
  stream(sim.rec, e, 30, [&](double t, const OnlineEstimate& est) {
    show(t - c.start_time_s, est);
    EXPECT_EQ(est.value.line_delay_s, 0.0);
    EXPECT_EQ(est.notes.line_delay.status, ValueStatus::Fixed);
  });
  const OnlineEstimate& est = e.estimate();
  ASSERT_EQ(est.state, OnlineState::Converged) << est.reason;
  EXPECT_EQ(est.rows, RowsSeen::Global);
  EXPECT_EQ(est.sigma.line_delay_s, 0.0);
  EXPECT_NE(est.notes.line_delay.why.find("global shutter"), std::string::npos) << est.notes.line_delay.why;
  EXPECT_NEAR(est.value.time_offset_s, 0.015, 0.5e-3);
  EXPECT_LE(std::abs(est.value.time_offset_s - 0.015), 4 * est.sigma.time_offset_s + 1e-5);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(est.value.gyro_bias[i], 0.01, 0.002) << "axis " << i;
  EXPECT_EQ(est.notes.gyro_bias.status, ValueStatus::Learned);
}

TEST(OnlineEstimator, AStaticCameraHoldsTheEstimate) {
  SimConfig c = hand_held(8, 30);
  c.motion_source = MotionSource::Constant;  // at rest: zero velocity, zero rate
  const SimulatedRecording sim = simulate_recording(c);
  const OnlineCalibration start{0.012, 1.1 * kNominalLineDelay, Vector3d(0.02, -0.01, 0.005)};
  OnlineEstimator e(c.nominal, start);
  int updates = 0;
  stream(sim.rec, e, 30, [&](double, const OnlineEstimate& est) {
    ++updates;
    EXPECT_EQ(est.state, OnlineState::Held);
    EXPECT_EQ(est.value.time_offset_s, start.time_offset_s);
    EXPECT_EQ(est.value.line_delay_s, start.line_delay_s);
    EXPECT_EQ(est.value.gyro_bias, start.gyro_bias);
  });
  EXPECT_GE(updates, 29);
  EXPECT_NE(e.estimate().reason.find("rotation"), std::string::npos) << e.estimate().reason;
  // Every value says it is held, and why.
  const OnlineNotes& n = e.estimate().notes;
  for (const ValueNote* v : {&n.time_offset, &n.line_delay, &n.gyro_bias, &n.mount_rotation}) {
    EXPECT_EQ(v->status, ValueStatus::Held);
    EXPECT_NE(v->why.find("rotation"), std::string::npos) << v->why;
  }
}

TEST(OnlineEstimator, RefusesBadOptionsNamingThem) {
  NominalModel n;
  OnlineEstimatorOptions o;
  o.window_s = 0;
  try {
    OnlineEstimator e(n, nominal_start(), o);
    FAIL() << "accepted window_s = 0";
  } catch (const std::invalid_argument& ex) {
    EXPECT_NE(std::string(ex.what()).find("window_s"), std::string::npos);
  }
  EXPECT_NO_THROW(OnlineEstimator(n, {0, 0, Vector3d::Zero()}));  // no line delay given: unknown
  try {
    OnlineEstimator e(n, {0, -1e-5, Vector3d::Zero()});
    FAIL() << "accepted a negative line delay";
  } catch (const std::invalid_argument& ex) {
    EXPECT_NE(std::string(ex.what()).find("line delay"), std::string::npos) << ex.what();
  }
  OnlineEstimatorOptions global;
  global.global_shutter = true;
  try {
    OnlineEstimator e(n, nominal_start(), global);
    FAIL() << "accepted a line delay for a global shutter";
  } catch (const std::invalid_argument& ex) {
    EXPECT_NE(std::string(ex.what()).find("global shutter"), std::string::npos) << ex.what();
  }
  OnlineEstimatorOptions short_span, wild_drift;
  short_span.drift_span_s = 1;  // shorter than the window
  wild_drift.max_drift_ppm = 5000;
  for (const auto& [opt, name] : {std::pair{short_span, "drift_span_s"}, std::pair{wild_drift, "max_drift_ppm"}}) {
    try {
      OnlineEstimator e(n, nominal_start(), opt);
      ADD_FAILURE() << "accepted a bad " << name;
    } catch (const std::invalid_argument& ex) {
      EXPECT_NE(std::string(ex.what()).find(name), std::string::npos) << ex.what();
    }
  }
}
