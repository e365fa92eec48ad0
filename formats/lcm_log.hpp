// LCM log files (the format lcm-logger writes and lcm-logplayer / lcm-spy read), read robustly
// and written without per-event heap allocation.
//
// An event is: sync word 0xEDA1DA01, event number (int64), timestamp (int64, us), channel
// length (int32), data length (int32), channel bytes, data bytes; all big-endian. LCM's own
// reader stops (or crashes) at the first damaged event; this one skips damaged regions and
// counts every skip with its reason, so the rest of a log still replays:
//  - a broken sync word: scan forward to the next sync word;
//  - absurd sizes (channel longer than LCM allows, data beyond the limit or the file): skip
//    the header and resynchronise;
//  - a truncated last event: stop there.
// Callers add the reasons only they can judge (unknown channel, wrong fingerprint, a
// message that does not decode) through skip(), so one summary covers the whole log.
//
// The only LCM log reader and writer in rsd: the daemon (replay source, --record), rsd-replay,
// rsd-extract, the tools' frame sources (rsd-calib) and rsd-sim's logs all use it.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

namespace rsd::formats {

inline constexpr uint32_t kLcmLogSync = 0xEDA1DA01u;

enum class LogSkip {
  BadSync,           // bytes that are not an event (a broken sync word); skipped to the next one
  AbsurdSize,        // channel or data length beyond the limits or the file
  Truncated,         // the file ends inside an event
  UnknownChannel,    // a channel the reader has no use for (callers decide)
  WrongFingerprint,  // the payload is a different LCM type than the channel's
  Undecodable,       // right type, but the payload does not decode (or is inconsistent)
  OutOfOrder,        // a frame whose first-row time does not come after the previous frame's
};
inline constexpr size_t kLogSkipKinds = 7;
const char* to_string(LogSkip s);

struct LogLimits {
  uint32_t max_channel = 63;             // LCM's LCM_MAX_CHANNEL_NAME_LENGTH
  uint32_t max_data = 256u << 20;        // 256 MiB: far beyond any frame rsd handles
  int max_messages_per_reason = 3;       // messages printed per reason; the rest only counted
};

struct LogEvent {
  uint64_t offset = 0;     // byte offset of the event's sync word in the file
  int64_t number = 0;      // the event number written in the log
  int64_t timestamp_us = 0;
  std::string channel;
  std::vector<uint8_t> data;  // reused between events: no allocation once large enough
};

class LcmLogReader {
 public:
  // Throws std::runtime_error naming the file if it cannot be opened.
  explicit LcmLogReader(const std::string& path, LogLimits limits = {});
  ~LcmLogReader();
  LcmLogReader(const LcmLogReader&) = delete;
  LcmLogReader& operator=(const LcmLogReader&) = delete;

  // The next intact event; false at the end of the file. Damaged regions are skipped,
  // counted and reported.
  bool next(LogEvent& ev);
  // Back to the start (counts are kept: they describe what the caller has seen).
  void rewind();

  // Counts a skip and reports it ("FILE: event at byte N: REASON: detail") through the
  // message handler (the first max_messages_per_reason of each reason).
  void skip(LogSkip reason, uint64_t offset, const std::string& detail);
  uint64_t skipped(LogSkip reason) const { return skips_[static_cast<size_t>(reason)]; }
  uint64_t skipped_total() const;
  // "2 broken sync word, 1 truncated" (empty when nothing was skipped).
  std::string skip_summary() const;
  // Where skip messages go; the default prints "rsd: MESSAGE" on stderr.
  void set_message_handler(std::function<void(const std::string&)> h) { message_ = std::move(h); }

  uint64_t position() const { return pos_; }
  uint64_t size() const { return size_; }
  const std::string& path() const { return path_; }

 private:
  bool read_exact(void* dst, size_t n);
  bool resync(uint64_t from);  // to the next sync word at or after `from`; false at EOF
  std::string path_;
  LogLimits limits_;
  std::FILE* f_ = nullptr;
  uint64_t pos_ = 0, size_ = 0;
  std::array<uint64_t, kLogSkipKinds> skips_{};
  std::function<void(const std::string&)> message_;
};

// Appends events to a log, from any thread (one event at a time under a mutex). No heap
// allocation per event: the header is assembled on the stack and written with stdio.
class LcmLogWriter {
 public:
  // Throws std::runtime_error naming the file if it cannot be created. `append` continues an
  // existing log (the daemon after a SIGHUP reload) instead of starting it afresh.
  explicit LcmLogWriter(const std::string& path, bool append = false);
  ~LcmLogWriter();
  LcmLogWriter(const LcmLogWriter&) = delete;
  LcmLogWriter& operator=(const LcmLogWriter&) = delete;
  // timestamp_us: the event's time (lcm-logger uses the wall clock; lcm-logplayer paces by
  // the differences). Returns false on I/O errors (counted in errors()).
  bool write(const char* channel, int64_t timestamp_us, const void* data, size_t size);
  void flush();
  // Any thread.
  uint64_t events() const { return events_.load(std::memory_order_relaxed); }
  uint64_t errors() const { return errors_.load(std::memory_order_relaxed); }
  // The system's reason for the newest failed write ("" if none failed): a full disk, a file
  // size limit.
  std::string last_error() const;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::FILE* f_ = nullptr;
  std::mutex mutex_;
  std::atomic<uint64_t> events_{0}, errors_{0};
  std::atomic<int> last_errno_{0};
};

// CLOCK_REALTIME in microseconds: what lcm-logger stamps events with.
int64_t wall_clock_us();

// Whether the file starts with an LCM log sync word.
bool looks_like_lcm_log(const std::string& path);

}  // namespace rsd::formats
