// Where a tool reads frames from: image files or directories of them, an LCM log of
// bot_core.image_t frames (rsd's own raw frames, a recording, lcm-logger output), or a live
// camera. Every one is a drivers::CameraSource (images, replay, or a registered camera
// driver), read here frame by frame into images, so calibration and extraction work the same
// on all of them.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/camera_source.hpp"
#include "drivers/images_source.hpp"
#include "dsp/core/image.hpp"

namespace rsd::tools {

struct SourceFrame {
  dsp::Image image;
  std::string name;                   // for error messages: file, or frame of a log or camera
  std::optional<double> timestamp_s;  // first row's capture time, when the source knows it
};

struct FrameSourceOptions {
  std::string channel = "RSD_RAW";  // LCM logs: the image channel
  int live_frames = 60;             // live cameras: how many frames to take
};

// Pulls frames from a started camera source until it ends (or, live, `limit` frames).
class FrameSource {
 public:
  FrameSource(std::unique_ptr<drivers::CameraSource> cam, std::string description, bool stamped, int limit);
  ~FrameSource();
  std::optional<SourceFrame> next();  // nullopt at the end
  const std::string& description() const { return description_; }

 private:
  std::unique_ptr<drivers::CameraSource> cam_;
  const drivers::ImagesSource* images_ = nullptr;  // names frames by their files
  std::string description_;
  bool stamped_;
  int left_, taken_ = 0;
};

// INPUT forms: "live:DRIVER:ADDRESS" (a registered camera driver: live:aravis:ADDRESS,
// live:v4l2:/dev/videoN, live:libcamera[:ID]); an LCM log (recognised by its sync word);
// image files and directories (natural name order). Throws UsageError for inputs that do not
// exist or name no driver, std::runtime_error for sources that cannot be opened.
std::unique_ptr<FrameSource> open_frame_source(const std::vector<std::string>& inputs, const FrameSourceOptions& opt);

// "frame2" before "frame10": digit runs compare as numbers.
bool natural_less(const std::string& a, const std::string& b);
// Image files named by inputs: files as given, directories expanded (natural order).
std::vector<std::string> expand_inputs(const std::vector<std::string>& inputs);
// "first" or "first and N more", for messages.
std::string describe_inputs(const std::vector<std::string>& inputs);

}  // namespace rsd::tools
