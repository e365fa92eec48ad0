#include "tools/common/progress_line.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rsd::tools {

std::string progress_bar(long done, long total, int width) {
  const long filled = total > 0 ? std::clamp(done * width / total, 0L, static_cast<long>(width)) : 0;
  std::string bar(static_cast<size_t>(width) + 2, '-');
  bar.front() = '[', bar.back() = ']';
  std::fill_n(bar.begin() + 1, filled, '#');
  return bar;
}

void ProgressLine::step(const std::string& stage, long done, long total, const std::string& detail) {
  const auto now = std::chrono::steady_clock::now();
  if (stage != stage_ || !open_) stage_ = stage, start_ = now;
  const double spent = std::chrono::duration<double>(now - start_).count();
  std::string line = "\r" + prefix_ + stage + " " + progress_bar(done, total) + " " + std::to_string(done) + "/" +
                     std::to_string(total);
  if (!detail.empty()) line += ", " + detail;
  // The pace is known once two steps are done: the first may carry the stage's setting up.
  if (done >= 2 && done < total) {
    const double left = spent / done * (total - done);
    char text[48];
    std::snprintf(text, sizeof text, left < 10 ? ", about %.1f s left" : ", about %.0f s left", left);
    line += text;
  }
  std::fprintf(stderr, "%s      ", line.c_str());
  open_ = done < total;
  if (!open_) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

void ProgressLine::message(const std::string& text) {
  finish();
  std::fprintf(stderr, "%s%s\n", prefix_.c_str(), text.c_str());
}

void ProgressLine::finish() {
  if (open_) std::fprintf(stderr, "\n");
  open_ = false;
}

}  // namespace rsd::tools
