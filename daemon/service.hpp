// The rsd service: wires the configured camera source, velocity input, rectifier and LCM
// publisher into a pipeline, reports health once a second (LCM, systemd STATUS, a status
// line), reconnects a lost camera with backoff, and stops cleanly on request.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "daemon/config.hpp"

namespace rsd::daemon {

struct RunLimits {
  uint64_t max_frames = 0;  // 0: run until stopped
  double max_seconds = 0;   // 0: run until stopped
  bool status_line = true;
  bool progress = false;  // a progress bar for replays (instead of the status line)
};

// What a run did, for tests and the exit message.
struct RunSummary {
  uint64_t frames_out = 0;
  int reconnects = 0;
  // Replays: frames read from the log, events skipped (and why), seconds taken.
  uint64_t replayed = 0, skipped = 0;
  std::string skips;
  double seconds = 0;
};

// Makes the camera source; the default builds the configured driver. Tests substitute one.
using SourceFactory = std::function<std::unique_ptr<drivers::CameraSource>(const Config&)>;

// Flags the signal handlers set; the service polls them (every 20 ms while streaming, every
// 50 ms while waiting for a camera: SIGTERM stops it well within 500 ms).
struct StopFlags {
  std::atomic<bool> stop{false};
  std::atomic<bool> reload{false};
};

// Runs until asked to stop or to reload (flags.reload stays set for the caller to see).
// Throws on configuration errors found while wiring; a camera that cannot be opened is
// retried with backoff until a stop, never an error.
void run_service(const Config& cfg, StopFlags& flags, const RunLimits& limits, const SourceFactory& factory = {},
                 RunSummary* summary = nullptr);

}  // namespace rsd::daemon
