// The in-process Aravis fake's own stamp of each frame, the truth the tests hold the driver's and
// the pipeline's stamps to.
//
// The fake stamps a frame in software when its stream thread wakes (CLOCK_REALTIME in Aravis
// 0.8), so on a loaded host its frames fall off their grid of periods by milliseconds and the
// grid's period drifts by percents (2.8% under ASan beside four busy loops): a test that judged
// the stamps against the grid judged the host. What the driver promises is that a frame's stamp
// is the camera's own stamp of it, mapped onto CLOCK_MONOTONIC (and moved from the stamped
// instant to the first row's exposure start): that holds to the microsecond however late the
// stream thread woke.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <map>
#include <mutex>
#include <utility>
#include <vector>

namespace rsd::test {

// Thread contract: record() on Aravis' stream thread (the fake_fill hook) while a run lasts;
// expect_stamps_are_the_cameras() on the test's thread, at any time.
class FakeCameraStamps {
 public:
  void record(uint64_t frame_id, int64_t realtime_ns) {
    const std::lock_guard<std::mutex> lock(m_);
    realtime_ns_[frame_id] = realtime_ns;
  }

  // `stamps`: (camera frame id, stamp on CLOCK_MONOTONIC in ns) per delivered frame, each
  // expected `before_s` before the camera's own stamp of it (the exposure, for a camera that
  // stamps the start of exposure and a driver told that the stamped instant is its receipt
  // bound). Each stamp's error from that is the same for every frame to the microsecond (a
  // utime's resolution, the clocks' reading), and near zero.
  void expect_stamps_are_the_cameras(const std::vector<std::pair<uint64_t, int64_t>>& stamps, double before_s) {
    const std::lock_guard<std::mutex> lock(m_);
    const int64_t to_monotonic = monotonic_minus_realtime_ns();
    std::vector<double> err_us;
    for (const auto& [id, stamp_ns] : stamps) {
      const auto it = realtime_ns_.find(id);
      ASSERT_NE(it, realtime_ns_.end()) << "frame " << id << " delivered but never filled";
      err_us.push_back((stamp_ns - (it->second + to_monotonic)) * 1e-3 + before_s * 1e6);
    }
    ASSERT_FALSE(err_us.empty());
    std::vector<double> sorted = err_us;
    std::sort(sorted.begin(), sorted.end());
    const double median = sorted[sorted.size() / 2];
    EXPECT_LT(std::abs(median), 20.0) << "the stamps are off the camera's by a constant (us)";
    int exact = 0;
    for (const double e : err_us) exact += std::abs(e - median) < 20.0;
    EXPECT_GE(exact, static_cast<int>(err_us.size()) * 9 / 10)
        << "stamps that do not follow the camera's; errors (us) from " << sorted.front() << " to " << sorted.back();
  }

 private:
  // CLOCK_MONOTONIC minus CLOCK_REALTIME, from the tightest of a few bracketing reads.
  static int64_t monotonic_minus_realtime_ns() {
    const auto ns = [](clockid_t c) {
      timespec t{};
      clock_gettime(c, &t);
      return int64_t{t.tv_sec} * 1000000000 + t.tv_nsec;
    };
    int64_t best_width = INT64_MAX, offset = 0;
    for (int k = 0; k < 20; ++k) {
      const int64_t m0 = ns(CLOCK_MONOTONIC), r = ns(CLOCK_REALTIME), m1 = ns(CLOCK_MONOTONIC);
      if (m1 - m0 < best_width) best_width = m1 - m0, offset = (m0 + m1) / 2 - r;
    }
    return offset;
  }

  std::mutex m_;
  std::map<uint64_t, int64_t> realtime_ns_;  // the fake's stamp by frame id
};

}  // namespace rsd::test
