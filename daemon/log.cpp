#include "daemon/log.hpp"

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/base_sink.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <mutex>

namespace rsd::daemon {

namespace {

// sd-daemon(3) priority prefixes: journald reads the level from them.
class PriorityFlag : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg& msg, const std::tm&, spdlog::memory_buf_t& dest) override {
    const char* p = "<6>";
    switch (msg.level) {
      case spdlog::level::trace:
      case spdlog::level::debug: p = "<7>"; break;
      case spdlog::level::info: p = "<6>"; break;
      case spdlog::level::warn: p = "<4>"; break;
      case spdlog::level::err: p = "<3>"; break;
      case spdlog::level::critical: p = "<2>"; break;
      default: break;
    }
    dest.append(p, p + 3);
  }
  std::unique_ptr<custom_flag_formatter> clone() const override { return std::make_unique<PriorityFlag>(); }
};

// stderr, shared with the status line under one mutex.
struct Stream {
  std::mutex mutex;
  bool status_open = false;  // a status line is on screen, not yet ended
  bool journal = false;
  bool colour = false;
};
Stream& stream() {
  static Stream s;
  return s;
}

class StderrSink : public spdlog::sinks::base_sink<std::mutex> {
 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    spdlog::memory_buf_t line;
    formatter_->format(msg, line);
    Stream& s = stream();
    std::lock_guard lock(s.mutex);
    if (s.status_open) std::fputc('\n', stderr), s.status_open = false;
    if (s.colour && msg.color_range_end > msg.color_range_start) {
      const char* colour = msg.level >= spdlog::level::err ? "\033[1;31m" : msg.level == spdlog::level::warn ? "\033[33m" : "\033[32m";
      std::fwrite(line.data(), 1, msg.color_range_start, stderr);
      std::fputs(colour, stderr);
      std::fwrite(line.data() + msg.color_range_start, 1, msg.color_range_end - msg.color_range_start, stderr);
      std::fputs("\033[0m", stderr);
      std::fwrite(line.data() + msg.color_range_end, 1, line.size() - msg.color_range_end, stderr);
    } else {
      std::fwrite(line.data(), 1, line.size(), stderr);
    }
    std::fflush(stderr);
  }
  void flush_() override { std::fflush(stderr); }
};

}  // namespace

std::optional<spdlog::level::level_enum> parse_log_level(std::string_view name) {
  if (name == "warning") return spdlog::level::warn;
  if (name == "err") return std::nullopt;  // spdlog's spelling; ours is "error"
  const spdlog::level::level_enum l = spdlog::level::from_str(std::string(name));
  if (l == spdlog::level::off && name != "off") return std::nullopt;  // from_str's "unknown"
  return l;
}

bool stderr_is_journal() {
  const char* js = std::getenv("JOURNAL_STREAM");
  if (!js) return false;
  unsigned long long dev = 0, ino = 0;
  if (std::sscanf(js, "%llu:%llu", &dev, &ino) != 2) return false;
  struct stat st;
  if (fstat(STDERR_FILENO, &st) != 0) return false;
  return static_cast<unsigned long long>(st.st_dev) == dev && static_cast<unsigned long long>(st.st_ino) == ino;
}

void init_log(spdlog::level::level_enum level) {
  Stream& s = stream();
  s.journal = stderr_is_journal();
  s.colour = !s.journal && isatty(STDERR_FILENO) && !std::getenv("NO_COLOR");
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  if (s.journal)
    formatter->add_flag<PriorityFlag>('*').set_pattern("%*%v");
  else
    formatter->set_pattern("[%H:%M:%S.%e] rsd: %^%l%$: %v");
  auto sink = std::make_shared<StderrSink>();
  sink->set_formatter(std::move(formatter));
  auto logger = std::make_shared<spdlog::logger>("rsd", std::move(sink));
  logger->set_level(level);
  logger->flush_on(spdlog::level::trace);
  spdlog::set_default_logger(std::move(logger));
}

void log_fatal(const std::string& message) {
  const auto logger = spdlog::default_logger();
  const auto level = logger->level();
  if (level > spdlog::level::err) logger->set_level(spdlog::level::err);
  logger->error("{}", message);
  logger->set_level(level);
}

void show_status_line(const std::string& text) {
  Stream& s = stream();
  if (s.journal) return;
  std::lock_guard lock(s.mutex);
  std::fprintf(stderr, "\rrsd: %s   ", text.c_str());
  std::fflush(stderr);
  s.status_open = true;
}

void end_status_line() {
  Stream& s = stream();
  std::lock_guard lock(s.mutex);
  if (s.status_open) std::fputc('\n', stderr), s.status_open = false;
}

void show_replay_progress(double progress, uint64_t frames, double seconds) {
  constexpr int kWidth = 30;
  char bar[kWidth + 1];
  for (int i = 0; i < kWidth; ++i) bar[i] = i < static_cast<int>(progress * kWidth + 0.5) ? '#' : '.';
  bar[kWidth] = '\0';
  char text[128];
  std::snprintf(text, sizeof text, "replay [%s] %3.0f%%  %llu frames  %.1f fps", bar, 100 * progress,
                static_cast<unsigned long long>(frames), seconds > 0 ? static_cast<double>(frames) / seconds : 0.0);
  show_status_line(text);
}

}  // namespace rsd::daemon
