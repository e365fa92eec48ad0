#include "tools/extract/video_inputs.hpp"

#include <rsd/velocity_t.hpp>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "formats/gcsv.hpp"
#include "formats/gopro_axes.hpp"
#include "formats/gpmf_mp4.hpp"
#include "formats/recording_v1.hpp"
#include "formats/sensor_csv.hpp"
#include "formats/video_file.hpp"
#include "formats/video_frame_times.hpp"
#include "tools/common/cli_util.hpp"
#include "tools/extract/nominal_model.hpp"

namespace rsd::tools::extract {

using formats::MotionLog;

bool looks_like_mp4(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[8] = {};
  return in.read(head, 8) && std::memcmp(head + 4, "ftyp", 4) == 0;
}

namespace {

// A GoPro clip's frames and GPMF gyro as the motion log the rest of rsd-extract reads.
MotionLog motion_of(const formats::GpmfVideo& v, const std::string& clip) {
  MotionLog s;
  for (double t : v.frame_t_s) s.frames.push_back({t, std::nullopt, std::nullopt, v.width, v.height});
  for (size_t i = 0; i < v.gyro_t_s.size(); ++i) s.gyro.push_back({v.gyro_t_s[i], v.gyro_rad_s[i]});
  s.gyro_frame = static_cast<int>(rsd::velocity_t::FRAME_IMU);  // a value: the constant has no definition to bind to
  s.channels = {{clip + " video", static_cast<int>(v.frame_t_s.size())}, {clip + " GPMF", v.payloads}};
  s.events = static_cast<int>(v.frame_t_s.size()) + v.payloads;
  return s;
}

// A video's frames and a gyro in IMU axes (s) as an images recording whose pictures stay in the
// video (observations.video), for rsd-diagnose OUT and rsd --replay OUT. The gyro's axes in the
// camera are what --imu-to-camera (or --nominal's motion.imu_to_camera) says, else what the
// clip itself says (`clip_axes`: a GoPro's), else the identity: rsd-diagnose --imu-axes search
// asks the pictures.
int write_video_recording(const Options& o, const MotionLog& s, const std::optional<formats::GoProAxes>& clip_axes = std::nullopt) {
  Nominal n = nominal_model(o, s);
  if (n.imu_to_camera) n.model.imu_to_camera = *n.imu_to_camera;
  else if (clip_axes) {
    n.model.imu_to_camera = clip_axes->imu_to_camera;
    n.notes.push_back("the gyro's axes in the camera: " + clip_axes->letters + " from " + clip_axes->source + ", imu_to_camera " +
                      matrix_text(clip_axes->imu_to_camera) + " (--imu-to-camera states others; rsd-diagnose --imu-axes check says "
                      "when the pictures clearly follow others)");
  } else
    n.notes.push_back("the gyro's axes in the camera: not given, taken as the identity (rsd-diagnose --imu-axes search "
                      "finds them from the pictures; --imu-to-camera states them)");
  dsp::Recording rec;
  rec.kind = dsp::ObservationKind::Matches;
  rec.motion = dsp::MotionKind::Gyro;
  rec.gyro = s.gyro;
  rec.noise_px = o.noise_px;
  rec.nominal = n.model;
  for (const std::string& note : n.notes) std::fprintf(stderr, "rsd-extract: %s\n", note.c_str());
  const std::vector<bool> ok = covered(s, n, true);
  rec.frames = covered_frames(s, ok, o.log);
  formats::ImagesRecording out;
  out.rec = rec;
  out.video = o.log;
  std::filesystem::create_directories(o.out);
  formats::write_images_recording(o.out, out);
  std::printf("rsd-extract: wrote an images recording (%zu of %zu frames, the pictures in %s; %zu gyro samples) to %s\n",
              rec.frames.size(), s.frames.size(), o.log.c_str(), rec.gyro.size(), o.out.c_str());
  return 0;
}

}  // namespace

int run_on_gopro_clip(const Options& o) {
  if (!o.target.empty()) throw UsageError(o.log + " is a GoPro clip: its motion is its gyro; --target needs a trajectory");
  std::fprintf(stderr, "rsd-extract: reading the GoPro clip %s\n", o.log.c_str());
  const formats::GpmfVideo v = formats::read_gpmf_video(o.log);
  std::fprintf(stderr, "rsd-extract: %zu frames at %dx%d, %zu gyro samples in %d GPMF payloads (%s, ORIN '%s', firmware '%s')\n",
               v.frame_t_s.size(), v.width, v.height, v.gyro_t_s.size(), v.payloads, v.device.c_str(), v.orin.c_str(),
               v.firmware.c_str());
  std::optional<formats::GoProAxes> axes;
  try {
    axes = formats::gopro_axes(v.orin, v.firmware);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(o.log + ": " + e.what());
  }
  return write_video_recording(o, motion_of(v, o.log), axes);
}

int run_on_video_with_csv(const Options& o) {
  if (!o.target.empty()) throw UsageError("--gyro-csv: the motion is a gyro; --target needs a trajectory");
  if (o.frame_times.empty()) throw UsageError("--gyro-csv needs --frame-times (the video's frames' times)");
  formats::GyroColumns columns;
  try {
    columns = formats::parse_gyro_columns(o.gyro_columns);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--gyro-columns: ") + e.what());
  }
  const double unit_s = formats::time_unit_seconds(o.time_unit);  // the option's check allows only known units
  const std::vector<double> times = formats::read_frame_times(o.frame_times, unit_s);
  MotionLog s;
  s.gyro = formats::read_gyro_csv(o.gyro_csv, columns, unit_s);
  s.gyro_frame = static_cast<int>(rsd::velocity_t::FRAME_IMU);
  std::fprintf(stderr, "rsd-extract: counting the frames of %s\n", o.log.c_str());
  formats::VideoReader video(o.log);
  dsp::Image frame;
  long n = 0;
  while (video.next(frame)) ++n;
  if (o.first_frame_index + n > static_cast<long>(times.size()))
    throw std::runtime_error(o.log + ": " + std::to_string(n) + " frames, but " + o.frame_times + " lists " + std::to_string(times.size()) +
                             " times, " + std::to_string(o.first_frame_index) + " of them before the video's first frame (--first-frame-index)");
  for (long k = 0; k < n; ++k) s.frames.push_back({times[o.first_frame_index + k], std::nullopt, std::nullopt, video.width(), video.height()});
  s.channels = {{o.log + " video", static_cast<int>(n)}, {o.gyro_csv, static_cast<int>(s.gyro.size())}};
  s.events = static_cast<int>(n + s.gyro.size());
  std::fprintf(stderr, "rsd-extract: %ld frames at %dx%d (times from line %ld of %s on), %zu gyro samples from %s\n", n, video.width(),
               video.height(), o.first_frame_index, o.frame_times.c_str(), s.gyro.size(), o.gyro_csv.c_str());
  return write_video_recording(o, s);
}

int run_on_video_with_gcsv(const Options& o) {
  if (!o.target.empty()) throw UsageError("--gcsv: the motion is a gyro; --target needs a trajectory");
  if (!o.gyro_csv.empty() || !o.frame_times.empty()) throw UsageError("--gcsv is the video's gyro: not with --gyro-csv or --frame-times");
  const formats::GcsvLog g = formats::read_gcsv(o.gcsv);
  const std::vector<double> times = formats::read_video_frame_times(o.log);
  const formats::VideoReader video(o.log);
  std::optional<double> line_delay;
  std::optional<dsp::Readout> readout;
  if (g.readout_direction && *g.readout_direction > 1)
    std::fprintf(stderr, "rsd-extract: %s: frame_readout_direction %d reads columns; rsd's rolling shutter reads rows, so its readout is "
                 "left out of the nominal model\n", o.gcsv.c_str(), *g.readout_direction);
  else if (g.frame_readout_s) {
    line_delay = *g.frame_readout_s / video.height();
    readout = g.readout_direction == 1 ? dsp::Readout::BottomToTop : dsp::Readout::TopToBottom;
  }
  MotionLog s;
  for (double t : times) s.frames.push_back({t, line_delay, readout, video.width(), video.height()});
  s.gyro = g.gyro;
  s.gyro_frame = static_cast<int>(rsd::velocity_t::FRAME_IMU);
  s.channels = {{o.log + " video", static_cast<int>(times.size())}, {o.gcsv, static_cast<int>(g.gyro.size())}};
  s.events = static_cast<int>(times.size() + g.gyro.size());
  std::fprintf(stderr, "rsd-extract: %zu frames at %dx%d from %s, %zu gyro samples from %s (id '%s', orientation '%s': gyroflow's axes "
               "convention, not read; rsd-diagnose --imu-axes search finds the axes)\n", times.size(), video.width(), video.height(),
               o.log.c_str(), g.gyro.size(), o.gcsv.c_str(), g.id.c_str(), g.orientation.c_str());
  return write_video_recording(o, s);
}

}  // namespace rsd::tools::extract
