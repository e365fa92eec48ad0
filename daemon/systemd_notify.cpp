#include "daemon/systemd_notify.hpp"

#include <systemd/sd-daemon.h>

#include <string>

namespace rsd::daemon {

SystemdNotify::SystemdNotify() {
  uint64_t usec = 0;
  if (sd_watchdog_enabled(0, &usec) > 0) watchdog_us_ = usec;
}

void SystemdNotify::ready() { sd_notify(0, "READY=1"); }

void SystemdNotify::reloading() {
  const auto us = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch());
  sd_notify(0, ("RELOADING=1\nMONOTONIC_USEC=" + std::to_string(us.count())).c_str());
}

void SystemdNotify::status(const std::string& text) { sd_notify(0, ("STATUS=" + text).c_str()); }

void SystemdNotify::stopping() { sd_notify(0, "STOPPING=1"); }

void SystemdNotify::watchdog() {
  if (watchdog_us_ == 0) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_pet_ < std::chrono::microseconds(watchdog_us_ / 2)) return;
  last_pet_ = now;
  sd_notify(0, "WATCHDOG=1");
}

}  // namespace rsd::daemon
