// rsd's configuration: one YAML file, validated strictly (unknown keys and bad values are
// errors naming the file, line and key). Every key has a default; `rsd
// --print-default-config` prints them all, and an empty file runs the built-in simulated
// camera.
#pragma once

#include <string>

#include "daemon/frame_rectifier.hpp"
#include "daemon/lcm_publisher.hpp"
#include "daemon/online_calibration.hpp"
#include "daemon/pipeline.hpp"
#include "daemon/source_watch.hpp"
#include "daemon/velocity_buffer.hpp"
#include "daemon/velocity_input.hpp"
#include "daemon/source_config.hpp"

namespace rsd::daemon {

struct Config {
  SourceConfig source;
  PipelineConfig pipeline;
  RectifyConfig rectify;
  VelocityLimits velocity_limits;
  std::string velocity_channel = "RSD_VELOCITY";
  VelocityInputConfig velocity_input;  // pose channel, sensor-to-camera rotations, gyro-only
  std::string lcm_url = "memq://";
  Channels channels;
  // rsd --record FILE: raw frames with their timing, velocity and outputs into one LCM log.
  std::string record_file;
  bool record_append = false;  // after a SIGHUP reload: continue the recording
  // rsd --output-dir / --output-video (replays only): rectified frames to files as well.
  FrameFilesConfig output;
  HealthConfig health;                // the stall detector and the frame-rate warning
  OnlineCalibrationConfig online;     // calibration: the online self-calibration
  std::string log_level = "info";     // log.level; rsd --log-level overrides it
};

// Throws formats::ConfigError naming file, line and key.
Config load_config(const std::string& file);
// rsd --calibration FILE: an rsd-calibration/1 file (docs/formats/calibration-v1.md) over the
// configuration: intrinsics, row timing, and the IMU's rotation, clock offset, bias and scale
// replace what the configuration (or its own calibration_file) says of them.
void use_calibration_file(Config& c, const std::string& file);
// The same for a calibration in memory (an images recording's nominal model, for one).
void apply_calibration(Config& c, formats::Calibration cal);
std::string default_config_yaml();

}  // namespace rsd::daemon
