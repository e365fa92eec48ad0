#include "daemon/source_config.hpp"

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <utility>

#include "drivers/driver_registry.hpp"
#include "drivers/recording_replay_source.hpp"
#include "drivers/replay_source.hpp"
#include "formats/intrinsics_file.hpp"
#include "formats/number_text.hpp"

namespace rsd::daemon {

namespace {

// source.camera or source.intrinsics_file (Kalibr camchain or ROS camera_info, relative paths
// taken from the configuration's directory); reading only.
void read_intrinsics(formats::YamlMap& m, SourceConfig& s) {
  if (m.has("camera")) {
    const dsp::CameraModel none;
    s.camera = formats::read_camera_section(m.map("camera"), none);
  }
  if (!m.has("intrinsics_file")) {
    m.text("intrinsics_camera", "");
    return;
  }
  if (s.camera) m.fail("intrinsics_file", "and source.camera both give intrinsics: keep one");
  s.camera_origin = "source.intrinsics_file";
  std::filesystem::path file = m.text("intrinsics_file", "");
  if (file.is_relative()) file = std::filesystem::path(m.file()).parent_path() / file;
  formats::Intrinsics in;
  try {
    in = formats::load_intrinsics(file.string(), m.text("intrinsics_camera", ""));
  } catch (const std::exception& e) {
    m.fail("intrinsics_file", std::string("cannot be used: ") + e.what());
  }
  s.camera = in.cam;
  if (in.line_delay_s)  // a calibrated line delay beats "the readout fills the frame"
    for (const drivers::Driver& d : drivers::all_drivers()) d.use_row_timing(s.settings[d.name], *in.line_delay_s, std::nullopt, false);
}

}  // namespace

void use_calibration(SourceConfig& s, formats::Calibration cal) {
  if (s.camera && s.camera_origin != cal.file + " (cam0)")
    throw formats::ConfigError(cal.file + ": the calibration's intrinsics and " + s.camera_origin + " both give the camera: keep one");
  if (s.shutter == dsp::Shutter::Global && cal.has_rsd_block && cal.line_delay_s > 0)
    throw formats::ConfigError(cal.file + ": cam0.rsd.line_delay_s is " + formats::number_text(cal.line_delay_s) +
                               " s, but source.shutter is global (no line delay): correct one of them");
  s.camera = cal.cam;
  s.camera_origin = cal.file + " (cam0)";
  // A line delay of 0 in a calibration means a global shutter; the drivers' own timing (0: the
  // readout fills the frame) then stays, since there is no rolling shutter to correct.
  if (cal.has_rsd_block && cal.line_delay_s > 0)
    for (const drivers::Driver& d : drivers::all_drivers()) d.use_row_timing(s.settings[d.name], cal.line_delay_s, cal.readout, true);
  s.calibration = std::move(cal);
}

SourceConfig::SourceConfig() {
  for (const drivers::Driver& d : drivers::all_drivers()) settings[d.name] = d.defaults();
}

void visit_source(formats::ConfigSection& c, SourceConfig& s) {
  c.value("driver", s.driver, "sim, aravis, v4l2, libcamera, replay (a recorded log), recording (an images recording) or lcm (frames over LCM)");
  const drivers::Driver* driver = drivers::find_driver(s.driver);
  c.check(driver != nullptr, "driver", "must be " + drivers::driver_names());
  c.choice("shutter", s.shutter, {{"rolling", dsp::Shutter::Rolling}, {"global", dsp::Shutter::Global}},
           "rolling (rows read one after another; a line delay of 0 from a recording: not yet measured, the online "
           "calibration finds it) or global (every row at once: no line delay, no rolling-shutter rectification)");
  c.note("camera: {width: 1280, height: 720, fx: 900, fy: 900, cx: 639.5, cy: 359.5, distortion: [0, 0, 0, 0]}");
  c.note("    (a fisheye: model: pinhole-equi, distortion: [k1, k2, k3, k4]; docs/geometry.md, lens models)");
  c.note("intrinsics_file: camchain.yaml   # or a Kalibr camchain / ROS camera_info file (intrinsics_camera: cam0)");
  c.note("calibration_file: cal.yaml   # or an rsd-calibration/1 file (docs/formats/calibration-v1.md): intrinsics,");
  c.note("    line delay, readout, and the IMU's time offset, gyro bias and scale, rotation (rsd --calibration FILE)");
  c.note("The intrinsics of a real camera are required (camera, intrinsics_file or calibration_file).");
  auto* reader = dynamic_cast<formats::ConfigReader*>(&c);
  if (reader) read_intrinsics(reader->map(), s);
  for (const drivers::Driver& d : drivers::all_drivers())
    c.section(d.name.c_str(), [&](formats::ConfigSection& sub) { d.visit(sub, s.settings[d.name]); }, d.summary.c_str());
  if (s.shutter == dsp::Shutter::Global)
    for (const drivers::Driver& d : drivers::all_drivers()) d.use_global_shutter(s.settings[d.name]);
  // After the drivers' sections: a calibration's row timing replaces theirs.
  if (reader && reader->map().has("calibration_file")) {
    formats::YamlMap& m = reader->map();
    std::filesystem::path file = m.text("calibration_file", "");
    if (file.is_relative()) file = std::filesystem::path(m.file()).parent_path() / file;
    formats::Calibration cal;
    try {
      cal = formats::read_calibration(file.string());
    } catch (const std::exception& e) {
      m.fail("calibration_file", std::string("cannot be used: ") + e.what());
    }
    use_calibration(s, std::move(cal));
  }
  if (!driver) return;
  if (s.driver == "replay") {
    const std::string& log = s.settings_of<drivers::ReplayConfig>("replay").file;
    c.check(!log.empty(), "driver", "'replay' needs replay.file: the LCM log to play");
    c.check(log.empty() || std::filesystem::is_regular_file(log), "driver",
            "'replay' plays replay.file '" + log + "', which does not exist (or is not a file)");
  }
  if (s.driver == "recording") {
    const std::string& dir = s.settings_of<drivers::RecordingReplayConfig>("recording").dir;
    c.check(!dir.empty(), "driver", "'recording' needs recording.dir: the images recording to play");
    c.check(dir.empty() || std::filesystem::is_regular_file(std::filesystem::path(dir) / "recording.yaml"), "driver",
            "'recording' plays recording.dir '" + dir + "', which holds no recording.yaml");
  }
  // Intrinsics for another frame size than the section asks the camera for (or the simulator
  // renders): refused now, not when the camera first delivers (at start, or over SIGHUP).
  const char* intrinsics_key = s.calibration ? "calibration_file" : s.camera_origin == "source.intrinsics_file" ? "intrinsics_file" : "camera";
  std::optional<std::pair<int, int>> size = driver->configured_size(s.settings.at(s.driver));
  if (const auto own = driver->own_camera(s.settings.at(s.driver)); own && !size) size = std::pair<int, int>(own->width, own->height);
  if (s.camera && size)
    c.check(s.camera->width == size->first && s.camera->height == size->second, intrinsics_key,
            s.camera_origin + " gives intrinsics for " + std::to_string(s.camera->width) + "x" +
                std::to_string(s.camera->height) + ", but source." + s.driver + " asks the camera for " +
                std::to_string(size->first) + "x" + std::to_string(size->second));
  c.check(!driver->real_camera || s.camera.has_value(), "driver",
          "'" + s.driver + "' needs the camera's intrinsics: add source.camera {width, height, fx, fy, cx, cy, distortion}, "
          "source.intrinsics_file (Kalibr camchain or ROS camera_info) or source.calibration_file");
}

std::unique_ptr<drivers::CameraSource> make_source(const SourceConfig& s) {
  const drivers::Driver* d = drivers::find_driver(s.driver);
  if (!d) throw std::runtime_error("source.driver '" + s.driver + "' is not one of " + drivers::driver_names());
  return d->make(s.settings.at(s.driver));
}

dsp::CameraModel camera_model(const SourceConfig& s, const drivers::FrameFormat& f,
                              const std::optional<dsp::CameraModel>& recorded) {
  // What the daemon is told (source.camera, a calibration) comes first, even for the simulator,
  // whose own camera is then the hidden truth the rectifier does not know.
  if (!s.camera)
    if (const drivers::Driver* d = drivers::find_driver(s.driver))
      if (const auto own = d->own_camera(s.settings.at(s.driver))) return *own;
  if (!s.camera && !recorded)
    throw std::runtime_error("source '" + s.driver + "': the frames carry no intrinsics (only rsd --record writes them): "
                             "add source.camera or source.intrinsics_file");
  const dsp::CameraModel& c = s.camera ? *s.camera : *recorded;
  if (c.width != f.width || c.height != f.height)
    throw std::runtime_error((s.camera ? s.camera_origin : std::string("the recorded intrinsics")) + " says " +
                             std::to_string(c.width) + "x" + std::to_string(c.height) + "," +
                             " but the camera delivers " + std::to_string(f.width) + "x" + std::to_string(f.height));
  return c;
}

}  // namespace rsd::daemon
