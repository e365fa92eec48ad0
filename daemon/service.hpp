// The rsd service: wires the configured camera source, velocity input, rectifier and LCM
// publisher into a pipeline, reports health once a second (LCM, systemd STATUS, a status
// line), reconnects a lost camera with backoff, and stops cleanly on request.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "daemon/config.hpp"

namespace rsd::daemon {

struct RunLimits {
  uint64_t max_frames = 0;  // 0: run until stopped
  double max_seconds = 0;   // 0: run until stopped
  bool status_line = true;
  bool progress = false;  // a progress bar for replays (instead of the status line)
  // Frames arrived in an earlier run of this process (before a restart for a changed
  // configuration): a stop before this run's first frame is then no failure.
  bool frames_before = false;
  // Stop one health report (a second) after the online calibration first reported a converged
  // estimate (in apply mode: one the rectifier uses): a calibration session ends on the event,
  // whatever the machine's speed; `max_seconds` still bounds it.
  bool until_online_converged = false;
};

// What a run did, for tests and the exit message.
struct RunSummary {
  uint64_t frames_out = 0;
  int reconnects = 0;
  // Replays: frames read from the log, events skipped (and why), seconds taken.
  uint64_t replayed = 0, skipped = 0;
  std::string skips;
  double seconds = 0;
  int calibrations_applied = 0;  // SIGHUP calibrations taken up between two frames
  // calibration.online: the last estimate, and the one the rectifier used at the end (apply).
  std::optional<dsp::OnlineEstimate> online;
  std::optional<dsp::OnlineCalibration> online_applied;
};

// Makes the camera source; the default builds the configured driver. Tests substitute one.
using SourceFactory = std::function<std::unique_ptr<drivers::CameraSource>(const Config&)>;

// Flags the signal handlers set; the service polls them (every 20 ms while streaming, every
// 50 ms while waiting for a camera: SIGTERM stops it well within 500 ms).
struct StopFlags {
  std::atomic<bool> stop{false};
  std::atomic<bool> reload{false};
};

// What a SIGHUP asks for, once the caller has read its files again.
struct Reload {
  enum Kind {
    Refused,      // a file is bad: keep running as before (`why` says what is wrong)
    Calibration,  // only the calibration changed: apply `cfg`'s between two frames
    Restart,      // the configuration changed: return, for the caller to run `cfg` afresh
  } kind = Refused;
  Config cfg;
  std::string why;
};
using Reloader = std::function<Reload()>;

// Runs until asked to stop or to reload. Without a reloader a SIGHUP returns at once (flags.reload
// stays set for the caller to see); with one, the service asks it what to do: a new calibration
// is applied from the next frame without stopping the pipeline (no frame dropped), a bad one is
// refused and the running one kept, and a changed configuration returns with flags.reload set.
// Throws on configuration errors found while wiring; a camera that cannot be opened is
// retried with backoff until a stop, never an error.
void run_service(const Config& cfg, StopFlags& flags, const RunLimits& limits, const SourceFactory& factory = {},
                 RunSummary* summary = nullptr, const Reloader& reloader = {});

}  // namespace rsd::daemon
