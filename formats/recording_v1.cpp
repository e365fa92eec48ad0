// Reading rsd-recording/1 (docs/formats/recording-v1.md), every header, field and reference
// checked; writing is recording_v1_write.cpp.
#include "formats/recording_v1.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <string>
#include <vector>

#include "dsp/core/stamp.hpp"
#include "formats/intrinsics_file.hpp"
#include "formats/nominal_sections.hpp"
#include "formats/number_text.hpp"
#include "formats/target_spec.hpp"
#include "formats/yaml_map.hpp"

namespace rsd::formats {

namespace fs = std::filesystem;
using dsp::Recording;

namespace {

class CsvReader {
 public:
  CsvReader(const fs::path& path, const std::vector<std::string>& columns) : path_(path.string()), in_(path) {
    if (!in_) throw RecordingError(path_ + ": cannot open (the recording needs this file)");
    std::string header;
    std::getline(in_, header);
    strip_cr(header);
    std::string expected;
    for (size_t i = 0; i < columns.size(); ++i) expected += (i ? "," : "") + columns[i];
    if (header != expected)
      throw RecordingError(path_ + ":1:1: header is '" + header + "', the spec requires '" + expected + "'");
    columns_ = columns;
  }
  // Next data row, split into fields with their 1-based columns; false at end of file.
  bool next() {
    std::string line;
    while (std::getline(in_, line)) {
      ++line_no_;
      strip_cr(line);
      if (line.empty()) continue;  // tolerate blank lines (e.g. a trailing newline)
      split(line);
      return true;
    }
    return false;
  }
  double number(size_t i) const {
    double v;
    const std::string& s = fields_[i];
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    if (r.ec != std::errc() || r.ptr != s.data() + s.size() || !std::isfinite(v)) fail(i, "'" + s + "' is not a finite number");
    return v;
  }
  // A time in seconds: finite and within rsd's window for times from outside (dsp::Stamp).
  double time(size_t i) const {
    const double t = number(i);
    if (!dsp::Stamp::from_s(t)) fail(i, "time " + fields_[i] + " s is beyond +-" + number_text(dsp::Stamp::kLimitS) + " s");
    return t;
  }
  const std::string& text(size_t i) const { return fields_[i]; }
  int integer(size_t i) const {
    int v;
    const std::string& s = fields_[i];
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    if (r.ec != std::errc() || r.ptr != s.data() + s.size()) fail(i, "'" + s + "' is not an integer");
    return v;
  }
  [[noreturn]] void fail(size_t i, const std::string& why) const {
    throw RecordingError(path_ + ":" + std::to_string(line_no_) + ":" + std::to_string(starts_[i]) + ": field '" +
                         columns_[i] + "': " + why);
  }
  [[noreturn]] void fail_line(const std::string& why) const {
    throw RecordingError(path_ + ":" + std::to_string(line_no_) + ":1: " + why);
  }

 private:
  static void strip_cr(std::string& s) {
    if (!s.empty() && s.back() == '\r') s.pop_back();
  }
  void split(const std::string& line) {
    fields_.clear();
    starts_.clear();
    size_t start = 0;
    for (;;) {
      const size_t comma = line.find(',', start);
      fields_.push_back(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
      starts_.push_back(start + 1);
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    if (fields_.size() != columns_.size())
      fail_line("expected " + std::to_string(columns_.size()) + " fields, found " + std::to_string(fields_.size()));
  }
  std::string path_;
  std::ifstream in_;
  std::vector<std::string> columns_, fields_;
  std::vector<size_t> starts_;
  int line_no_ = 1;
};

// Sections are read with the strict YAML reader every rsd file uses (formats/yaml_map.hpp):
// camera: and timing: by their one reader each, the rest here. Keys the format requires are
// required; errors name file, line, column and the key's path.
void require(const YamlMap& m, std::initializer_list<const char*> keys) {
  for (const char* k : keys)
    if (!m.has(k)) m.fail(k, "is missing");
}

std::string one_of(YamlMap& m, const char* key, std::initializer_list<const char*> allowed) {
  require(m, {key});
  const std::string v = m.text(key, "");
  std::string list;
  for (const char* a : allowed) {
    if (v == a) return v;
    list += std::string(list.empty() ? "" : " or ") + a;
  }
  m.fail(key, "is '" + v + "', expected " + list);
}

void read_motion(YamlMap m, Recording& r, std::string& file) {
  r.motion = one_of(m, "kind", {"trajectory", "gyro"}) == "trajectory" ? dsp::MotionKind::Trajectory : dsp::MotionKind::Gyro;
  require(m, {"file"});
  file = m.text("file", "");
  read_motion_extrinsics(m, r.nominal);
}

struct Files {
  std::string motion, observations, points, frames;
  bool images = false;
  std::string video;
  std::optional<dsp::TargetSpec> target;
};

// observations.target of an images recording: {type: checkerboard, cols, rows, square_m} or
// {type: aprilgrid, cols, rows, tag_m, spacing}, checked as the command line's --target is.
dsp::TargetSpec read_target(YamlMap t) {
  const std::string type = one_of(t, "type", {"checkerboard", "aprilgrid"});
  require(t, {"cols", "rows", type == "checkerboard" ? "square_m" : "tag_m"});
  const int cols = t.integer("cols", 0), rows = t.integer("rows", 0);
  std::string text = type + ":" + std::to_string(cols) + "x" + std::to_string(rows) + ":";
  if (type == "checkerboard") text += number_text(t.number("square_m"));
  else text += number_text(t.number("tag_m")) + ":" + number_text(t.number("spacing", 0.3));
  t.finish();
  try {
    return parse_target(text);
  } catch (const std::invalid_argument& e) {
    t.fail("type", e.what());
  }
}

void read_observations_header(YamlMap o, Recording& r, Files& files) {
  const std::string kind = one_of(o, "kind", {"landmarks", "matches", "images"});
  files.images = kind == "images";
  if (files.images) {
    // What the pictures make: matches with a gyro, landmarks of a known target with a trajectory.
    r.kind = r.motion == dsp::MotionKind::Gyro ? dsp::ObservationKind::Matches : dsp::ObservationKind::Landmarks;
    if (o.has("video") == o.has("file")) o.fail("file", "an images recording gives either file (images.csv) or video, not both or neither");
    if (o.has("video")) files.video = o.text("video", "");
    if (r.kind == dsp::ObservationKind::Landmarks) {
      if (!o.has("target") || !o.has("points"))
        o.fail(o.has("points") ? "target" : "points", "is missing: an images recording with trajectory motion needs the target "
                                                     "to detect (target:) and its corners' coordinates (points:)");
      files.target = read_target(o.map("target"));
    }
  } else {
    r.kind = kind == "landmarks" ? dsp::ObservationKind::Landmarks : dsp::ObservationKind::Matches;
    require(o, {"file"});
  }
  if (o.has("video") && !files.images) o.fail("video", "applies to images recordings only (kind: images)");
  if (o.has("target") && !files.target) o.fail("target", "applies to images recordings with trajectory motion only");
  if (o.has("file")) files.observations = o.text("file", "");
  if (r.kind == dsp::ObservationKind::Landmarks) {
    require(o, {"points"});
    files.points = o.text("points", "");
  }
}

Files read_header(const fs::path& dir, Recording& r) {
  const std::string f = (dir / "recording.yaml").string();
  if (!fs::exists(f)) throw RecordingError(f + ": cannot open (is " + dir.string() + " an rsd-recording/1 directory?)");
  Files files;
  try {
    YamlMap y = YamlMap::load(f);
    one_of(y, "format", {"rsd-recording/1"});
    // Values first (a bad one is named where it is), then what the format requires.
    const YamlMap cam = y.map("camera");
    r.nominal.cam = read_camera_section(cam, r.nominal.cam);
    require(cam, {"width", "height", "fx", "fy", "cx", "cy"});
    const YamlMap timing = y.map("timing");
    read_timing_section(timing, r.nominal);
    require(timing, {"frame_rate_hz"});
    read_motion(y.map("motion"), r, files.motion);
    read_observations_header(y.map("observations"), r, files);
    require(y, {"frames"});
    files.frames = y.text("frames", "");
    if (y.has("noise_px")) r.noise_px = y.number("noise_px");
  } catch (const ConfigError& e) {
    throw RecordingError(e.what());
  }
  return files;
}

void read_frames(const fs::path& path, Recording& r, std::map<int, double>& by_id) {
  CsvReader csv(path, {"frame", "t"});
  while (csv.next()) {
    const int id = csv.integer(0);
    const double t = csv.time(1);
    if (!by_id.emplace(id, t).second) csv.fail(0, "frame " + std::to_string(id) + " appears twice");
    r.frames.push_back({id, t});
  }
  if (r.frames.empty()) throw RecordingError(path.string() + ": no frames");
  std::sort(r.frames.begin(), r.frames.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  r.nominal.time.t0 = r.frames.front().t;
}

std::vector<dsp::PoseSample> read_poses(const fs::path& path) {
  std::vector<dsp::PoseSample> out;
  CsvReader csv(path, {"t", "x", "y", "z", "qw", "qx", "qy", "qz"});
  while (csv.next()) {
    Eigen::Quaterniond q(csv.number(4), csv.number(5), csv.number(6), csv.number(7));
    if (std::abs(q.norm() - 1) > 1e-3) csv.fail(4, "quaternion is not unit length (norm " + number_text(q.norm()) + ")");
    const double t = csv.time(0);
    if (!out.empty() && t < out.back().t) csv.fail(0, "time goes backwards");
    out.push_back({t, {csv.number(1), csv.number(2), csv.number(3)}, q.normalized()});
  }
  if (out.size() < 2) throw RecordingError(path.string() + ": needs at least two poses");
  return out;
}

void read_motion(const fs::path& path, Recording& r) {
  if (r.motion == dsp::MotionKind::Trajectory) {
    r.trajectory = read_poses(path);
  } else {
    CsvReader csv(path, {"t", "wx", "wy", "wz"});
    while (csv.next()) r.gyro.push_back({csv.time(0), {csv.number(1), csv.number(2), csv.number(3)}});
    if (r.gyro.size() < 2) throw RecordingError(path.string() + ": needs at least two gyro samples");
    // The spec allows irregular, repeated samples: order them, keep repeats.
    std::stable_sort(r.gyro.begin(), r.gyro.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  }
}

std::map<int, size_t> read_points(const fs::path& points, Recording& r) {
  std::map<int, size_t> ids;
  CsvReader p(points, {"id", "x", "y", "z"});
  while (p.next()) {
    const int id = p.integer(0);
    if (!ids.emplace(id, r.points.size()).second) p.fail(0, "point " + std::to_string(id) + " appears twice");
    r.points.push_back({id, {p.number(1), p.number(2), p.number(3)}});
  }
  return ids;
}

void read_landmarks(const fs::path& points, const fs::path& obs, Recording& r, const std::map<int, double>& frames) {
  const std::map<int, size_t> ids = read_points(points, r);
  CsvReader o(obs, {"frame", "id", "u", "v"});
  while (o.next()) {
    const int f = o.integer(0), id = o.integer(1);
    if (!frames.count(f)) o.fail(0, "frame " + std::to_string(f) + " is not in frames.csv");
    if (!ids.count(id)) o.fail(1, "point " + std::to_string(id) + " is not in points.csv");
    r.observations.push_back({f, id, {o.number(2), o.number(3)}});
  }
}

void read_matches(const fs::path& path, Recording& r, const std::map<int, double>& frames) {
  CsvReader m(path, {"frame_a", "ua", "va", "frame_b", "ub", "vb"});
  while (m.next()) {
    const int a = m.integer(0), b = m.integer(3);
    if (!frames.count(a)) m.fail(0, "frame " + std::to_string(a) + " is not in frames.csv");
    if (!frames.count(b)) m.fail(3, "frame " + std::to_string(b) + " is not in frames.csv");
    r.matches.push_back({a, {m.number(1), m.number(2)}, b, {m.number(4), m.number(5)}});
  }
}

// images.csv: one picture per frame of frames.csv, in the frames' order.
std::vector<std::string> read_image_list(const fs::path& dir, const fs::path& path, const Recording& r) {
  std::map<int, std::string> by_frame;
  CsvReader c(path, {"frame", "file"});
  std::map<int, double> frames;
  for (const dsp::FrameStamp& f : r.frames) frames.emplace(f.frame, f.t);
  while (c.next()) {
    const int f = c.integer(0);
    if (!frames.count(f)) c.fail(0, "frame " + std::to_string(f) + " is not in frames.csv");
    // The file's own field, as written (no quoting in the format: a comma cannot occur).
    const std::string file = c.text(1);
    if (file.empty()) c.fail(1, "is empty");
    if (!by_frame.emplace(f, (dir / file).string()).second) c.fail(0, "frame " + std::to_string(f) + " appears twice");
  }
  std::vector<std::string> files;
  for (const dsp::FrameStamp& f : r.frames) {
    const auto it = by_frame.find(f.frame);
    if (it == by_frame.end())
      throw RecordingError(path.string() + ": frame " + std::to_string(f.frame) + " of frames.csv has no picture");
    files.push_back(it->second);
  }
  return files;
}

Recording read_common(const fs::path& dir, Files& files) {
  if (!fs::is_directory(dir)) throw RecordingError(dir.string() + ": not a directory");
  Recording r;
  files = read_header(dir, r);
  std::map<int, double> frames;
  read_frames(dir / files.frames, r, frames);
  read_motion(dir / files.motion, r);
  return r;
}

}  // namespace

std::vector<dsp::PoseSample> read_trajectory_csv(const std::string& path) { return read_poses(path); }

Recording read_recording(const std::string& dir_name) {
  const fs::path dir(dir_name);
  Files files;
  Recording r = read_common(dir, files);
  if (files.images)
    throw RecordingError((dir / "recording.yaml").string() + ": observations.kind is images: the observations are still to be "
                         "made from the pictures (rsd-extract " + dir_name + " OUT, or a tool that reads images recordings)");
  std::map<int, double> frames;
  for (const dsp::FrameStamp& f : r.frames) frames.emplace(f.frame, f.t);
  if (r.kind == dsp::ObservationKind::Landmarks)
    read_landmarks(dir / files.points, dir / files.observations, r, frames);
  else
    read_matches(dir / files.observations, r, frames);
  return r;
}

bool is_images_recording(const std::string& dir) {
  try {
    YamlMap y = YamlMap::load((fs::path(dir) / "recording.yaml").string());
    return y.has("observations") && y.map("observations").text("kind", "") == "images";
  } catch (const std::exception&) {
    return false;
  }
}

ImagesRecording read_images_recording(const std::string& dir_name) {
  const fs::path dir(dir_name);
  Files files;
  ImagesRecording out;
  out.rec = read_common(dir, files);
  if (!files.images)
    throw RecordingError((dir / "recording.yaml").string() + ": observations.kind is " + dsp::to_string(out.rec.kind) +
                         ", not images: this recording holds observations, not pictures");
  if (files.video.empty()) out.files = read_image_list(dir, dir / files.observations, out.rec);
  else {
    out.video = (dir / files.video).string();
    if (!fs::exists(out.video)) throw RecordingError((dir / "recording.yaml").string() + ": observations.video: " + out.video + " does not exist");
    for (const dsp::FrameStamp& f : out.rec.frames) {
      if (f.frame < 0) throw RecordingError((dir / files.frames).string() + ": frame " + std::to_string(f.frame) + ": a video's frames are numbered from 0");
      out.files.push_back(std::to_string(f.frame));
    }
  }
  if (out.rec.kind == dsp::ObservationKind::Landmarks) {
    read_points(dir / files.points, out.rec);
    out.target = files.target;
  }
  return out;
}

}  // namespace rsd::formats
