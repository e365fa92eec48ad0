// Where a tool reads frames from: image files or directories of them, an LCM log of
// bot_core.image_t frames (rsd's own raw frames, a recording, lcm-logger output), or a live
// camera through rsd's drivers. One interface, so calibration and extraction work the same
// on all of them.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dsp/core/image.hpp"

namespace rsd::tools {

struct SourceFrame {
  dsp::Image image;
  std::string name;                   // for error messages: file, or log event
  std::optional<double> timestamp_s;  // first row's capture time, when the source knows it
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual std::optional<SourceFrame> next() = 0;  // nullopt at the end
  virtual std::string description() const = 0;
};

struct FrameSourceOptions {
  std::string channel = "RSD_RAW";  // LCM logs: the image channel
  int live_frames = 60;             // live cameras: how many frames to take
};

// INPUT forms: "live:aravis:ADDRESS", "live:v4l2:/dev/videoN", "live:libcamera[:ID]"; an LCM
// log (recognised by its sync word); image files and directories (natural name order).
// Throws UsageError for inputs that do not exist or hold nothing usable.
std::unique_ptr<FrameSource> open_frame_source(const std::vector<std::string>& inputs, const FrameSourceOptions& opt);

// "frame2" before "frame10": digit runs compare as numbers.
bool natural_less(const std::string& a, const std::string& b);
// Image files named by inputs: files as given, directories expanded (natural order).
std::vector<std::string> expand_inputs(const std::vector<std::string>& inputs);
// "first" or "first and N more", for messages.
std::string describe_inputs(const std::vector<std::string>& inputs);

}  // namespace rsd::tools
