#include "drivers/lcm_receive.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace rsd::drivers {
namespace {

// Big-endian 32-bit word at p (tcpq's framing).
uint32_t word_at(const uint8_t* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return ntohl(v);
}

// Whether the next tcpq message, as far as it has arrived, claims more than rsd takes. A header
// not yet whole is judged on the next call (the provider reads it under the receive timeout).
// Not a stream socket (memq://, file://): nothing to look at.
bool claims_too_much(int fd) {
  // type, channel length, channel (at most kLcmMaxChannelBytes), payload length
  uint8_t head[4 + 4 + kLcmMaxChannelBytes + 4];
  const ssize_t got = recv(fd, head, sizeof head, MSG_PEEK | MSG_DONTWAIT);
  if (got < 8) return false;
  const uint32_t channel = word_at(head + 4);
  if (channel > kLcmMaxChannelBytes) return true;
  if (static_cast<size_t>(got) < 12 + channel) return false;
  return word_at(head + 8 + channel) > kLcmMaxMessageBytes;
}

// Ends the connection under the provider without letting it read another byte: the descriptor
// is replaced (atomically, dup3) by a socket whose peer is gone, so the provider's next recv()
// returns 0 and it drops the connection as for a hub that closed; the hub's connection closes
// with the descriptor it had. (shutdown() would not do: the bytes already queued stay readable.)
void drop_connection(int fd) {
  int pair[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, pair) != 0) {
    (void)shutdown(fd, SHUT_RDWR);  // out of descriptors: the receive timeout still bounds it
    return;
  }
  close(pair[1]);
  (void)dup3(pair[0], fd, O_CLOEXEC);
  close(pair[0]);
}

}  // namespace

int handle_lcm(lcm_t* lcm, int timeout_ms, int partial_timeout_ms, std::mutex* publishing) {
  std::unique_lock<std::mutex> lock = lock_if(publishing);
  const int fd = lcm_get_fileno(lcm);
  if (fd < 0) return -1;
  if (publishing) lock.unlock();  // waiting for the first bytes, publishing goes on
  pollfd p{fd, POLLIN, 0};
  const int ready = poll(&p, 1, timeout_ms);
  if (ready < 0) return errno == EINTR ? 0 : -1;
  if (ready == 0) return 0;
  if (publishing) {
    lock.lock();
    // A publish lost the hub meanwhile (-1), or lost it and connected again: the socket polled
    // is not the provider's (under the same number, lcm_handle_timeout finds nothing: 0).
    const int now = lcm_get_fileno(lcm);
    if (now < 0) return -1;
    if (now != fd) return 0;
  }
  // Set every time, not once per instance: a reconnected provider has a new socket (and its
  // descriptor number may be an old one's). Not a socket: ENOTSOCK, nothing to guard.
  timeval tv{};
  tv.tv_sec = partial_timeout_ms / 1000;
  tv.tv_usec = (partial_timeout_ms % 1000) * 1000;
  (void)setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  if (claims_too_much(fd)) drop_connection(fd);
  return lcm_handle_timeout(lcm, 0);
}

}  // namespace rsd::drivers
