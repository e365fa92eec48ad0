// How often a repeating fault is logged: at the first, then whenever its count has grown
// tenfold since the last line, so that a flood is seen growing without a line per event.
//
// Thread contract: one thread calls due().
#pragma once

#include <cstdint>

namespace rsd::drivers {

class TenfoldLog {
 public:
  // Whether a (never decreasing) count of `n` deserves a line now.
  bool due(uint64_t n) {
    if (n == 0 || (said_ > 0 && n < 10 * said_)) return false;
    said_ = n;
    return true;
  }

 private:
  uint64_t said_ = 0;
};

}  // namespace rsd::drivers
