#include "daemon/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>

namespace rsd::daemon {

std::string make_thread_realtime(const std::string& thread, int priority, int cpu) {
  std::string why;
  if (priority > 0) {
    sched_param p{};
    p.sched_priority = priority;
    if (const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p); e != 0)
      why = "the " + thread + " thread stays at normal priority: SCHED_FIFO " + std::to_string(priority) + " " +
            (e == EPERM ? "is not permitted (it needs CAP_SYS_NICE or RLIMIT_RTPRIO; the service unit grants them)"
                        : std::string("failed: ") + std::strerror(e));
  }
  if (cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    if (const int e = pthread_setaffinity_np(pthread_self(), sizeof set, &set); e != 0)
      why += (why.empty() ? "" : "; ") + ("the " + thread + " thread runs on any CPU: CPU " + std::to_string(cpu) + " " +
                                          std::strerror(e));
  }
  return why;
}

std::string lock_memory() {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) return "";
  const int e = errno;
  return std::string("memory stays pageable: mlockall ") +
         (e == EPERM || e == ENOMEM ? "is not permitted (it needs CAP_IPC_LOCK or a large RLIMIT_MEMLOCK; the service unit "
                                      "grants them)"
                                    : std::string("failed: ") + std::strerror(e));
}

}  // namespace rsd::daemon
