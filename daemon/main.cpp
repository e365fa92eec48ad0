// rsd: the rolling-shutter camera daemon.
//
//   rsd                          run on the built-in simulated camera (all defaults)
//   rsd --config FILE            run as configured
//   rsd --check-config FILE      validate a configuration and exit
//   rsd --print-default-config   print every key with its default
//   rsd --record FILE            also write raw frames, velocity and outputs to an LCM log
//   rsd --replay LOG [--speed N|fast] [--loop]   play a recorded log through the pipeline
//   rsd --calibration CAL        apply an rsd-calibration/1 file (intrinsics, row timing, IMU)
#include <CLI/CLI.hpp>
#include <unistd.h>

#include <csignal>
#include <cstdio>

#include "daemon/service.hpp"
#include "formats/yaml_map.hpp"
#include "drivers/replay_source.hpp"

namespace {

rsd::daemon::StopFlags g_flags;

void on_signal(int sig) {
  if (sig == SIGHUP) g_flags.reload = true;
  else g_flags.stop = true;
}

// --replay/--speed/--loop on top of the configuration (the log's own intrinsics are used
// unless the configuration gives source.camera).
bool apply_replay_options(rsd::daemon::Config& cfg, const std::string& file, const std::string& speed, bool loop) {
  if (!file.empty()) {
    cfg.source.driver = "replay";
    cfg.source.settings_of<rsd::drivers::ReplayConfig>("replay").file = file;
  }
  if (!speed.empty() && !rsd::drivers::parse_speed(speed, cfg.source.settings_of<rsd::drivers::ReplayConfig>("replay").speed)) {
    std::fprintf(stderr, "rsd: --speed: expected a positive factor or fast, not '%s'\n", speed.c_str());
    return false;
  }
  if (loop) cfg.source.settings_of<rsd::drivers::ReplayConfig>("replay").loop = true;
  if ((!speed.empty() || loop) && cfg.source.driver != "replay") {
    std::fprintf(stderr, "rsd: --speed and --loop apply to replays (--replay LOG or source.driver: replay)\n");
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rsd: rolling-shutter camera daemon. Captures frames, stamps every row with its capture time,\n"
               "rectifies the rolling-shutter distortion with the current velocity, and publishes images,\n"
               "frame info and health over LCM. Without --config it runs the built-in simulated camera."};
  std::string config_file;
  bool check = false, print_default = false, quiet = false, progress = false, loop = false;
  std::string record_file, replay_file, speed, calibration_file;
  rsd::daemon::RunLimits limits;
  app.add_option("--config,-c", config_file, "YAML configuration (see --print-default-config)")->check(CLI::ExistingFile);
  app.add_option("--calibration", calibration_file,
                 "an rsd-calibration/1 file (docs/formats/calibration-v1.md) over the configuration: intrinsics, line delay,\n"
                 "readout, and the IMU's rotation, time offset, gyro bias and scale")
      ->check(CLI::ExistingFile);
  app.add_flag("--check-config", check, "validate the configuration and exit (status 0 if valid)");
  app.add_flag("--print-default-config", print_default, "print the default configuration and exit");
  app.add_option("--frames", limits.max_frames, "stop after publishing this many frames (0: run until stopped)");
  app.add_option("--duration", limits.max_seconds, "stop after this many seconds (0: run until stopped)");
  app.add_flag("--quiet,-q", quiet, "no live status line, progress bar or closing summary on stderr");
  app.add_option("--record", record_file, "record raw frames (with per-row timing), velocity and outputs to this LCM log");
  app.add_option("--replay", replay_file, "replay this LCM log (source.driver: replay) instead of the configured camera")
      ->check(CLI::ExistingFile);
  app.add_option("--speed", speed, "replay speed: 1 real time (default), N times, or fast (no waiting, no drops)");
  app.add_flag("--loop", loop, "replay: start again at the end of the log");
  app.add_flag("--progress", progress, "replay: show the progress bar even when stderr is not a terminal");
  CLI11_PARSE(app, argc, argv);
  limits.status_line = !quiet;
  limits.progress = !quiet && (progress || isatty(STDERR_FILENO));
  if (print_default) {
    std::fputs(rsd::daemon::default_config_yaml().c_str(), stdout);
    return 0;
  }
  rsd::daemon::Config cfg;
  try {
    if (!config_file.empty()) cfg = rsd::daemon::load_config(config_file);
    if (!calibration_file.empty()) rsd::daemon::use_calibration_file(cfg, calibration_file);
  } catch (const rsd::formats::ConfigError& e) {
    std::fprintf(stderr, "rsd: configuration error: %s\n", e.what());
    return 2;
  }
  if (!apply_replay_options(cfg, replay_file, speed, loop)) return 2;
  cfg.record_file = record_file;
  if (check) {
    std::printf("rsd: %s is valid\n", config_file.empty() ? "the default configuration" : config_file.c_str());
    return 0;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGHUP, on_signal);
  for (;;) {
    try {
      rsd::daemon::run_service(cfg, g_flags, limits);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rsd: error: %s\n", e.what());
      return 1;
    }
    if (!g_flags.reload.exchange(false) || g_flags.stop.load()) return 0;
    // SIGHUP: read the configuration again; a broken file keeps the running one. The
    // command line's replay and recording stay, and the recording continues.
    try {
      if (!config_file.empty() || !calibration_file.empty()) {
        rsd::daemon::Config next;
        if (!config_file.empty()) next = rsd::daemon::load_config(config_file);
        if (!calibration_file.empty()) rsd::daemon::use_calibration_file(next, calibration_file);
        apply_replay_options(next, replay_file, speed, loop);
        next.record_file = record_file;
        cfg = next;
      }
      std::fprintf(stderr, "rsd: configuration reloaded\n");
    } catch (const rsd::formats::ConfigError& e) {
      std::fprintf(stderr, "rsd: reload refused, keeping the running configuration: %s\n", e.what());
    }
    cfg.record_append = true;
  }
}
