#include "formats/lcm_log.hpp"

#include <cerrno>
#include <cstring>
#include <ctime>
#include <stdexcept>
#include <sys/stat.h>

namespace rsd::formats {

namespace {

uint32_t be32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) << 24 | static_cast<uint32_t>(p[1]) << 16 | static_cast<uint32_t>(p[2]) << 8 | p[3];
}
uint64_t be64(const uint8_t* p) { return static_cast<uint64_t>(be32(p)) << 32 | be32(p + 4); }
void put32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (24 - 8 * i));
}
void put64(uint8_t* p, uint64_t v) {
  put32(p, static_cast<uint32_t>(v >> 32));
  put32(p + 4, static_cast<uint32_t>(v));
}

// A channel name is printable ASCII: anything else means the header is garbage.
bool printable(const std::string& s) {
  for (unsigned char c : s)
    if (c < 0x20 || c > 0x7e) return false;
  return true;
}

constexpr size_t kHeader = 4 + 8 + 8 + 4 + 4;

}  // namespace

const char* to_string(LogSkip s) {
  switch (s) {
    case LogSkip::BadSync: return "broken sync word";
    case LogSkip::AbsurdSize: return "absurd size";
    case LogSkip::Truncated: return "truncated";
    case LogSkip::UnknownChannel: return "unknown channel";
    case LogSkip::WrongFingerprint: return "wrong fingerprint";
    case LogSkip::Undecodable: return "undecodable";
    case LogSkip::OutOfOrder: return "out of order";
  }
  return "?";
}

LcmLogReader::LcmLogReader(const std::string& path, LogLimits limits) : path_(path), limits_(limits) {
  f_ = std::fopen(path.c_str(), "rb");
  if (!f_) throw std::runtime_error(path + ": cannot open LCM log: " + std::strerror(errno));
  struct stat st {};
  if (fstat(fileno(f_), &st) == 0) size_ = static_cast<uint64_t>(st.st_size);
  message_ = [](const std::string& m) { std::fprintf(stderr, "rsd: %s\n", m.c_str()); };
}

LcmLogReader::~LcmLogReader() {
  if (f_) std::fclose(f_);
}

void LcmLogReader::rewind() {
  std::fseek(f_, 0, SEEK_SET);
  pos_ = 0;
}

bool LcmLogReader::read_exact(void* dst, size_t n) {
  const size_t got = std::fread(dst, 1, n, f_);
  pos_ += got;
  return got == n;
}

void LcmLogReader::skip(LogSkip reason, uint64_t offset, const std::string& detail) {
  const uint64_t n = ++skips_[static_cast<size_t>(reason)];
  if (!message_ || n > static_cast<uint64_t>(limits_.max_messages_per_reason)) return;
  std::string m = path_ + ": event at byte " + std::to_string(offset) + ": " + to_string(reason);
  if (!detail.empty()) m += ": " + detail;
  if (n == static_cast<uint64_t>(limits_.max_messages_per_reason)) m += " (further ones only counted)";
  message_(m);
}

uint64_t LcmLogReader::skipped_total() const {
  uint64_t n = 0;
  for (uint64_t c : skips_) n += c;
  return n;
}

std::string LcmLogReader::skip_summary() const {
  std::string s;
  for (size_t i = 0; i < kLogSkipKinds; ++i) {
    if (!skips_[i]) continue;
    if (!s.empty()) s += ", ";
    s += std::to_string(skips_[i]) + " " + to_string(static_cast<LogSkip>(i));
  }
  return s;
}

bool LcmLogReader::resync(uint64_t from) {
  if (fseeko(f_, static_cast<off_t>(from), SEEK_SET) != 0) return false;
  pos_ = from;
  uint32_t window = 0;
  int have = 0;
  for (int c; (c = std::getc(f_)) != EOF;) {
    window = window << 8 | static_cast<uint32_t>(c);
    ++pos_;
    if (++have >= 4 && window == kLcmLogSync) {
      pos_ -= 4;
      fseeko(f_, static_cast<off_t>(pos_), SEEK_SET);
      return true;
    }
  }
  return false;
}

bool LcmLogReader::next(LogEvent& ev) {
  for (;;) {
    const uint64_t off = pos_;
    uint8_t h[kHeader];
    const size_t got = std::fread(h, 1, kHeader, f_);
    pos_ += got;
    if (got == 0) return false;  // a clean end
    if (got >= 4 && be32(h) != kLcmLogSync) {
      const bool found = resync(off + 1);
      skip(LogSkip::BadSync, off, found ? "resynchronised at byte " + std::to_string(pos_)
                                        : "no further event in the file");
      if (!found) return false;
      continue;
    }
    if (got < kHeader) {
      skip(LogSkip::Truncated, off, "the file ends inside the event header");
      return false;
    }
    const int64_t number = static_cast<int64_t>(be64(h + 4));
    const int64_t ts = static_cast<int64_t>(be64(h + 12));
    const uint32_t chan_len = be32(h + 20), data_len = be32(h + 24);
    const uint64_t end = off + kHeader + chan_len + static_cast<uint64_t>(data_len);
    if (chan_len == 0 || chan_len > limits_.max_channel || data_len > limits_.max_data) {
      skip(LogSkip::AbsurdSize, off, "channel length " + std::to_string(static_cast<int32_t>(chan_len)) +
                                         ", data length " + std::to_string(static_cast<int32_t>(data_len)));
      if (!resync(off + 4)) return false;
      continue;
    }
    if (size_ && end > size_) {
      // Either the file was cut inside this event or the length is corrupt: if another
      // event follows, the length lied; otherwise the log is truncated here.
      const bool found = resync(off + 4);
      skip(found ? LogSkip::AbsurdSize : LogSkip::Truncated, off,
           "data length " + std::to_string(data_len) + " runs past the end of the file (" + std::to_string(size_) + " bytes)");
      if (!found) return false;
      continue;
    }
    ev.channel.resize(chan_len);
    ev.data.resize(data_len);
    if (!read_exact(ev.channel.data(), chan_len) || !read_exact(ev.data.data(), data_len)) {
      skip(LogSkip::Truncated, off, "the file ends inside the event");
      return false;
    }
    if (!printable(ev.channel)) {
      skip(LogSkip::BadSync, off, "channel name is not text");
      if (!resync(off + 4)) return false;
      continue;
    }
    ev.offset = off;
    ev.number = number;
    ev.timestamp_us = ts;
    return true;
  }
}

LcmLogWriter::LcmLogWriter(const std::string& path, bool append) : path_(path) {
  f_ = std::fopen(path.c_str(), append ? "ab" : "wb");
  if (!f_) throw std::runtime_error(path + ": cannot create LCM log: " + std::strerror(errno));
}

LcmLogWriter::~LcmLogWriter() {
  if (f_) std::fclose(f_);
}

bool LcmLogWriter::write(const char* channel, int64_t timestamp_us, const void* data, size_t size) {
  const size_t chan_len = std::strlen(channel);
  uint8_t h[kHeader];
  std::lock_guard<std::mutex> lock(mutex_);
  put32(h, kLcmLogSync);
  put64(h + 4, events_);
  put64(h + 12, static_cast<uint64_t>(timestamp_us));
  put32(h + 20, static_cast<uint32_t>(chan_len));
  put32(h + 24, static_cast<uint32_t>(size));
  const bool ok = std::fwrite(h, 1, kHeader, f_) == kHeader && std::fwrite(channel, 1, chan_len, f_) == chan_len &&
                  std::fwrite(data, 1, size, f_) == size;
  if (ok) {
    events_.fetch_add(1, std::memory_order_relaxed);
  } else {
    last_errno_.store(errno ? errno : EIO, std::memory_order_relaxed);
    errors_.fetch_add(1, std::memory_order_relaxed);
    std::clearerr(f_);  // the next event tries again (space may have been freed)
  }
  return ok;
}

std::string LcmLogWriter::last_error() const {
  const int e = last_errno_.load(std::memory_order_relaxed);
  return e ? std::strerror(e) : "";
}

void LcmLogWriter::flush() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::fflush(f_);
}

int64_t wall_clock_us() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}

bool looks_like_lcm_log(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  uint8_t b[4];
  const bool ok = std::fread(b, 1, 4, f) == 4 && be32(b) == kLcmLogSync;
  std::fclose(f);
  return ok;
}

}  // namespace rsd::formats
