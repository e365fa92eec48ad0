#include "tools/common/frame_sources.hpp"

#include <bot_core/image_t.hpp>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "tools/common/cli_util.hpp"
#include "drivers/aravis_source.hpp"
#include "formats/image_t_codec.hpp"
#include "drivers/libcamera_source.hpp"
#include "drivers/v4l2_source.hpp"
#include "formats/image_file.hpp"
#include "formats/lcm_log.hpp"

namespace rsd::tools {

namespace fs = std::filesystem;
using dsp::Image;

namespace {

class ImageFileSource final : public FrameSource {
 public:
  ImageFileSource(std::vector<std::string> files, std::string description)
      : files_(std::move(files)), description_(std::move(description)) {}
  std::optional<SourceFrame> next() override {
    if (index_ >= files_.size()) return std::nullopt;
    const std::string& f = files_[index_++];
    return SourceFrame{formats::read_image(f), f, std::nullopt};  // formats::read_image names the file on error
  }
  std::string description() const override { return description_; }

 private:
  std::vector<std::string> files_;
  std::string description_;
  size_t index_ = 0;
};

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool is_image_name(const fs::path& p) {
  const std::string ext = lower(p.extension().string());
  return ext == ".png" || ext == ".pgm";
}

}  // namespace

bool natural_less(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
      size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      const std::string na = a.substr(i, ie - i), nb = b.substr(j, je - j);
      const std::string ta = na.substr(std::min(na.find_first_not_of('0'), na.size()));
      const std::string tb = nb.substr(std::min(nb.find_first_not_of('0'), nb.size()));
      if (ta.size() != tb.size()) return ta.size() < tb.size();
      if (ta != tb) return ta < tb;
      i = ie, j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i, ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

namespace {
std::vector<std::string> images_in(const std::string& dir) {
  std::vector<std::string> files;
  for (const fs::directory_entry& e : fs::directory_iterator(dir))
    if (e.is_regular_file() && is_image_name(e.path())) files.push_back(e.path().string());
  std::sort(files.begin(), files.end(), natural_less);
  if (files.empty()) throw UsageError("INPUT: directory '" + dir + "' holds no .png or .pgm images");
  return files;
}

}  // namespace

std::vector<std::string> expand_inputs(const std::vector<std::string>& inputs) {
  std::vector<std::string> files;
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (fs::is_directory(in, ec)) {
      const std::vector<std::string> d = images_in(in);
      files.insert(files.end(), d.begin(), d.end());
    } else if (fs::exists(in, ec)) {
      files.push_back(in);
    } else {
      throw UsageError("INPUT: '" + in + "' does not exist");
    }
  }
  return files;
}

std::string describe_inputs(const std::vector<std::string>& inputs) {
  if (inputs.size() == 1) return inputs.front();
  return inputs.front() + " and " + std::to_string(inputs.size() - 1) + " more";
}

namespace {

// ---------------------------------------------------------------- LCM logs

// Frames on one channel of an LCM log, read as rsd reads every raw frame (formats/): the
// robust log reader, and the bot_core.image_t codec with its fingerprint check and timestamp
// rule. A damaged event is an error naming it: calibration must not quietly lose frames.
class LcmLogSource final : public FrameSource {
 public:
  LcmLogSource(const std::string& path, std::string channel) : path_(path), channel_(std::move(channel)), log_(path) {}
  std::optional<SourceFrame> next() override {
    while (log_.next(ev_)) {
      ++event_;
      if (ev_.channel != channel_) continue;
      const std::string where = path_ + ": event " + std::to_string(event_) + " on " + channel_;
      std::string why;
      if (formats::decode_frame(ev_.data.data(), ev_.data.size(), img_, frame_, why) != formats::DecodeStatus::Ok)
        throw std::runtime_error(where + ": " + why);
      const formats::FrameFormat& f = frame_.format;
      Image img(f.width, f.height, f.format);
      formats::copy_pixels(img_, img.view());
      seen_any_ = true;
      return SourceFrame{std::move(img), where, frame_.meta.first_row_ns * 1e-9};
    }
    if (!seen_any_) throw UsageError("INPUT: '" + path_ + "' has no frames on channel " + channel_ + " (see --channel)");
    return std::nullopt;
  }
  std::string description() const override { return path_ + " (" + channel_ + ")"; }

 private:
  std::string path_, channel_;
  formats::LcmLogReader log_;
  formats::LogEvent ev_;
  bot_core::image_t img_;
  formats::RecordedFrame frame_;
  int event_ = 0;
  bool seen_any_ = false;
};

// ---------------------------------------------------------------- live cameras

std::unique_ptr<drivers::CameraSource> make_camera(const std::string& spec) {
  const std::string rest = spec.substr(5);  // after "live:"
  if (rest.rfind("aravis:", 0) == 0) {
    drivers::AravisConfig c;
    c.camera = rest.substr(7);
    return std::make_unique<drivers::AravisSource>(c);
  }
  if (rest.rfind("v4l2:", 0) == 0) {
    drivers::V4l2Config c;
    c.device = rest.substr(5);
    return std::make_unique<drivers::V4l2Source>(c);
  }
  if (rest.rfind("libcamera", 0) == 0) {
    drivers::LibcameraConfig c;
    if (rest.size() > 10) c.camera_id = rest.substr(10);
    return std::make_unique<drivers::LibcameraSource>(c);
  }
  throw UsageError("INPUT: '" + spec + "': live sources are live:aravis:ADDRESS, live:v4l2:DEVICE or live:libcamera[:ID]");
}

class LiveSource final : public FrameSource {
 public:
  LiveSource(const std::string& spec, int frames) : spec_(spec), left_(frames), cam_(make_camera(spec)) {
    try {
      cam_->open();
    } catch (const drivers::CameraError& e) {
      throw std::runtime_error(spec + ": " + e.what());
    }
    cam_->start();
  }
  ~LiveSource() override { cam_->stop(); }
  std::optional<SourceFrame> next() override {
    if (left_-- <= 0) return std::nullopt;
    const drivers::FrameFormat f = cam_->format();
    SourceFrame out{Image(f.width, f.height, f.format), spec_ + ": frame " + std::to_string(taken_++), std::nullopt};
    drivers::FrameMeta meta;
    for (int tries = 0; tries < 20; ++tries)
      if (cam_->capture(out.image.view(), meta, std::chrono::milliseconds(500)) == drivers::CaptureStatus::Frame) {
        out.timestamp_s = meta.first_row_ns * 1e-9;
        return out;
      }
    throw std::runtime_error(spec_ + ": no frame within 10 s");
  }
  std::string description() const override { return spec_; }

 private:
  std::string spec_;
  int left_, taken_ = 0;
  std::unique_ptr<drivers::CameraSource> cam_;
};

}  // namespace

std::unique_ptr<FrameSource> open_frame_source(const std::vector<std::string>& inputs, const FrameSourceOptions& opt) {
  if (inputs.size() == 1 && inputs.front().rfind("live:", 0) == 0)
    return std::make_unique<LiveSource>(inputs.front(), opt.live_frames);
  if (inputs.size() == 1 && fs::is_regular_file(inputs.front()) && formats::looks_like_lcm_log(inputs.front()))
    return std::make_unique<LcmLogSource>(inputs.front(), opt.channel);
  return std::make_unique<ImageFileSource>(expand_inputs(inputs), describe_inputs(inputs));
}


}  // namespace rsd::tools
