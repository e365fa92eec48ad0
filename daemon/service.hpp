// The rsd service: wires the configured camera source, velocity input, rectifier and LCM
// publisher into a pipeline, reports health once a second (LCM, systemd STATUS, a status
// line), reconnects a lost camera with backoff, and stops cleanly on request.
#pragma once

#include <atomic>
#include <cstdint>

#include "daemon/config.hpp"

namespace rsd::daemon {

struct RunLimits {
  uint64_t max_frames = 0;  // 0: run until stopped
  double max_seconds = 0;   // 0: run until stopped
  bool status_line = true;
};

// Flags the signal handlers set; the service polls them (every 50 ms: SIGTERM stops it
// well within 500 ms).
struct StopFlags {
  std::atomic<bool> stop{false};
  std::atomic<bool> reload{false};
};

// Runs until asked to stop or to reload (flags.reload stays set for the caller to see).
// Returns the process exit status. Throws on configuration errors found while wiring.
int run_service(const Config& cfg, const std::string& config_file, StopFlags& flags, const RunLimits& limits);

}  // namespace rsd::daemon
