// The `source:` section of rsd's configuration: which driver, every driver's own section
// (each driver reads and prints it: drivers/driver.hpp), and the camera's intrinsics (the
// simulated camera knows its own; real cameras need `camera:` or `intrinsics_file:`).
#pragma once

#include <any>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "drivers/camera_source.hpp"
#include "dsp/geometry/camera_model.hpp"
#include "dsp/online/shutter.hpp"
#include "formats/calibration_v1.hpp"
#include "formats/config_section.hpp"

namespace rsd::daemon {

struct SourceConfig {
  SourceConfig();  // every driver's defaults
  std::string driver = "sim";
  std::map<std::string, std::any> settings;  // by driver name: that driver's config struct
  std::optional<dsp::CameraModel> camera;    // intrinsics of a real camera (source.camera)
  std::string camera_origin = "source.camera";  // where `camera` came from, for messages
  std::optional<formats::Calibration> calibration;  // source.calibration_file or rsd --calibration
  // source.shutter: rolling (the rows read one after another; a line delay of 0 from a recording
  // means not yet measured) or global (every row at once: no line delay, no rolling-shutter
  // rectification; the online calibration learns the clock offset and the gyro bias).
  dsp::Shutter shutter = dsp::Shutter::Rolling;

  // A driver's settings as its own type (drivers::ReplayConfig for "replay", ...).
  template <class C>
  C& settings_of(const std::string& name) { return std::any_cast<C&>(settings.at(name)); }
  template <class C>
  const C& settings_of(const std::string& name) const { return std::any_cast<const C&>(settings.at(name)); }
};

// Takes a calibration file's intrinsics and row timing (the IMU part is the velocity input's:
// daemon/config.hpp). Throws ConfigError naming the file when the intrinsics are also given
// by source.camera or source.intrinsics_file.
void use_calibration(SourceConfig& s, formats::Calibration cal);

// Reads (formats::ConfigReader) or prints (formats::DefaultsPrinter) the section.
void visit_source(formats::ConfigSection& c, SourceConfig& s);

std::unique_ptr<drivers::CameraSource> make_source(const SourceConfig& s);

// The intrinsics the rectifier uses, for the format the camera delivers: the configured ones
// (sizes must match), the simulated camera's own, or (replay, lcm) those the frames carry.
dsp::CameraModel camera_model(const SourceConfig& s, const drivers::FrameFormat& f,
                              const std::optional<dsp::CameraModel>& recorded = std::nullopt);

}  // namespace rsd::daemon
