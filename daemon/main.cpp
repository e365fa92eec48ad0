// rsd: the rolling-shutter camera daemon.
//
//   rsd                          run on the built-in simulated camera (all defaults)
//   rsd --config FILE            run as configured
//   rsd --check-config FILE      validate a configuration and exit
//   rsd --print-default-config   print every key with its default
//   rsd --record FILE            also write raw frames, velocity and outputs to an LCM log
//   rsd --replay LOG [--speed N|fast] [--loop]   play a recorded log through the pipeline
//   rsd --replay DIR [--output-dir OUT] [--output-video FILE]   play an images recording
//   rsd --calibration CAL        apply an rsd-calibration/1 file (intrinsics, row timing, IMU)
#include <CLI/CLI.hpp>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "daemon/log.hpp"
#include "daemon/service.hpp"
#include "rsd/version.hpp"
#include "drivers/recording_replay_source.hpp"
#include "drivers/replay_source.hpp"
#include "formats/recording_v1.hpp"
#include "formats/yaml_map.hpp"

namespace {

rsd::daemon::StopFlags g_flags;

void on_signal(int sig) {
  if (sig == SIGHUP) g_flags.reload = true;
  else g_flags.stop = true;
}

// What the command line says beyond the configuration.
struct CommandLine {
  std::string config_file, calibration_file, record_file, replay, speed;
  bool loop = false, realtime = false;
  rsd::daemon::FrameFilesConfig output;
};

// --replay LOG (an LCM log) or DIR (an images recording), --speed, --loop on top of the
// configuration. A log's own intrinsics are used unless the configuration gives source.camera.
bool apply_replay_options(rsd::daemon::Config& cfg, const CommandLine& cl) {
  using rsd::drivers::RecordingReplayConfig;
  using rsd::drivers::ReplayConfig;
  if (!cl.replay.empty() && std::filesystem::is_directory(cl.replay)) {
    cfg.source.driver = "recording";
    cfg.source.settings_of<RecordingReplayConfig>("recording").dir = cl.replay;
  } else if (!cl.replay.empty()) {
    cfg.source.driver = "replay";
    cfg.source.settings_of<ReplayConfig>("replay").file = cl.replay;
  }
  const bool lcm_log = cfg.source.driver == "replay", recording = cfg.source.driver == "recording";
  if (!cl.speed.empty()) {
    double& speed = recording ? cfg.source.settings_of<RecordingReplayConfig>("recording").speed
                              : cfg.source.settings_of<ReplayConfig>("replay").speed;
    if (!rsd::drivers::parse_speed(cl.speed, speed)) {
      rsd::daemon::log_fatal("--speed: expected a positive factor or fast, not '" + cl.speed + "'");
      return false;
    }
  }
  if (cl.loop) cfg.source.settings_of<ReplayConfig>("replay").loop = true;
  if ((!cl.speed.empty() && !lcm_log && !recording) || (cl.loop && !lcm_log)) {
    rsd::daemon::log_fatal(cl.loop ? "--loop applies to LCM log replays (--replay LOG)"
                                   : "--speed applies to replays (--replay LOG or DIR)");
    return false;
  }
  if ((!cl.output.dir.empty() || !cl.output.video.empty()) && !lcm_log && !recording) {
    rsd::daemon::log_fatal("--output-dir and --output-video apply to replays (--replay DIR or LOG): a live camera never "
                           "waits on a disk");
    return false;
  }
  cfg.output = cl.output;
  return true;
}

// A file's bytes ("" if it cannot be read): whether a SIGHUP changed the configuration.
std::string file_text(const std::string& path) {
  if (path.empty()) return "";
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// rsd --replay DIR without a calibration: the recording's own camera, timing and motion
// extrinsics are the nominal calibration.
void use_recording_nominal(rsd::daemon::Config& cfg) {
  if (cfg.source.driver != "recording" || cfg.source.calibration || cfg.source.camera) return;
  const std::string dir = cfg.source.settings_of<rsd::drivers::RecordingReplayConfig>("recording").dir;
  const rsd::formats::ImagesRecording rec = rsd::formats::read_images_recording(dir);
  rsd::daemon::apply_calibration(cfg, rsd::formats::calibration_of(rec.rec.nominal, dir + "/recording.yaml"));
}

// The configuration the command line asks for (ConfigError, RecordingError on bad files).
bool make_config(const CommandLine& cl, rsd::daemon::Config& out) {
  rsd::daemon::Config cfg = cl.config_file.empty() ? rsd::daemon::Config() : rsd::daemon::load_config(cl.config_file);
  if (!cl.calibration_file.empty()) rsd::daemon::use_calibration_file(cfg, cl.calibration_file);
  if (!apply_replay_options(cfg, cl)) return false;
  use_recording_nominal(cfg);
  cfg.record_file = cl.record_file;
  if (cl.realtime) cfg.pipeline.realtime.enabled = true;
  out = std::move(cfg);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rsd: rolling-shutter camera daemon. Captures frames, stamps every row with its capture time,\n"
               "rectifies the rolling-shutter distortion with the current velocity, and publishes images,\n"
               "frame info and health over LCM. Without --config it runs the built-in simulated camera."};
  CommandLine cl;
  bool check = false, print_default = false, quiet = false, progress = false;
  rsd::daemon::RunLimits limits;
  app.add_option("--config,-c", cl.config_file, "YAML configuration (see --print-default-config)")->check(CLI::ExistingFile);
  app.add_option("--calibration", cl.calibration_file,
                 "an rsd-calibration/1 file (docs/formats/calibration-v1.md) over the configuration: intrinsics, line delay,\n"
                 "readout, and the IMU's rotation, time offset, gyro bias and scale")
      ->check(CLI::ExistingFile);
  app.add_flag("--check-config", check, "validate the configuration and exit (status 0 if valid)");
  app.add_flag("--print-default-config", print_default, "print the default configuration and exit");
  app.add_option("--frames", limits.max_frames, "stop after publishing this many frames (0: run until stopped)");
  app.add_option("--duration", limits.max_seconds, "stop after this many seconds (0: run until stopped)");
  app.add_flag("--until-calibrated", limits.until_online_converged,
               "stop a second after the online calibration converged (calibration.online observe or apply; its "
               "state_file keeps the estimate): a calibration session that ends on the event, not on the clock");
  app.add_flag("--realtime", cl.realtime,
               "the capture thread at SCHED_FIFO (realtime.capture_priority) and memory locked after start-up\n"
               "(realtime.lock_memory), when permitted; a warning and normal scheduling when not. The service unit\n"
               "runs rsd with it and grants exactly that (CAP_SYS_NICE, CAP_IPC_LOCK)");
  app.add_flag("--quiet,-q", quiet, "no live status line, progress bar or closing summary on stderr (the log goes on)");
  std::string log_level;
  app.add_option("--log-level", log_level,
                 "trace, debug, info (default), warning, error, critical or off; over the configuration's log.level.\n"
                 "Under systemd each line carries its journald priority (journalctl -p warning -u rsd)")
      ->check([](const std::string& v) { return rsd::daemon::parse_log_level(v) ? "" : "expected trace, debug, info, warning, error, critical or off"; });
  app.add_option("--record", cl.record_file, "record raw frames (with per-row timing), velocity and outputs to this LCM log");
  app.add_option("--replay", cl.replay,
                 "replay instead of the configured camera: an LCM log (source.driver: replay), or an images recording\n"
                 "directory (rsd-recording/1 with images.csv or a video, and its gyro or trajectory; source.driver:\n"
                 "recording), whose recording.yaml is the nominal calibration unless --calibration is given")
      ->check(CLI::ExistingPath);
  app.add_option("--speed", cl.speed, "replay speed: 1 real time (default), N times, or fast (no waiting, no drops)");
  app.add_flag("--loop", cl.loop, "replay of an LCM log: start again at the end of the log");
  app.add_option("--output-dir", cl.output.dir,
                 "replays: also write every rectified frame as OUT/<frame>.png (frame number zero-padded to 6 digits)");
  app.add_option("--output-video", cl.output.video, "replays: also write the rectified frames as a video (.avi, .mp4, .mov, .mkv)");
  app.add_flag("--progress", progress, "replay: show the progress bar even when stderr is not a terminal");
  app.set_version_flag("--version", std::string("rsd ") + rsd::kVersion);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; a bad argument 2, as in every rsd program.
    return app.exit(e) == 0 ? 0 : 2;
  }
  rsd::daemon::init_log(log_level.empty() ? spdlog::level::info : *rsd::daemon::parse_log_level(log_level));
  limits.status_line = !quiet;
  limits.progress = !quiet && (progress || isatty(STDERR_FILENO));
  if (print_default) {
    std::fputs(rsd::daemon::default_config_yaml().c_str(), stdout);
    return 0;
  }
  rsd::daemon::Config cfg;
  try {
    if (!make_config(cl, cfg)) return 2;
  } catch (const rsd::formats::ConfigError& e) {
    rsd::daemon::log_fatal(std::string("configuration error: ") + e.what());
    return 2;
  } catch (const rsd::formats::RecordingError& e) {
    rsd::daemon::log_fatal(std::string("--replay: ") + e.what());
    return 2;
  } catch (const std::exception& e) {  // anything a parser let through is still the file's fault
    rsd::daemon::log_fatal(std::string("configuration error: ") + (cl.config_file.empty() ? "" : cl.config_file + ": ") + e.what());
    return 2;
  }
  if (log_level.empty()) spdlog::set_level(*rsd::daemon::parse_log_level(cfg.log_level));
  if (limits.until_online_converged && cfg.online.mode == rsd::daemon::OnlineMode::Off) {
    rsd::daemon::log_fatal("--until-calibrated: calibration.online.mode is off, so nothing would converge (set it to observe or apply)");
    return 2;
  }
  if (check) {
    std::printf("rsd: %s is valid\n", cl.config_file.empty() ? "the default configuration" : cl.config_file.c_str());
    return 0;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGHUP, on_signal);
  // A recording that reaches the file size limit (RLIMIT_FSIZE) must fail its writes (counted,
  // logged, the run goes on), not kill the daemon.
  std::signal(SIGXFSZ, SIG_IGN);
  // SIGHUP reads both files again: the calibration alone changed (or nothing did) -> applied
  // between two frames; the configuration file changed -> the pipeline restarts with it; a bad
  // file -> refused, the running configuration kept.
  std::string config_text = file_text(cl.config_file);
  rsd::daemon::Config restart_cfg;
  const rsd::daemon::Reloader reloader = [&]() -> rsd::daemon::Reload {
    rsd::daemon::Reload r;
    try {
      if (!make_config(cl, r.cfg)) return r.why = "the command line does not apply to the new configuration", r;
    } catch (const std::exception& e) {
      r.why = e.what();
      return r;
    }
    const std::string text = file_text(cl.config_file);
    r.kind = text == config_text ? rsd::daemon::Reload::Calibration : rsd::daemon::Reload::Restart;
    if (r.kind == rsd::daemon::Reload::Restart) config_text = text, restart_cfg = r.cfg;
    return r;
  };
  // A reloaded configuration that passed every check and still fails to start (a camera that
  // delivers another size than its calibration's, say) must not end a daemon that was running:
  // it goes back to the configuration that ran, once.
  rsd::daemon::Config ran = cfg;
  bool trying_reloaded = false;
  for (;;) {
    rsd::daemon::RunSummary summary;
    try {
      rsd::daemon::run_service(cfg, g_flags, limits, {}, &summary, reloader);
    } catch (const std::exception& e) {
      if (!trying_reloaded || g_flags.stop.load()) {
        rsd::daemon::log_fatal(e.what());
        return 1;
      }
      spdlog::error("reload refused: the new configuration failed to start ({}); restarting with the one that ran", e.what());
      cfg = ran, trying_reloaded = false;
      cfg.record_append = true;
      continue;
    }
    ran = cfg, trying_reloaded = false;
    // SIGTERM just after a restart, before its first frame, is no failure of the whole run.
    limits.frames_before = limits.frames_before || summary.frames_out > 0;
    if (!g_flags.reload.exchange(false) || g_flags.stop.load()) return 0;
    spdlog::info("configuration reloaded: restarting the pipeline");
    cfg = restart_cfg, trying_reloaded = true;
    cfg.record_append = true;  // the recording continues
    if (log_level.empty()) spdlog::set_level(*rsd::daemon::parse_log_level(cfg.log_level));
  }
}
