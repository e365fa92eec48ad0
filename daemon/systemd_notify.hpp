// Talks to systemd's service manager (Type=notify): READY, RELOADING, STATUS, WATCHDOG and STOPPING
// through libsystemd's sd_notify. Outside systemd (no NOTIFY_SOCKET) every call is a no-op.
#pragma once

#include <chrono>
#include <string>

namespace rsd::daemon {

class SystemdNotify {
 public:
  SystemdNotify();
  void ready();
  // A reload has begun (SIGHUP); ready() says it has ended. Carries MONOTONIC_USEC, which
  // Type=notify-reload services must send with RELOADING=1.
  void reloading();
  void status(const std::string& text);
  void stopping();
  // Pets the watchdog if systemd asked for one (WatchdogSec), at most every half period.
  void watchdog();
  bool watchdog_enabled() const { return watchdog_us_ > 0; }

 private:
  uint64_t watchdog_us_ = 0;
  std::chrono::steady_clock::time_point last_pet_{};
};

}  // namespace rsd::daemon
