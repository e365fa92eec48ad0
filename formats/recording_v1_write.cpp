// Writing rsd-recording/1 (docs/formats/recording-v1.md): the header, frames.csv, the motion and
// the observations, or an images recording's list of pictures; reading is recording_v1.cpp.
#include "formats/recording_v1.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>

#include "formats/number_text.hpp"

namespace rsd::formats {

namespace fs = std::filesystem;
using dsp::Recording;

namespace {

class CsvWriter {
 public:
  CsvWriter(const fs::path& path, const char* header) : path_(path), out_(path) {
    if (!out_) throw RecordingError(path.string() + ": cannot open for writing");
    out_ << header << '\n';
  }
  template <class... V>
  void row(const V&... v) {
    bool first = true;
    ((out_ << (first ? "" : ",") << field(v), first = false), ...);
    out_ << '\n';
  }
  ~CsvWriter() noexcept(false) {
    out_.flush();
    if (!out_) throw RecordingError(path_.string() + ": write failed (disk full?)");
  }

 private:
  static std::string field(double v) { return number_text(v); }
  static std::string field(int v) { return std::to_string(v); }
  static std::string field(const std::string& v) { return v; }
  fs::path path_;
  std::ofstream out_;
};

YAML::Node camera_node(const dsp::NominalModel& n) {
  YAML::Node c;
  c["width"] = n.cam.width;
  c["height"] = n.cam.height;
  c["fx"] = number_text(n.cam.fx);
  c["fy"] = number_text(n.cam.fy);
  c["cx"] = number_text(n.cam.cx);
  c["cy"] = number_text(n.cam.cy);
  // camera.model: pinhole-radtan's distortion is [k1, k2, p1, p2], pinhole-equi's [k1, k2, k3, k4].
  YAML::Node d;
  for (double v : dsp::file_terms(n.cam.dist)) d.push_back(number_text(v));
  d.SetStyle(YAML::EmitterStyle::Flow);
  c["distortion"] = d;
  if (n.cam.dist.model == dsp::LensModel::PinholeEqui) c["model"] = dsp::lens_model_name(n.cam.dist.model);
  return c;
}

YAML::Node flow_list(std::initializer_list<double> v) {
  YAML::Node n;
  for (double x : v) n.push_back(number_text(x));
  n.SetStyle(YAML::EmitterStyle::Flow);
  return n;
}

// The header; `observations` is the section as the recording's kind writes it.
void write_header(const fs::path& dir, const Recording& r, const YAML::Node& observations) {
  const auto& n = r.nominal;
  YAML::Node y;
  y["format"] = "rsd-recording/1";
  y["camera"] = camera_node(n);
  y["timing"]["frame_rate_hz"] = number_text(n.frame_rate_hz);
  y["timing"]["line_delay_s"] = number_text(n.time.line_delay_s);
  y["timing"]["readout"] = std::string(dsp::to_string(n.time.readout));
  y["timing"]["time_offset_s"] = number_text(n.time.time_offset_s);
  y["timing"]["drift_ppm"] = number_text(n.time.drift_ppm);
  const bool traj = r.motion == dsp::MotionKind::Trajectory;
  y["motion"]["kind"] = dsp::to_string(r.motion);
  y["motion"]["file"] = traj ? "trajectory.csv" : "gyro.csv";
  const auto& R = n.imu_to_camera;
  y["motion"]["imu_to_camera"] = flow_list({R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)});
  y["motion"]["lever_arm_m"] = flow_list({n.lever_arm.x(), n.lever_arm.y(), n.lever_arm.z()});
  y["observations"] = observations;
  y["frames"] = "frames.csv";
  if (r.noise_px) y["noise_px"] = number_text(*r.noise_px);
  std::ofstream out(dir / "recording.yaml");
  out << y << '\n';
  if (!out) throw RecordingError((dir / "recording.yaml").string() + ": write failed");
}

// The directory, the header, frames.csv and the motion: what every kind writes.
void write_common(const fs::path& dir, const Recording& r, const YAML::Node& observations) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw RecordingError(dir.string() + ": cannot create directory: " + ec.message());
  write_header(dir, r, observations);
  {
    CsvWriter w(dir / "frames.csv", "frame,t");
    for (const auto& f : r.frames) w.row(f.frame, f.t);
  }
  if (r.motion == dsp::MotionKind::Trajectory) {
    CsvWriter w(dir / "trajectory.csv", "t,x,y,z,qw,qx,qy,qz");
    for (const auto& p : r.trajectory) w.row(p.t, p.p.x(), p.p.y(), p.p.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z());
  } else {
    CsvWriter w(dir / "gyro.csv", "t,wx,wy,wz");
    for (const auto& g : r.gyro) w.row(g.t, g.w.x(), g.w.y(), g.w.z());
  }
}

void write_points(const fs::path& dir, const Recording& r) {
  CsvWriter p(dir / "points.csv", "id,x,y,z");
  for (const auto& L : r.points) p.row(L.id, L.X.x(), L.X.y(), L.X.z());
}

YAML::Node target_node(const dsp::TargetSpec& t) {
  YAML::Node n;
  const bool board = t.kind == dsp::TargetKind::Checkerboard;
  n["type"] = board ? "checkerboard" : "aprilgrid";
  n["cols"] = t.cols;
  n["rows"] = t.rows;
  n[board ? "square_m" : "tag_m"] = number_text(t.spacing_m);
  if (!board) n["spacing"] = number_text(t.tag_spacing);
  return n;
}

}  // namespace

void write_recording(const std::string& dir_name, const Recording& r) {
  const fs::path dir(dir_name);
  const bool lm = r.kind == dsp::ObservationKind::Landmarks;
  YAML::Node o;
  o["kind"] = dsp::to_string(r.kind);
  o["file"] = lm ? "observations.csv" : "matches.csv";
  if (lm) o["points"] = "points.csv";
  write_common(dir, r, o);
  if (lm) {
    write_points(dir, r);
    CsvWriter w(dir / "observations.csv", "frame,id,u,v");
    for (const auto& ob : r.observations) w.row(ob.frame, ob.id, ob.px.x(), ob.px.y());
  } else {
    CsvWriter m(dir / "matches.csv", "frame_a,ua,va,frame_b,ub,vb");
    for (const auto& mt : r.matches) m.row(mt.frame_a, mt.a.x(), mt.a.y(), mt.frame_b, mt.b.x(), mt.b.y());
  }
}

void write_images_recording(const std::string& dir_name, const ImagesRecording& r) {
  const fs::path dir(dir_name);
  const bool lm = r.rec.kind == dsp::ObservationKind::Landmarks;
  // Paths as the reader gives them (usable from here), written relative to the directory.
  auto relative = [&](const std::string& p) { return fs::absolute(p).lexically_relative(fs::absolute(dir)).string(); };
  YAML::Node o;
  o["kind"] = "images";
  if (!r.video.empty()) o["video"] = relative(r.video);
  else o["file"] = "images.csv";
  if (lm) o["points"] = "points.csv";
  if (lm && r.target) o["target"] = target_node(*r.target);
  write_common(dir, r.rec, o);
  if (lm) write_points(dir, r.rec);
  if (r.video.empty()) {
    CsvWriter w(dir / "images.csv", "frame,file");
    for (size_t i = 0; i < r.rec.frames.size() && i < r.files.size(); ++i) w.row(r.rec.frames[i].frame, relative(r.files[i]));
  }
}

}  // namespace rsd::formats
