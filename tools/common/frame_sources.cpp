#include "tools/common/frame_sources.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "tools/common/cli_util.hpp"
#include "drivers/driver_registry.hpp"
#include "drivers/replay_source.hpp"
#include "formats/config_section.hpp"
#include "formats/image_file.hpp"
#include "formats/lcm_log.hpp"

namespace rsd::tools {

namespace fs = std::filesystem;
using dsp::Image;

namespace {

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

// A registered camera driver, configured through its own section reader with the address
// the spec gives ("live:aravis:192.168.1.20": aravis.camera = 192.168.1.20).
std::unique_ptr<drivers::CameraSource> make_live(const std::string& spec) {
  const std::string rest = spec.substr(5);  // after "live:"
  const size_t colon = rest.find(':');
  const std::string name = rest.substr(0, colon);
  const drivers::Driver* d = drivers::find_driver(name);
  if (!d || !d->real_camera || d->address_key.empty())
    throw UsageError("INPUT: '" + spec + "': live sources are live:aravis:ADDRESS, live:v4l2:DEVICE or live:libcamera[:ID]");
  std::any cfg = d->defaults();
  if (colon != std::string::npos) {
    YAML::Node node;
    node[d->address_key] = rest.substr(colon + 1);
    formats::ConfigReader reader(formats::YamlMap(spec, node, ""));
    d->visit(reader, cfg);
  }
  return d->make(cfg);
}

}  // namespace

FrameSource::FrameSource(std::unique_ptr<drivers::CameraSource> cam, std::string description, bool stamped, int limit)
    : cam_(std::move(cam)), images_(dynamic_cast<const drivers::ImagesSource*>(cam_.get())),
      description_(std::move(description)), stamped_(stamped), left_(limit) {
  try {
    cam_->open();
  } catch (const drivers::CameraError& e) {
    throw std::runtime_error(description_ + ": " + e.what());
  }
  cam_->start();
}

FrameSource::~FrameSource() { cam_->stop(); }

std::optional<SourceFrame> FrameSource::next() {
  if (left_ == 0) return std::nullopt;
  const drivers::FrameFormat f = cam_->format();
  SourceFrame out{dsp::Image(f.width, f.height, f.format), "", std::nullopt};
  drivers::FrameMeta meta;
  for (int tries = 0; tries < 20; ++tries) {  // a live camera: 10 s for a frame
    const drivers::CaptureStatus st = cam_->capture(out.image.view(), meta, std::chrono::milliseconds(500));
    if (st == drivers::CaptureStatus::EndOfStream) return std::nullopt;
    if (st != drivers::CaptureStatus::Frame) continue;
    out.name = images_ ? images_->current_file() : description_ + ": frame " + std::to_string(taken_);
    if (stamped_) out.timestamp_s = static_cast<double>(meta.first_row_ns) * 1e-9;
    ++taken_;
    if (left_ > 0) --left_;
    return out;
  }
  throw std::runtime_error(description_ + ": no frame within 10 s");
}

std::unique_ptr<FrameSource> open_frame_source(const std::vector<std::string>& inputs, const FrameSourceOptions& opt) {
  if (inputs.size() == 1 && inputs.front().rfind("live:", 0) == 0)
    return std::make_unique<FrameSource>(make_live(inputs.front()), inputs.front(), true, opt.live_frames);
  if (inputs.size() == 1 && fs::is_regular_file(inputs.front()) && formats::looks_like_lcm_log(inputs.front())) {
    drivers::ReplayConfig c;
    c.file = inputs.front();
    c.speed = 0;  // as fast as it reads, nothing dropped
    c.channel = opt.channel;
    return std::make_unique<FrameSource>(std::make_unique<drivers::ReplaySource>(c), inputs.front() + " (" + opt.channel + ")",
                                         true, -1);
  }
  drivers::ImagesConfig c;
  c.files = expand_inputs(inputs);
  return std::make_unique<FrameSource>(std::make_unique<drivers::ImagesSource>(c), describe_inputs(inputs), false, -1);
}

}  // namespace rsd::tools
