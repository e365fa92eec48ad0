// The clock every frame and velocity stamp in rsd is on: CLOCK_MONOTONIC, in nanoseconds.
// Drivers convert their hardware stamps to it once; the daemon measures latency against it.
#pragma once

#include <cstdint>
#include <ctime>

namespace rsd::drivers {

inline int64_t monotonic_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

}  // namespace rsd::drivers
