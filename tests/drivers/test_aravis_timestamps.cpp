// The Aravis stamp rules against synthetic stamp sequences whose truth is known: a camera
// clock with a known offset and rate error, host receipts late by a known floor plus random
// jitter (and spikes), 16-bit frame ids that wrap.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>

#include "drivers/aravis_timestamps.hpp"

using namespace rsd::drivers;

namespace {

constexpr int64_t kMs = 1000000, kUs = 1000;

int64_t abs_ns(int64_t v) { return v < 0 ? -v : v; }

// A camera whose clock reads camera_ns = (t - t0) * (1 - drift) + c0 at host time t, so host
// time = c0-relative camera time * (1 + ~drift): frames every period, received late by a
// positive exponential jitter (mean jitter_mean) on top of a floor.
struct SyntheticCamera {
  int64_t c0 = 1'700'000'000'000'000'000;  // a CLOCK_REALTIME-like camera clock
  int64_t host0 = 5'000'000'000'000;       // CLOCK_MONOTONIC at the first frame
  double period_s = 0.01;
  double drift = 0;  // host seconds per camera second, minus 1
  int64_t floor_ns = 0;
  double jitter_mean_s = 300e-6;
  std::mt19937_64 rng{42};

  int64_t camera(int i) const { return c0 + std::llround(i * period_s * 1e9); }
  int64_t truth_host(int64_t camera_ns) const {
    return host0 + std::llround(static_cast<double>(camera_ns - c0) * (1 + drift));
  }
  int64_t receipt(int i) {
    std::exponential_distribution<double> jitter(1.0 / jitter_mean_s);
    return truth_host(camera(i)) + floor_ns + std::llround(jitter(rng) * 1e9);
  }
};

// Largest |mapped - truth| over frames [from, to), feeding every frame.
int64_t max_error(CameraClockMapper& m, SyntheticCamera& cam, int from, int to) {
  int64_t worst = 0;
  for (int i = 0; i < to; ++i) {
    const int64_t mapped = m.add(cam.camera(i), cam.receipt(i));
    if (i >= from) worst = std::max(worst, abs_ns(mapped - cam.truth_host(cam.camera(i))));
  }
  return worst;
}

}  // namespace

TEST(HostStamp, StampsBeyondTheWindowAreAbsent) {
  // guint64 stamps through dsp::Stamp: within 2^61 ns kept, beyond (or negative once signed) 0.
  EXPECT_EQ(checked_stamp(123'456'789), 123'456'789);
  EXPECT_EQ(checked_stamp(std::uint64_t{1} << 61), std::int64_t{1} << 61);
  EXPECT_EQ(checked_stamp((std::uint64_t{1} << 61) + 1), 0);
  EXPECT_EQ(checked_stamp(UINT64_MAX), 0);
  EXPECT_EQ(checked_stamp(std::uint64_t{1} << 63), 0);
}

TEST(HostStamp, RealtimeStampMovesOntoMonotonic) {
  const HostClocks now{1'700'000'000'123'456'789, 5'000'000'000'000};
  // Received 3 ms ago on CLOCK_REALTIME: 3 ms ago on CLOCK_MONOTONIC.
  EXPECT_EQ(host_stamp_to_monotonic(now.realtime_ns - 3 * kMs, now), now.monotonic_ns - 3 * kMs);
  // A stamp already on CLOCK_MONOTONIC stays; a missing stamp is "now".
  EXPECT_EQ(host_stamp_to_monotonic(now.monotonic_ns - 7 * kMs, now), now.monotonic_ns - 7 * kMs);
  EXPECT_EQ(host_stamp_to_monotonic(0, now), now.monotonic_ns);
}

TEST(HostStamp, ReadsBothClocksTogether) {
  const HostClocks a = read_host_clocks();
  const HostClocks b = read_host_clocks();
  // CLOCK_REALTIME - CLOCK_MONOTONIC is the same to well within a millisecond between reads.
  EXPECT_NEAR(static_cast<double>((a.realtime_ns - a.monotonic_ns) - (b.realtime_ns - b.monotonic_ns)), 0.0, 1e6);
  EXPECT_GE(b.monotonic_ns, a.monotonic_ns);
}

// A thread preempted for 200 us between a bracket's first monotonic read and its realtime read
// puts the mid-point 100 us before the realtime read's instant; the tight bracket read after it
// gives the clocks' true difference, and it is the one taken, whichever comes first.
TEST(HostStamp, TheNarrowestBracketIsTaken) {
  const int64_t offset = 1'700'000'000'000'000'000;  // CLOCK_REALTIME - CLOCK_MONOTONIC
  const ClockBracket preempted{1'000'000, 1'200'050 + offset, 1'200'100};
  const ClockBracket tight{1'300'000, 1'300'050 + offset, 1'300'100};
  for (const auto& pair : {std::array{preempted, tight}, std::array{tight, preempted}}) {
    const HostClocks c = from_narrowest(pair.data(), pair.size());
    EXPECT_EQ(c.realtime_ns - c.monotonic_ns, offset);
  }
  const HostClocks alone = from_narrowest(&preempted, 1);
  EXPECT_EQ(alone.realtime_ns - alone.monotonic_ns, offset + 100'000);  // what one bracket alone gave
}

TEST(ReceiptModel, ExposureStartStampIsTheFirstRowAndLeadsReceiptByExposure) {
  ReceiptModel m;
  m.stamp = CameraStamp::ExposureStart;
  m.exposure_s = 0.004;
  m.leader_delay_s = 0.0015;
  EXPECT_EQ(m.receipt_delay_ns(), 5'500'000);
  EXPECT_EQ(m.first_row_ns(123'456'789), 123'456'789);
}

TEST(ReceiptModel, ExposureEndStampIsExposureAfterTheFirstRow) {
  ReceiptModel m;
  m.stamp = CameraStamp::ExposureEnd;
  m.exposure_s = 0.004;
  m.leader_delay_s = 0.0015;
  EXPECT_EQ(m.receipt_delay_ns(), 1'500'000);
  EXPECT_EQ(m.first_row_ns(123'456'789), 119'456'789);
}

TEST(CameraClockMapper, RecoversOffsetUnderJitter) {
  SyntheticCamera cam;
  CameraClockMapper m;
  // 300 us mean jitter; after 50 frames the envelope is within a few us of the truth.
  const int64_t worst = max_error(m, cam, 50, 600);
  std::printf("offset only: worst error %.1f us (jitter mean 300 us)\n", worst / 1e3);
  EXPECT_LE(worst, 50 * kUs);
  std::printf("offset only: drift estimate %.2f ppm (truth 0)\n", m.drift() * 1e6);
  EXPECT_EQ(m.resets(), 0u);
  EXPECT_NEAR(m.drift(), 0.0, 5e-6);
}

TEST(CameraClockMapper, FirstFrameIsItsOwnReceipt) {
  SyntheticCamera cam;
  CameraClockMapper m;
  const int64_t r = cam.receipt(0);
  EXPECT_EQ(m.add(cam.camera(0), r), r);
  EXPECT_EQ(m.size(), 1u);
}

TEST(CameraClockMapper, FollowsCrystalDrift) {
  SyntheticCamera cam;
  cam.drift = 80e-6;
  CameraClockMapper m;
  // The window (1024 frames, 10.24 s) is full from frame 1024 on.
  const int64_t worst = max_error(m, cam, 1024, 4000);
  std::printf("80 ppm drift: worst error %.1f us, drift estimate %.2f ppm\n", worst / 1e3, m.drift() * 1e6);
  EXPECT_NEAR(m.drift(), 80e-6, 5e-6);
  EXPECT_LE(worst, 50 * kUs);

  // Without the rate, the window's minimum lags the newest frame by drift x window span.
  SyntheticCamera same;
  same.drift = 80e-6;
  ClockMapperOptions no_rate;
  no_rate.max_drift = 0;
  CameraClockMapper flat(no_rate);
  const int64_t flat_worst = max_error(flat, same, 1024, 4000);
  std::printf("80 ppm drift, rate not fitted: worst error %.1f us\n", flat_worst / 1e3);
  EXPECT_GE(flat_worst, 600 * kUs);  // 80e-6 x 10.24 s = 819 us at the window's newest end
}

TEST(CameraClockMapper, IgnoresLatencySpikes) {
  SyntheticCamera cam;
  cam.drift = -50e-6;
  CameraClockMapper m;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  int64_t worst = 0;
  for (int i = 0; i < 4000; ++i) {
    int64_t r = cam.receipt(i);
    if (u(rng) < 0.05) r += std::llround((0.02 + 0.18 * u(rng)) * 1e9);  // 5% late by 20..200 ms
    const int64_t mapped = m.add(cam.camera(i), r);
    if (i >= 1024) worst = std::max(worst, abs_ns(mapped - cam.truth_host(cam.camera(i))));
  }
  std::printf("5%% spikes of 20..200 ms, -50 ppm: worst error %.1f us, drift estimate %.2f ppm\n", worst / 1e3,
              m.drift() * 1e6);
  EXPECT_NEAR(m.drift(), -50e-6, 5e-6);
  EXPECT_LE(worst, 50 * kUs);
  EXPECT_EQ(m.resets(), 0u);
}

TEST(CameraClockMapper, HostBoundFloorIsCarriedThrough) {
  // The mapping is the least-late receipt: a constant floor the caller did not subtract
  // shows up whole in the result (this is what ReceiptModel is for).
  SyntheticCamera cam;
  cam.floor_ns = 2 * kMs;
  CameraClockMapper m;
  for (int i = 0; i < 500; ++i) m.add(cam.camera(i), cam.receipt(i));
  const int64_t c = cam.camera(500);
  EXPECT_NEAR(static_cast<double>(m.to_host(c) - cam.truth_host(c)), 2e6, 30e3);
}

TEST(CameraClockMapper, RestartsWhenTheCameraClockResets) {
  SyntheticCamera cam;
  CameraClockMapper m;
  for (int i = 0; i < 500; ++i) m.add(cam.camera(i), cam.receipt(i));
  // The camera reboots: its clock starts again near zero, 500 frames on.
  SyntheticCamera rebooted = cam;
  rebooted.c0 = 1000;
  rebooted.host0 = cam.truth_host(cam.camera(500));
  int64_t worst = 0;
  for (int i = 0; i < 300; ++i) {
    const int64_t mapped = m.add(rebooted.camera(i), rebooted.receipt(i));
    if (i >= 50) worst = std::max(worst, abs_ns(mapped - rebooted.truth_host(rebooted.camera(i))));
  }
  EXPECT_EQ(m.resets(), 1u);
  EXPECT_LE(worst, 50 * kUs);
}

TEST(CameraClockMapper, RejectsATooSmallWindow) {
  ClockMapperOptions o;
  o.window = 1;
  EXPECT_THROW(CameraClockMapper{o}, std::invalid_argument);
}

TEST(FrameCounter, GigEVisionBlockIdsWrapFrom65535To1) {
  FrameCounter c;
  EXPECT_EQ(c.next(65533), 65533u);
  EXPECT_EQ(c.next(65534), 65534u);
  EXPECT_EQ(c.next(65535), 65535u);
  EXPECT_EQ(c.next(1), 65536u);
  EXPECT_EQ(c.next(2), 65537u);
  EXPECT_EQ(c.restarts(), 0u);
}

TEST(FrameCounter, GapsAcrossTheWrapAreDrops) {
  FrameCounter c;
  c.next(65534);
  EXPECT_EQ(c.next(2), 65534u + 3);  // 65535 and 1 were dropped
}

TEST(FrameCounter, CounterRestartContinuesByOne) {
  FrameCounter c;
  c.next(500);
  c.next(501);
  EXPECT_EQ(c.next(1), 502u);  // acquisition restarted: not 65000 frames dropped
  EXPECT_EQ(c.next(2), 503u);
  EXPECT_EQ(c.restarts(), 1u);
}

TEST(FrameCounter, WideIdsDoNotWrap) {
  FrameCounter c;
  c.next(100000);
  EXPECT_EQ(c.next(100001), 100001u);
  EXPECT_EQ(c.next(100005), 100005u);
  EXPECT_EQ(c.next(7), 100006u);
  EXPECT_EQ(c.restarts(), 1u);
}
