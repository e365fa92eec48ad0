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

#include "drivers/camera_source.hpp"
#include "dsp/geometry/camera_model.hpp"
#include "formats/config_section.hpp"

namespace rsd::drivers {

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
  // A line delay calibrated elsewhere (an intrinsics file from Kalibr): used unless the
  // section sets its own.
  std::function<void(std::any&, double)> use_line_delay = [](std::any&, double) {};
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
  if constexpr (requires(Config x) { x.line_delay_s = 0.0; }) {
    if (real_camera)
      d.use_line_delay = [](std::any& c, double s) {
        auto& x = std::any_cast<Config&>(c);
        if (x.line_delay_s == 0) x.line_delay_s = s;
      };
  }
  return d;
}

}  // namespace rsd::drivers
