// What a camera driver tells the rest of rsd about itself: its name (the `source.driver`
// value and the name of its config section), its config section (read and printed by one
// visit function, formats/config_section.hpp), and how to make its CameraSource. Drivers
// are listed in drivers/driver_registry.cpp, apart from the core: the daemon and the tools
// know only this and CameraSource (libcamera's pipeline-handler registration is the model).
//
// Thread contract: entries are immutable after start-up; make() runs on the caller's thread.
#pragma once

#include <any>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "drivers/camera_source.hpp"
#include "dsp/core/input_limits.hpp"
#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/row_timing.hpp"
#include "formats/config_section.hpp"

namespace rsd::drivers {

// What a driver section may ask for: an image side, a frame rate, an exposure, buffers.
inline constexpr int kMinSide = dsp::limits::kMinSide, kMaxSide = dsp::limits::kMaxSide;  // the rectifier's
inline constexpr double kMaxRateHz = 10000, kMaxExposureS = 10;
inline constexpr int kMaxBuffers = 64;

struct Driver {
  std::string name;
  std::string summary;      // the comment of its section in the printed defaults
  bool real_camera = true;  // needs the camera's intrinsics (source.camera or intrinsics_file)
  // The key of its section that names which camera to open ("live:NAME:ADDRESS" in the tools).
  std::string address_key;
  std::function<std::any()> defaults;
  std::function<void(formats::ConfigSection&, std::any&)> visit;
  std::function<std::unique_ptr<CameraSource>(const std::any&)> make;
  // Sources that know their own intrinsics (the simulator); nullopt for the others.
  std::function<std::optional<dsp::CameraModel>(const std::any&)> own_camera = [](const std::any&) {
    return std::optional<dsp::CameraModel>();
  };
  // Row timing calibrated elsewhere (an intrinsics file from Kalibr, a calibration file):
  // `force` replaces the section's own; otherwise it is used only where the section has none.
  std::function<void(std::any&, double line_delay_s, std::optional<dsp::Readout>, bool force)> use_row_timing =
      [](std::any&, double, std::optional<dsp::Readout>, bool) {};
  // source.shutter: global: a camera that can read every row at once does (the simulator);
  // the others' own timing is overruled by the daemon (no line delay).
  std::function<void(std::any&)> use_global_shutter = [](std::any&) {};
  // The motion sensor's calibrated clock offset (t_imu = t_cam + offset), for sources that hand
  // over recorded motion ahead of the frames that need it.
  std::function<void(std::any&, double offset_s)> use_clock_offset = [](std::any&, double) {};
  // The frame size its section asks the camera for (nullopt: the camera's own, or unknown until
  // it opens), so that intrinsics for another size are refused before it runs.
  std::function<std::optional<std::pair<int, int>>(const std::any&)> configured_size = [](const std::any&) {
    return std::optional<std::pair<int, int>>();
  };
};

// A driver whose settings are `Config` and whose source is `Source(const Config&)`.
template <class Source, class Config>
Driver make_driver(std::string name, std::string summary, bool real_camera, void (*visit)(formats::ConfigSection&, Config&)) {
  Driver d;
  d.name = std::move(name);
  d.summary = std::move(summary);
  d.real_camera = real_camera;
  d.defaults = [] { return std::any(Config{}); };
  d.visit = [visit](formats::ConfigSection& s, std::any& c) { visit(s, std::any_cast<Config&>(c)); };
  d.make = [](const std::any& c) -> std::unique_ptr<CameraSource> { return std::make_unique<Source>(std::any_cast<const Config&>(c)); };
  if constexpr (requires(Config x) {
                  x.width = 0;
                  x.height = 0;
                }) {
    if (real_camera)
      d.configured_size = [](const std::any& c) -> std::optional<std::pair<int, int>> {
        const auto& x = std::any_cast<const Config&>(c);
        if (x.width > 0 && x.height > 0) return std::pair<int, int>(x.width, x.height);
        return std::nullopt;
      };
  }
  if constexpr (requires(Config x) {
                  x.line_delay_s = 0.0;
                  x.readout = dsp::Readout::TopToBottom;
                }) {
    if (real_camera)
      d.use_row_timing = [](std::any& c, double s, std::optional<dsp::Readout> readout, bool force) {
        auto& x = std::any_cast<Config&>(c);
        if (force || x.line_delay_s == 0) x.line_delay_s = s;
        if (readout && force) x.readout = *readout;
      };
  }
  if constexpr (requires(Config x) { x.global_shutter = true; })
    d.use_global_shutter = [](std::any& c) { std::any_cast<Config&>(c).global_shutter = true; };
  return d;
}

}  // namespace rsd::drivers
