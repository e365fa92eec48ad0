// The `source:` section of rsd's configuration: which driver, its settings, and the camera's
// intrinsics (the simulated camera knows its own; real cameras need `camera:`).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "drivers/aravis_source.hpp"
#include "drivers/lcm_source.hpp"
#include "drivers/libcamera_source.hpp"
#include "drivers/replay_source.hpp"
#include "drivers/sim_source.hpp"
#include "drivers/v4l2_source.hpp"
#include "formats/yaml_map.hpp"

namespace rsd::daemon {

struct SourceConfig {
  std::string driver = "sim";  // sim, aravis, v4l2, libcamera, replay, lcm
  drivers::SimSourceConfig sim;
  drivers::AravisConfig aravis;
  drivers::V4l2Config v4l2;
  drivers::LibcameraConfig libcamera;
  drivers::ReplayConfig replay;
  drivers::LcmSourceConfig lcm;
  std::optional<dsp::CameraModel> camera;  // intrinsics of a real camera (source.camera)
};

// Reads the section; throws drivers::ConfigError naming file, line and key.
void read_source(formats::YamlMap m, SourceConfig& s);

std::unique_ptr<drivers::CameraSource> make_source(const SourceConfig& s);

// The intrinsics the rectifier uses, for the format the camera delivers: the configured ones
// (sizes must match), the simulated camera's own, or (replay, lcm) those the frames carry.
dsp::CameraModel camera_model(const SourceConfig& s, const drivers::FrameFormat& f,
                              const std::optional<dsp::CameraModel>& recorded = std::nullopt);

}  // namespace rsd::daemon
