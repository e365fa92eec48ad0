// A time line: stamps from outside (a camera's frames, an IMU's samples) that must increase,
// each at most `max_gap` after the one before. A stamp that does not fit (a wild one, a repeat,
// a step back, a jump too far) is held aside, not taken. If the next stamps go on from the
// current line, it was a stray and costs nothing more. If instead `confirm` stamps in a row form
// a line of their own (each after the one before, within max_gap: the clock restarted or jumped,
// or the current line began with a stray), that line replaces the current one. One wild stamp
// therefore never stops a stream, and a real change of clock is followed within `confirm` stamps.
//
// Plain arithmetic on int64 nanoseconds that never overflows, whatever the stamps. Not thread
// safe: one writer (the thread receiving the stamps).
#pragma once

#include <cstdint>

namespace rsd::dsp {

class TimeLine {
 public:
  enum class Verdict {
    Continues,  // taken: on the current line (or the first stamp)
    Held,       // held aside (held() of them now, this one the newest)
    Replaces,   // taken: the held stamps and this one are the new line (held() was confirm - 1)
  };

  // allow_equal: a stamp equal to the newest continues the line (log events of one instant).
  TimeLine(int64_t max_gap, int confirm, bool allow_equal = false)
      : max_gap_(max_gap), confirm_(confirm < 1 ? 1 : confirm), allow_equal_(allow_equal) {}

  Verdict offer(int64_t t) {
    if (newest_ == kNone || follows(t, newest_)) {
      held_ = 0;
      newest_ = t;
      return Verdict::Continues;
    }
    if (held_ == 0 || !follows(t, last_held_)) held_ = 0;  // the held ones were strays after all
    ++held_;
    last_held_ = t;
    if (held_ < confirm_) return Verdict::Held;
    held_ = 0;
    newest_ = t;
    return Verdict::Replaces;
  }

  // The newest stamp taken; kNone before the first.
  int64_t newest() const { return newest_; }
  // Stamps held aside in a row since the last one taken.
  int held() const { return held_; }
  int confirm() const { return confirm_; }
  int64_t max_gap() const { return max_gap_; }
  void reset() { newest_ = kNone, held_ = 0; }

  static constexpr int64_t kNone = INT64_MIN;

 private:
  // t after `before` by at most max_gap (the difference taken unsigned: exact, as t >= before).
  bool follows(int64_t t, int64_t before) const {
    if (t == before) return allow_equal_;
    return t > before && static_cast<uint64_t>(t) - static_cast<uint64_t>(before) <= static_cast<uint64_t>(max_gap_);
  }

  int64_t max_gap_;
  int confirm_;
  bool allow_equal_;
  int64_t newest_ = kNone;
  int64_t last_held_ = 0;
  int held_ = 0;
};

}  // namespace rsd::dsp
