// Progress of the tools' long stages on stderr: one line rewritten as a stage moves on, with a
// bar of the steps done and the time left at the stage's own pace so far, and the stage's other
// messages as lines of their own. Used on the caller's thread only (not thread-safe).
#pragma once

#include <chrono>
#include <string>

namespace rsd::tools {

class ProgressLine {
 public:
  explicit ProgressLine(std::string prefix) : prefix_(std::move(prefix)) {}
  ~ProgressLine() { finish(); }
  // `done` of `total` steps of `stage` (a new stage text starts its own clock); `detail` follows
  // the count ("1234 matches"). The line ends when done reaches total.
  void step(const std::string& stage, long done, long total, const std::string& detail = "");
  // A line of its own (ending a rewritten line first).
  void message(const std::string& text);
  void finish();

 private:
  std::string prefix_, stage_;
  std::chrono::steady_clock::time_point start_{};
  bool open_ = false;
};

// "[#####-----]" for `done` of `total` in `width` characters.
std::string progress_bar(long done, long total, int width = 20);

}  // namespace rsd::tools
