// The clock every frame and velocity stamp in rsd is on: CLOCK_MONOTONIC, in nanoseconds.
// Drivers convert their hardware stamps to it once; the daemon measures latency against it.
// Unix time (CLOCK_REALTIME) only labels a frame for others (bot_core.image_t.utime, as libbot2
// stamps it): it jumps when the clock is set, so no interval is ever measured on it.
#pragma once

#include <cstdint>
#include <ctime>

#include "dsp/core/frame.hpp"

namespace rsd::drivers {

inline int64_t monotonic_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

inline int64_t realtime_ns() {
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

// Gives a frame its Unix time, unless its source knew it (a replayed log's recorded stamp): the
// monotonic stamp moved by the clocks' offset now, which is exact up to the offset's change
// since the first row was read (NTP slews by at most 0.5 ms/s).
inline void stamp_wall_clock(dsp::FrameMeta& meta) {
  if (meta.wall_ns == 0) meta.wall_ns = meta.first_row_ns + (realtime_ns() - monotonic_ns());
}

}  // namespace rsd::drivers
