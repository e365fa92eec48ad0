// Real-time capture: the pipeline's threads at SCHED_FIFO and on chosen CPUs, the process's
// memory locked once start-up has allocated it. Each step happens only when permitted
// (CAP_SYS_NICE or RLIMIT_RTPRIO for the priority, CAP_IPC_LOCK or RLIMIT_MEMLOCK for the lock,
// which the service unit grants); otherwise rsd says so once on stderr and carries on at
// normal priority with pageable memory.
#pragma once

#include <string>

namespace rsd::daemon {

struct RealtimeConfig {
  bool enabled = false;        // rsd --realtime (the service unit) or realtime.enabled
  int capture_priority = 50;   // SCHED_FIFO priority of the capture thread (1..99)
  bool lock_memory = true;     // mlockall(MCL_CURRENT | MCL_FUTURE) after start-up
  // CPUs (-1: any) for each pipeline thread, applied whether or not `enabled`.
  int capture_cpu = -1, rectify_cpu = -1, publish_cpu = -1;
};

// On the calling thread: SCHED_FIFO at `priority` (0: leave the policy alone) and pinned to
// `cpu` (-1: leave it alone). Returns "" or why a step was not possible (the thread keeps
// running as it was). `thread` names it in the message.
std::string make_thread_realtime(const std::string& thread, int priority, int cpu);

// mlockall(MCL_CURRENT | MCL_FUTURE); "" or why not.
std::string lock_memory();

}  // namespace rsd::daemon
