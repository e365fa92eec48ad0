// Receiving from LCM without ever blocking for good or allocating what a peer claims (issue 38).
//
// lcm_handle_timeout() waits at most its timeout for the first bytes of a message, but LCM's
// tcpq provider then reads the rest with blocking recv() calls: a hub peer that sends part of a
// message, or claims a channel name of 2 GB, would hold the receiving thread there for good, and
// with it the frames or the velocity and the daemon's shutdown. And the provider sizes its
// buffers by the lengths the peer claims: a payload of 4 GB - 1 makes its realloc fail, after
// which it reads on from the middle of that message as if a new one began.
//
// handle_lcm() therefore (1) gives the instance's socket a receive timeout, so that the rest of
// a message that does not come ends the read: the provider drops the connection and the caller
// sees a lost connection; (2) looks at the next message's header before the provider reads it
// (MSG_PEEK, never consuming a byte) and drops the connection itself, by shutting the socket
// down, when the header claims a channel name or payload longer than any LCM message rsd takes
// (kLcmMaxChannelBytes, kLcmMaxMessageBytes); (3) never hands a provider without a descriptor
// (tcpq after it lost its hub) to lcm_handle_timeout, whose FD_SET would abort on -1.
//
// Thread contract: call it from the instance's receiving thread (the only one that reads its
// socket). LCM's tcpq provider is not thread-safe: a publish that fails on a lost hub closes the
// socket and marks it -1, and a receive that enters the provider then reconnects inside
// lcm_handle, waiting for good on a hub that accepts and never answers, while the publishers
// write into that connection until they block too (LcmHubFaults failed so once, in a
// clean-clone run on a loaded machine). So when other threads publish through the instance, pass
// the lock they hold around lcm_publish (`publishing`): handle_lcm holds it from the descriptor
// check through the provider's read (not while it waits for the first bytes), so the socket it
// checked is the one the provider reads.
#pragma once

#include <lcm/lcm.h>

#include <cstdint>
#include <mutex>

namespace rsd::drivers {

// How long the rest of a message may take once its first bytes came.
inline constexpr int kLcmPartialMessageTimeoutMs = 1000;
// LCM's own limit on a channel name (lcm_publish refuses longer ones), with room to spare.
inline constexpr uint32_t kLcmMaxChannelBytes = 255;
// The largest message rsd takes: a frame of the largest side the boundary admits (8000 x 8000)
// in RGB8 is 192 MB; 256 MiB leaves room for row padding and the message's other fields.
inline constexpr uint32_t kLcmMaxMessageBytes = 256u << 20;

// lcm_handle_timeout(lcm, timeout_ms) with the guards above: > 0 a message was handled, 0 none
// came within the timeout, < 0 the connection is lost (or the provider cannot receive).
// partial_timeout_ms bounds the rest of a message (tests and the fuzz target shorten it), and
// so how long `publishing` is held.
int handle_lcm(lcm_t* lcm, int timeout_ms, int partial_timeout_ms = kLcmPartialMessageTimeoutMs,
               std::mutex* publishing = nullptr);

// `m` held (not held when there is none): the publishers' lock where an instance has one.
inline std::unique_lock<std::mutex> lock_if(std::mutex* m) {
  return m ? std::unique_lock<std::mutex>(*m) : std::unique_lock<std::mutex>();
}

}  // namespace rsd::drivers
