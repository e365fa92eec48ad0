// Receiving from LCM without ever blocking for good (issue 38).
//
// lcm_handle_timeout() waits at most its timeout for the first bytes of a message, but LCM's
// tcpq provider then reads the rest with blocking recv() calls: a hub peer that sends part of a
// message, or claims a channel name of 2 GB, would hold the receiving thread there for good, and
// with it the frames or the velocity and the daemon's shutdown. handle_lcm() gives the instance's
// socket a receive timeout first, so that such a read fails instead: the provider drops the
// connection and the caller sees a lost connection. A provider without a descriptor (tcpq after
// it lost its hub) is not handled at all: lcm_handle_timeout would hand -1 to FD_SET, which aborts.
//
// Thread contract: none of its own; call it from the instance's receiving thread.
#pragma once

#include <lcm/lcm.h>

namespace rsd::drivers {

// How long the rest of a message may take once its first bytes came.
inline constexpr int kLcmPartialMessageTimeoutMs = 1000;

// lcm_handle_timeout(lcm, timeout_ms) with the guards above: > 0 a message was handled, 0 none
// came within the timeout, < 0 the connection is lost (or the provider cannot receive).
int handle_lcm(lcm_t* lcm, int timeout_ms);

}  // namespace rsd::drivers
