// The gyro samples' times estimated from their rates (dsp/diagnosis/gyro_stamps.hpp) against
// the true sampling times of a simulated hand's shake, and the orientation the diagnosis's
// gyro track integrates from them against the motion's own.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "dsp/diagnosis/gyro.hpp"
#include "dsp/diagnosis/gyro_stamps.hpp"
#include "dsp/sim/smooth_motion.hpp"

using namespace rsd::dsp;
using Eigen::Vector3d;

namespace test_gyro_stamps {  // shares a unity unit (tests/CMakeLists.txt)

// A hand's shake: 0.25 rad at 1.2 Hz, rates to about 2 rad/s and their change to 14 rad/s^2.
SmoothPose shake() {
  return SmoothPose{Vector3d::Zero(), Eigen::Matrix3d::Identity(), SmoothSignal3(3, Vector3d::Zero(), 1.0),
                    SmoothSignal3(4, Vector3d::Constant(0.25), 1.2)};
}

struct Sampled {
  std::vector<double> truth;     // when each sample was taken
  std::vector<GyroSample> gyro;  // as stamped, clean_gyro's order
};

// An irregular gyro (20-200 Hz) with 2 mrad/s of noise whose stamps are off the sampling by
// `jitter_s` (normal), optionally with a 0.3 s gap at `gap_at`.
Sampled sample(const SmoothPose& pose, double jitter_s, unsigned seed, double gap_at = -1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> rate(20, 200);
  std::normal_distribution<double> n(0, 1);
  Sampled s;
  for (double t = 0; t <= 10.0; t += 1.0 / rate(rng)) {
    if (gap_at > 0 && t > gap_at && t < gap_at + 0.3) continue;
    s.truth.push_back(t);
    s.gyro.push_back({t + jitter_s * n(rng), pose.body_rate(t) + 0.002 * Vector3d(n(rng), n(rng), n(rng))});
  }
  return s;
}

double stamp_error_rms(const Sampled& s, const std::vector<GyroSample>& g) {
  double e = 0;
  for (size_t k = 0; k < g.size(); ++k) e += std::pow(g[k].t - s.truth[k], 2);
  return std::sqrt(e / static_cast<double>(g.size()));
}

// RMS error of the track's rotation over one frame interval (33 ms: what a match transfers
// through) against the motion's, on a grid of start times.
double frame_rotation_error(const SmoothPose& pose, const std::vector<GyroSample>& g) {
  const GyroTrack track(g, Vector3d::Zero(), Eigen::Matrix3d::Identity());
  double e = 0;
  int n = 0;
  for (double t = 0.2; t < 9.7; t += 2e-3, ++n) {
    const Eigen::Quaterniond truth = pose.orientation(t).conjugate() * pose.orientation(t + 1.0 / 30);
    const Eigen::Quaterniond got(track.camera_at(t).transpose() * track.camera_at(t + 1.0 / 30));
    e += std::pow(truth.angularDistance(got), 2);
  }
  return std::sqrt(e / n);
}

bool increasing(const std::vector<GyroSample>& g) {
  for (size_t k = 1; k < g.size(); ++k)
    if (!(g[k].t > g[k - 1].t)) return false;
  return true;
}

constexpr double kMaxInterval = 0.075;  // 1.5 x the longest sampling interval, as the diagnosis's gap limit

}  // namespace test_gyro_stamps

using namespace test_gyro_stamps;

TEST(GyroStamps, JitteredStampsMoveTowardsTheSamplingTimes) {
  // Half a millisecond of jitter against rates that change by up to 14 rad/s^2: 7 mrad/s of
  // error along the rate's slope, three times the noise. The spread is measured from the rates
  // alone; the times are brought a quarter nearer the truth, and of the rotation error over a
  // frame that the jitter adds to the noise's (its variance beyond the stamps-on-time track's)
  // a quarter to a half goes (seeds 1-3: 25, 51, 41%).
  const SmoothPose pose = shake();
  for (unsigned seed : {1u, 2u, 3u}) {
    const Sampled s = sample(pose, 0.0005, seed);
    const std::vector<GyroSample> jittered = clean_gyro(s.gyro);
    ASSERT_EQ(jittered.size(), s.truth.size());  // no two stamps swapped at 0.5 ms and 5 ms intervals
    const GyroStamps est = estimate_gyro_stamps(jittered, kMaxInterval);
    const double before = stamp_error_rms(s, jittered), after = stamp_error_rms(s, est.gyro);
    std::vector<GyroSample> on_time = jittered;
    for (size_t k = 0; k < on_time.size(); ++k) on_time[k].t = s.truth[k];
    const double rot_jittered = frame_rotation_error(pose, jittered), rot_est = frame_rotation_error(pose, est.gyro),
                 rot_true = frame_rotation_error(pose, on_time);
    std::printf("seed %u: jitter measured %.3f ms; stamp error %.3f -> %.3f ms (moved %.3f); rotation over a frame "
                "%.4f -> %.4f mrad (stamps on time: %.4f)\n",
                seed, 1e3 * est.spread.jitter_s, 1e3 * before, 1e3 * after, 1e3 * est.spread.moved_rms_s, 1e3 * rot_jittered,
                1e3 * rot_est, 1e3 * rot_true);
    EXPECT_NEAR(est.spread.jitter_s, 0.0005, 0.0001);
    EXPECT_LT(after, 0.8 * before);
    auto excess = [&](double rot) { return rot * rot - rot_true * rot_true; };
    EXPECT_LT(excess(rot_est), 0.8 * excess(rot_jittered));
    EXPECT_GT(rot_jittered, 1.5 * rot_true);  // the jitter matters here at all
    EXPECT_TRUE(increasing(est.gyro));
  }
}

TEST(GyroStamps, StampsOnTimeStayWhereTheyAre) {
  // No jitter: the rates' departures along the slope are the noise's and the curve's own, the
  // measured spread a few hundredths of a millisecond; a time moves by as little, and the
  // rotation over a frame is as good as from the stamps.
  const SmoothPose pose = shake();
  for (unsigned seed : {1u, 2u, 3u}) {
    const Sampled s = sample(pose, 0.0, seed);
    const std::vector<GyroSample> g = clean_gyro(s.gyro);
    const GyroStamps est = estimate_gyro_stamps(g, kMaxInterval);
    const double rot = frame_rotation_error(pose, g), rot_est = frame_rotation_error(pose, est.gyro);
    std::printf("seed %u: jitter measured %.3f ms, moved %.4f ms; rotation over a frame %.4f -> %.4f mrad\n", seed,
                1e3 * est.spread.jitter_s, 1e3 * est.spread.moved_rms_s, 1e3 * rot, 1e3 * rot_est);
    EXPECT_LT(est.spread.jitter_s, 0.0001);
    EXPECT_LT(est.spread.moved_rms_s, 0.00003);
    EXPECT_LT(rot_est, 1.02 * rot);
  }
}

TEST(GyroStamps, ASteadyTurnHoldsNoTimeAndMovesNothing) {
  // A constant rate: a sample's time changes nothing it reads, whatever its stamp's error.
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0, 1);
  std::vector<GyroSample> g;
  for (double t = 0; t <= 5.0; t += 0.005) g.push_back({t + 0.0005 * n(rng), Vector3d(0.3, -0.1, 0.2) + 0.002 * Vector3d(n(rng), n(rng), n(rng))});
  const GyroStamps est = estimate_gyro_stamps(clean_gyro(g), kMaxInterval);
  EXPECT_EQ(est.spread.moved_rms_s, 0.0);
}

TEST(GyroStamps, SamplesBesideAGapKeepTheirStamps) {
  // Across a gap the curve through the neighbours is a guess: the two samples on either side of
  // a 0.3 s gap keep their stamps exactly; the others still move.
  const SmoothPose pose = shake();
  const Sampled s = sample(pose, 0.0005, 5, 4.0);
  const std::vector<GyroSample> g = clean_gyro(s.gyro);
  const GyroStamps est = estimate_gyro_stamps(g, kMaxInterval);
  size_t gap = 0;
  for (size_t k = 1; k < g.size(); ++k)
    if (g[k].t - g[k - 1].t > kMaxInterval) gap = k;
  ASSERT_GT(gap, 2u);
  for (size_t k = gap - 2; k < gap + 2; ++k) EXPECT_EQ(est.gyro[k].t, g[k].t) << "sample " << k;
  EXPECT_EQ(est.gyro.front().t, g.front().t);
  EXPECT_EQ(est.gyro.back().t, g.back().t);
  EXPECT_GT(est.spread.moved_rms_s, 0.0001);
  EXPECT_TRUE(increasing(est.gyro));
}

TEST(GyroStamps, ANoisyGyroOnASteadyCameraShowsNoJitter) {
  // A drone's gimbal camera: a 400 Hz gyro whose rates are mostly its propellers' vibration,
  // stronger about one axis than the others (the Karma clip's: about 110, 45 and 13 mrad/s
  // sample to sample), over a slow pan. Where the noise makes the slope, the slope points
  // along the noisiest axis, and the departures along it are that axis's noise while those
  // across it are the quieter axes': measured along such slopes the Karma clip's gyro showed
  // 2.7 ms of "jitter" at 2.55 ms sampling. Only slopes clear of their noise measure the
  // stamps: none shows here, and nothing moves.
  std::mt19937 rng(6);
  std::normal_distribution<double> n(0, 1);
  std::vector<GyroSample> g;
  for (double t = 0; t <= 12.0; t += 0.0025)
    g.push_back({t, Vector3d(0.1 * std::sin(0.5 * t), 0.02, 0.05) + Vector3d(0.045 * n(rng), 0.013 * n(rng), 0.11 * n(rng))});
  const GyroStamps est = estimate_gyro_stamps(clean_gyro(g), kMaxInterval);
  std::printf("spread %.3f ms, moved %.4f ms\n", 1e3 * est.spread.jitter_s, 1e3 * est.spread.moved_rms_s);
  EXPECT_LT(est.spread.jitter_s, 0.0002);
  EXPECT_EQ(est.spread.moved_rms_s, 0.0);
}

TEST(GyroStamps, StampsOffByMuchOfTheIntervalAreNotMadeWorse) {
  // A regular 200 Hz gyro stamped 2 ms off (RMS): neighbours come swapped, which times kept
  // each between its neighbours cannot undo, and the spread measured is well short of the
  // truth. What moves must not make the rotation over a frame worse.
  const SmoothPose pose = shake();
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0, 1);
  std::vector<GyroSample> g;
  for (double t = 0; t <= 10.0; t += 0.005) g.push_back({t + 0.002 * n(rng), pose.body_rate(t)});
  const std::vector<GyroSample> c = clean_gyro(g);
  const GyroStamps est = estimate_gyro_stamps(c, kMaxInterval);
  const double before = frame_rotation_error(pose, c), after = frame_rotation_error(pose, est.gyro);
  std::printf("spread %.3f ms, moved %.4f ms; rotation over a frame %.4f -> %.4f mrad\n", 1e3 * est.spread.jitter_s,
              1e3 * est.spread.moved_rms_s, 1e3 * before, 1e3 * after);
  EXPECT_LE(after, 1.01 * before);
  EXPECT_TRUE(increasing(est.gyro));
}
