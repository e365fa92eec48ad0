// rsd-extract: an LCM recording (raw frames plus gyro or a trajectory) -> an observation
// recording (docs/formats/recording-v1.md) that rsd-diagnose reads. The matches kind comes
// from feature tracking between consecutive frames (dsp/features/feature_tracks.hpp), the landmarks
// kind from detecting a checkerboard or AprilGrid (dsp/features/target_observations.hpp). The nominal
// model is the user's (--nominal / --intrinsics and the timing options); see docs/extract.md.
#include <CLI/CLI.hpp>
#include <rsd/velocity_t.hpp>

#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dsp/features/feature_tracks.hpp"
#include "dsp/features/target_observations.hpp"
#include "formats/image_file.hpp"
#include "formats/lcm_log.hpp"
#include "formats/motion_log.hpp"
#include "formats/recording_v1.hpp"
#include "formats/target_spec.hpp"
#include "tools/common/cli_util.hpp"
#include "tools/common/frame_sources.hpp"
#include "tools/common/picture_observations.hpp"
#include "tools/common/progress_line.hpp"
#include "tools/extract/extract_options.hpp"
#include "tools/extract/nominal_model.hpp"
#include "tools/extract/video_inputs.hpp"

namespace formats = rsd::formats;
using namespace rsd;
using namespace rsd::tools;
using namespace rsd::dsp;
using namespace rsd::tools::extract;

using formats::MotionLog;
using formats::channel_list;

namespace {

constexpr const char* kDescription =
    "rsd-extract: turns an LCM log of raw frames (bot_core.image_t) plus motion into an observation\n"
    "recording (rsd-recording/1) for rsd-diagnose.\n"
    "  matches kind:   features tracked between consecutive frames; motion = the angular velocity\n"
    "                  of rsd.velocity_t (camera or IMU axes) as gyro.csv.\n"
    "  landmarks kind: a checkerboard or AprilGrid detected in every frame (--target); motion = the\n"
    "                  body pose of bot_core.pose_t (world = the target's frame) as trajectory.csv.\n"
    "The nominal model is yours: intrinsics from --nominal (recording.yaml's camera/timing/motion\n"
    "keys) or --intrinsics (Kalibr camchain / ROS camera_info). Timing precedence: options, then\n"
    "--nominal, then the intrinsics file (Kalibr line_delay, timeshift_cam_imu), then the log's\n"
    "metadata (line_delay_ns, readout), then global shutter. The frame rate defaults to the log's\n"
    "median frame interval. To test whether a sensor is really what a simulation assumed, state\n"
    "that assumption, e.g. --assume-global-shutter.\n"
    "With --images it writes an images recording instead: the frames as PNG files and the motion.\n"
    "Given an images recording directory (a phone's frames and gyro, say), it makes the observations\n"
    "from the pictures, with the recording's own recording.yaml as the nominal model.\n"
    "Given a GoPro MP4, any video with --frame-times and --gyro-csv (a phone logger's files), or any\n"
    "video with --gcsv (gyroflow's sidecar gyro log), it writes an images recording whose pictures\n"
    "stay in the video.\n\n"
    "Examples:\n"
    "  rsd-extract run.lcmlog rec/ --nominal nominal.yaml --assume-global-shutter \\\n"
    "      --target checkerboard:9x7:0.05 && rsd-diagnose rec/ --json diagnosis.json\n"
    "  rsd-extract run.lcmlog pictures/ --nominal nominal.yaml --images\n"
    "  rsd-extract pictures/ rec/\n"
    "  rsd-extract video.mp4 rec/ --frame-times frames.txt --gyro-csv gyro.csv --time-unit ns --nominal phone.yaml\n"
    "  rsd-extract clip.mp4 rec/ --gcsv clip.gcsv --intrinsics camchain.yaml\n"
    "Exit status: 0 on success, 2 on bad arguments, 1 on other errors. See docs/extract.md.";

// ---------------------------------------------------------------- pass 2: observations

// The log's frames, read a second time, as pictures for tools/common/picture_observations.
struct LogPictures {
  std::unique_ptr<FrameSource> src;
  PictureFrames frames;
  LogPictures(const Options& o, const MotionLog& s, const std::vector<bool>& ok)
      : src(open_frame_source({o.log}, FrameSourceOptions{o.image_channel, 0})) {
    frames.what = o.log + " (" + o.image_channel + ")";
    frames.usable = ok;
    for (size_t k = 0; k < s.frames.size(); ++k) frames.numbers.push_back(static_cast<int>(k)), frames.times.push_back(s.frames[k].t);
    frames.next = [this]() -> std::optional<dsp::Image> {
      std::optional<SourceFrame> f = src->next();
      if (!f) return std::nullopt;
      return std::move(f->image);
    };
  }
};

// ---------------------------------------------------------------- the run

dsp::ObservationKind choose_kind(const Options& o, const MotionLog& s) {
  const std::string ch = " (channels in the log: " + channel_list(s) + ")";
  if (o.kind == "landmarks" || (o.kind == "auto" && !o.target.empty() && !s.poses.empty())) {
    if (o.target.empty()) throw UsageError("--kind landmarks needs --target (checkerboard:COLSxROWS:SQUARE_M or aprilgrid:...)");
    if (s.poses.size() < 2)
      throw UsageError(o.log + ": fewer than two bot_core.pose_t on " + o.pose_channel + ": the landmarks kind needs the body trajectory (see --pose-channel)" + ch);
    return dsp::ObservationKind::Landmarks;
  }
  if (s.gyro.size() < 2)
    throw UsageError(o.log + ": fewer than two rsd.velocity_t on " + o.velocity_channel +
                     ": the matches kind needs the angular velocity (see --velocity-channel" +
                     (o.kind == "auto" ? "; or --target with poses on " + o.pose_channel + " for the landmarks kind)" : ")") + ch);
  return dsp::ObservationKind::Matches;
}

// The matches kind is rotation-only: a log whose velocity says the camera translates will show
// parallax wherever the scene is near, which rsd-diagnose reports as a remainder (never as an
// effect). 1 cm/s: the speed at which a scene 1 m away moves a 1000 px camera's image by 0.3 px
// between frames at 30 fps.
void warn_translation(const Options& o, const MotionLog& s) {
  if (s.with_translation == 0 || s.max_speed_m_s < 0.01) return;
  std::fprintf(stderr,
               "rsd-extract: warning: the velocity on %s carries translation (median %.3g m/s, up to %.3g m/s in %d "
               "of %zu messages); the matches kind assumes a rotating camera and a distant scene, so a near "
               "scene's parallax will show in rsd-diagnose as a remainder (translation), not as an effect\n",
               o.velocity_channel.c_str(), s.median_speed_m_s, s.max_speed_m_s, s.with_translation, s.gyro.size());
}

// --images: the usable frames as PNG files under OUT/frames, with images.csv, instead of
// observations: an images recording that rsd --replay, rsd-extract and rsd-diagnose read.
void write_pictures(const Options& o, LogPictures& pictures, const std::optional<TargetSpec>& target, dsp::Recording& rec) {
  formats::ImagesRecording out;
  out.rec = rec;
  out.target = target;
  if (rec.kind == dsp::ObservationKind::Landmarks) out.rec.points = target_points(*target);
  const std::filesystem::path dir = std::filesystem::path(o.out) / "frames";
  std::filesystem::create_directories(dir);
  PictureFrames& f = pictures.frames;
  for (size_t k = 0; k < f.numbers.size(); ++k) {
    std::optional<dsp::Image> img = f.next();
    if (!img) throw std::runtime_error(o.log + ": frame " + std::to_string(k) + " vanished on the second read");
    if (!f.usable[k]) continue;
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", f.numbers[k]);
    formats::write_png((dir / name).string(), img->view());
    out.files.push_back((dir / name).string());
    std::fprintf(stderr, "\rrsd-extract: frame %zu/%zu written", k + 1, f.numbers.size());
  }
  std::fprintf(stderr, "\n");
  formats::write_images_recording(o.out, out);
  std::printf("rsd-extract: wrote an images recording (%zu frames as PNG, %zu %s samples) to %s\n", out.files.size(),
              rec.motion == dsp::MotionKind::Gyro ? rec.gyro.size() : rec.trajectory.size(), dsp::to_string(rec.motion),
              o.out.c_str());
}

// The first pass's progress: the log read, in MB (it reads every frame's bytes to reach the
// motion between them; ten minutes of 1080p take a minute), one line rewritten as it goes.
std::function<void(uint64_t, uint64_t)> read_progress() {
  auto line = std::make_shared<ProgressLine>("rsd-extract: ");
  auto last = std::make_shared<long>(-1);
  return [line, last](uint64_t read, uint64_t size) {
    const long total = std::max(static_cast<long>(size >> 20), 1L), mb = std::min(static_cast<long>(read >> 20), total);
    const long done = read < size ? mb : total;
    if (done == *last) return;  // the end is said once
    *last = done;
    line->step("reading the motion (MB of the log)", done, total);
  };
}

// rsd-extract DIR OUT: an images recording's observations, made from its pictures.
int run_on_recording(const Options& o) {
  if (!o.nominal.empty() || !o.intrinsics.empty() || o.global_shutter || o.line_delay_s || o.frame_rate_hz || o.time_offset_s ||
      !o.readout.empty() || !o.imu_to_camera.empty() || !o.lever_arm.empty() || !o.target.empty() || o.images)
    throw UsageError(o.log + " is an images recording: its recording.yaml is the nominal model and names the target; "
                     "the nominal-model options, --target and --images apply to LCM logs");
  std::fprintf(stderr, "rsd-extract: reading the images recording %s\n", o.log.c_str());
  const formats::ImagesRecording r = formats::read_images_recording(o.log);
  dsp::Recording rec = observations_from_pictures(r, o.track, static_cast<size_t>(o.track_pairs));
  if (o.noise_px) rec.noise_px = o.noise_px;
  formats::write_recording(o.out, rec);
  std::printf("rsd-extract: wrote a %s recording (%zu frames) to %s\n", dsp::to_string(rec.kind), rec.frames.size(), o.out.c_str());
  return 0;
}

int run(const Options& o) {
  if (std::filesystem::is_directory(o.log)) return run_on_recording(o);
  if (!o.gcsv.empty()) return run_on_video_with_gcsv(o);
  if (!o.gyro_csv.empty()) return run_on_video_with_csv(o);
  if (!o.frame_times.empty()) throw UsageError("--frame-times goes with --gyro-csv (a video with its gyro as text)");
  if (looks_like_mp4(o.log)) return run_on_gopro_clip(o);
  std::optional<TargetSpec> target;
  if (!o.target.empty()) {
    try {
      target = formats::parse_target(o.target);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--target: ") + e.what());
    }
  }
  std::fprintf(stderr, "rsd-extract: reading %s\n", o.log.c_str());
  if (!formats::looks_like_lcm_log(o.log)) throw UsageError("LOG: '" + o.log + "' is not a readable LCM log");
  const MotionLog s = formats::read_motion_log(o.log, {o.image_channel, o.velocity_channel, o.pose_channel}, read_progress());
  if (s.events == 0) throw UsageError("LOG: '" + o.log + "' holds no LCM events (not an LCM log, or empty)");
  if (s.frames.empty())
    throw UsageError(o.log + ": no bot_core.image_t frames on channel " + o.image_channel + " (see --image-channel; channels in the log: " + channel_list(s) + ")");
  const dsp::ObservationKind kind = choose_kind(o, s);
  Nominal n = nominal_model(o, s);
  dsp::Recording rec;
  rec.kind = kind;
  rec.noise_px = o.noise_px;
  if (kind == dsp::ObservationKind::Matches) {
    rec.motion = dsp::MotionKind::Gyro;
    rec.gyro = s.gyro;
    warn_translation(o, s);
    if (*s.gyro_frame == rsd::velocity_t::FRAME_CAMERA) {
      n.model.imu_to_camera = Eigen::Matrix3d::Identity();  // the rates are already in camera axes
      n.notes.push_back("gyro in camera axes (rsd.velocity_t FRAME_CAMERA): imu_to_camera = identity");
    } else {
      if (!n.imu_to_camera) throw UsageError(o.log + ": the velocity on " + o.velocity_channel + " is in IMU axes: give --imu-to-camera or motion.imu_to_camera in --nominal");
      n.model.imu_to_camera = *n.imu_to_camera;
    }
  } else {
    rec.motion = dsp::MotionKind::Trajectory;
    rec.trajectory = s.poses;
  }
  rec.nominal = n.model;
  for (const std::string& note : n.notes) std::fprintf(stderr, "rsd-extract: %s\n", note.c_str());
  const std::vector<bool> ok = covered(s, n, kind == dsp::ObservationKind::Matches);
  rec.frames = covered_frames(s, ok, o.log);
  if (rec.frames.size() < s.frames.size())
    std::fprintf(stderr, "rsd-extract: %zu of %zu frames lie outside the motion's time span (with 50 ms to spare) and are left out\n",
                 s.frames.size() - rec.frames.size(), s.frames.size());
  LogPictures pictures(o, s, ok);
  if (o.images) {
    write_pictures(o, pictures, target, rec);
    return 0;
  }
  if (kind == dsp::ObservationKind::Matches) make_matches(pictures.frames, o.track, rec, static_cast<size_t>(o.track_pairs));
  else make_landmarks(pictures.frames, *target, o.target, rec);
  formats::write_recording(o.out, rec);
  std::printf("rsd-extract: wrote a %s recording (%zu frames, %zu %s samples) to %s\n", dsp::to_string(kind), rec.frames.size(),
              kind == dsp::ObservationKind::Matches ? rec.gyro.size() : rec.trajectory.size(), dsp::to_string(rec.motion), o.out.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app(kDescription, "rsd-extract");
  app.add_option("INPUT", o.log,
                 "LCM log with raw frames and motion, an images recording directory, a GoPro MP4 (its GPMF gyro), or a video "
                 "with --frame-times and --gyro-csv, or with --gcsv")
      ->required()->check(CLI::ExistingPath);
  app.add_option("OUTDIR", o.out, "Observation recording directory to write (created)")->required();
  app.add_option("--nominal", o.nominal, "YAML with recording.yaml's camera: / timing: / motion: keys (a recording.yaml will do)")
      ->check(CLI::ExistingFile);
  app.add_option("--intrinsics", o.intrinsics, "Kalibr camchain or ROS camera_info YAML with the nominal intrinsics")->check(CLI::ExistingFile);
  app.add_option("--intrinsics-camera", o.intrinsics_camera, "Kalibr camera (cam0, cam1, ...) in --intrinsics");
  app.add_option("--kind", o.kind, "matches, landmarks, or auto: landmarks when --target is given and the log has poses")
      ->check(CLI::IsMember({"auto", "matches", "landmarks"}))->capture_default_str();
  app.add_flag("--images", o.images,
               "write an images recording instead (the frames as PNG under OUTDIR/frames, images.csv, the motion):\n"
               "what rsd --replay DIR, rsd-extract DIR and rsd-diagnose DIR read");
  app.add_option("--target", o.target, "checkerboard:COLSxROWS:SQUARE_M (inner corners) or aprilgrid:COLSxROWS:TAG_M[:SPACING]");
  app.add_flag("--assume-global-shutter", o.global_shutter, "nominal line delay 0 (whatever the log or files say)");
  app.add_option("--line-delay", o.line_delay_s, "nominal line delay, s")->check(CLI::NonNegativeNumber);
  app.add_option("--readout", o.readout, "nominal readout: top_to_bottom or bottom_to_top (default: the log's metadata)");
  app.add_option("--frame-rate", o.frame_rate_hz, "nominal frame rate, Hz (default: the log's median frame interval)")->check(positive("Hz"));
  app.add_option("--time-offset", o.time_offset_s, "nominal time offset, s (t_motion = t_camera + offset)")->check(finite_number("s"));
  app.add_option("--imu-to-camera", o.imu_to_camera, "9 numbers, row-major R with w_camera = R w_imu (IMU-frame velocity; default for a GoPro MP4: its "
                 "gyro stream's ORIN, else the order GoPro documents for its model, else the identity)");
  app.add_option("--lever-arm", o.lever_arm, "camera origin in the tracked body's frame, m")->check(vec3("x,y,z in m"));
  app.add_option("--noise-px", o.noise_px, "state the known pixel noise sigma in recording.yaml (default: omitted)")->check(positive("px"));
  app.add_option("--frame-times", o.frame_times, "a video's frames' times, one per line (a phone logger's; with --gyro-csv)")
      ->check(CLI::ExistingFile);
  app.add_option("--gyro-csv", o.gyro_csv, "the gyro of a video as text, rad/s in IMU axes (columns: --gyro-columns)")->check(CLI::ExistingFile);
  app.add_option("--gyro-columns", o.gyro_columns, "the order of --gyro-csv's columns; '-' skips one, e.g. t,-,wx,wy,wz")
      ->capture_default_str();
  app.add_option("--time-unit", o.time_unit, "unit of the times in --frame-times and --gyro-csv")
      ->check(CLI::IsMember({"s", "ms", "us", "ns"}))->capture_default_str();
  app.add_option("--gcsv", o.gcsv, "the video's gyro as gyroflow's .gcsv log (times from the video's first frame; its readout time and direction the nominal timing)")
      ->check(CLI::ExistingFile);
  app.add_option("--first-frame-index", o.first_frame_index, "the line of --frame-times (from 0) that is the video's first frame")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--image-channel", o.image_channel, "bot_core.image_t channel")->capture_default_str();
  app.add_option("--velocity-channel", o.velocity_channel, "rsd.velocity_t channel (matches kind)")->capture_default_str();
  app.add_option("--pose-channel", o.pose_channel, "bot_core.pose_t channel (landmarks kind)")->capture_default_str();
  app.add_option("--max-matches", o.track.max_per_pair, "matches kept per frame pair")->check(int_range(1, 100000))->capture_default_str();
  app.add_option("--track-pairs", o.track_pairs, kTrackPairsHelp)->check(int_range(0, 100000000))->capture_default_str();
  app.add_option("--max-fb-error", o.track.max_fb_error_px, "forward-backward tracking check, px")->check(positive("px"))->capture_default_str();
  app.add_option("--min-ncc", o.track.min_ncc, "least correlation of the patches around a match's two ends")
      ->check(CLI::Range(-1.0, 1.0))->capture_default_str();
  if (const auto rc = parse_command_line(app, argc, argv)) return *rc;
  return run_tool("rsd-extract", [&] { return run(o); });
}
