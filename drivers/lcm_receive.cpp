#include "drivers/lcm_receive.hpp"

#include <sys/socket.h>
#include <sys/time.h>

namespace rsd::drivers {

int handle_lcm(lcm_t* lcm, int timeout_ms) {
  const int fd = lcm_get_fileno(lcm);
  if (fd < 0) return -1;
  // Set every time, not once per instance: a reconnected provider has a new socket (and its
  // descriptor number may be an old one's). Not a socket (memq://, file://): ENOTSOCK, nothing
  // to guard.
  timeval tv{};
  tv.tv_sec = kLcmPartialMessageTimeoutMs / 1000;
  tv.tv_usec = (kLcmPartialMessageTimeoutMs % 1000) * 1000;
  (void)setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  return lcm_handle_timeout(lcm, timeout_ms);
}

}  // namespace rsd::drivers
