#include "drivers/lcm_connect.hpp"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <thread>

#include <spdlog/spdlog.h>

namespace rsd::drivers {
namespace {

// tcpq's handshake words (LCM's lcm_tcpq.c), big-endian on the wire.
constexpr uint32_t kMagicServer = 0x287617fa, kMagicClient = 0x287617fb, kProtocolVersion = 0x0100;

using Clock = std::chrono::steady_clock;

struct Address {
  sockaddr_in sa{};
  std::string text;
};

// tcpq://HOST[:PORT][?options] as LCM reads it: an empty network is 127.0.0.1:7700.
bool parse_address(const std::string& url, Address& out, std::string& why) {
  std::string net = url.substr(7);
  net = net.substr(0, net.find('?'));
  if (net.empty()) net = "127.0.0.1:7700";
  const size_t colon = net.find(':');
  const std::string host = net.substr(0, colon);
  int port = 7700;
  if (colon != std::string::npos) {
    const std::string p = net.substr(colon + 1);
    char* end = nullptr;
    const long v = std::strtol(p.c_str(), &end, 0);
    if (p.empty() || *end != '\0' || v < 0 || v > 65535) return why = "port '" + p + "' is not 0..65535", false;
    port = static_cast<int>(v);
  }
  out.sa.sin_family = AF_INET;
  out.sa.sin_port = htons(static_cast<uint16_t>(port));
  if (inet_aton(host.c_str(), &out.sa.sin_addr) == 0) {
    addrinfo hints{}, *res = nullptr;
    hints.ai_family = AF_INET;
    hints.ai_socktype = SOCK_STREAM;
    if (getaddrinfo(host.c_str(), nullptr, &hints, &res) != 0 || !res) return why = "host '" + host + "' does not resolve", false;
    out.sa.sin_addr = reinterpret_cast<sockaddr_in*>(res->ai_addr)->sin_addr;
    freeaddrinfo(res);
  }
  out.text = host + ":" + std::to_string(port);
  return true;
}

// Milliseconds left until `deadline` (0 when past).
int left_ms(Clock::time_point deadline) {
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
  return ms > 0 ? static_cast<int>(ms) : 0;
}

// Waits for `events` on fd until the deadline: true if they came.
bool wait_for(int fd, short events, Clock::time_point deadline) {
  for (;;) {
    pollfd p{fd, events, 0};
    const int r = poll(&p, 1, left_ms(deadline));
    if (r > 0) return true;
    if (r == 0 || errno != EINTR) return false;
  }
}

HubProbe ask(int fd, const Address& a, Clock::time_point deadline) {
  const auto said = [&](HubAnswer h, const std::string& what) { return HubProbe{h, "tcpq hub " + a.text + ": " + what}; };
  if (connect(fd, reinterpret_cast<const sockaddr*>(&a.sa), sizeof a.sa) != 0 && errno != EINPROGRESS)
    return said(HubAnswer::Refused, std::string("cannot connect (") + std::strerror(errno) + ")");
  if (!wait_for(fd, POLLOUT, deadline)) return said(HubAnswer::Silent, "the connection was not accepted in time");
  int err = 0;
  socklen_t n = sizeof err;
  getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &n);
  if (err != 0) return said(HubAnswer::Refused, std::string("cannot connect (") + std::strerror(err) + ")");
  const uint32_t hello[2] = {htonl(kMagicClient), htonl(kProtocolVersion)};
  if (send(fd, hello, sizeof hello, MSG_NOSIGNAL) != static_cast<ssize_t>(sizeof hello))
    return said(HubAnswer::WrongAnswer, "the connection closed before the hello");
  uint32_t answer[2];
  size_t got = 0;
  while (got < sizeof answer) {
    if (!wait_for(fd, POLLIN, deadline))
      return said(HubAnswer::Silent, "accepted the connection but did not answer tcpq's hello (" + std::to_string(got) + " of 8 bytes)");
    const ssize_t r = recv(fd, reinterpret_cast<char*>(answer) + got, sizeof answer - got, 0);
    if (r == 0) return said(HubAnswer::WrongAnswer, "closed the connection instead of answering");
    if (r < 0 && errno != EINTR && errno != EAGAIN) return said(HubAnswer::WrongAnswer, std::string("recv: ") + std::strerror(errno));
    if (r > 0) got += static_cast<size_t>(r);
  }
  if (ntohl(answer[0]) != kMagicServer) return said(HubAnswer::WrongAnswer, "answered, but not as a tcpq hub");
  return said(HubAnswer::Answered, "answered");
}

}  // namespace

HubProbe probe_tcpq_hub(const std::string& url, int timeout_ms) {
  if (url.rfind("tcpq://", 0) != 0) return {};
  Address a;
  std::string why;
  if (!parse_address(url, a, why)) return {HubAnswer::BadAddress, "'" + url + "': " + why};
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return {HubAnswer::Silent, std::string("cannot make a socket to ask the hub (") + std::strerror(errno) + ")"};
  const HubProbe p = ask(fd, a, Clock::now() + std::chrono::milliseconds(timeout_ms));
  close(fd);
  return p;
}

lcm_t* create_lcm(const std::string& url, std::string& why, int timeout_ms) {
  why.clear();
  const HubProbe p = probe_tcpq_hub(url, timeout_ms);
  if (p.answer == HubAnswer::Silent || p.answer == HubAnswer::BadAddress) {
    why = p.why;
    return nullptr;
  }
  return lcm_create(url.c_str());
}

bool lost_tcpq_hub(lcm_t* lcm, const std::string& url) {
  return url.rfind("tcpq://", 0) == 0 && lcm_get_fileno(lcm) < 0;
}

bool may_reconnect(lcm_t* lcm, const std::string& url, int timeout_ms) {
  return !lost_tcpq_hub(lcm, url) || probe_tcpq_hub(url, timeout_ms).safe_to_connect();
}

void destroy_lcm_detached(lcm_t* lcm, const std::string& url) {
  spdlog::warn("lcm {}: the hub does not answer; the lost connection's instance is closed in the background", url);
  std::thread([lcm] { lcm_destroy(lcm); }).detach();
}

bool destroy_lcm(lcm_t* lcm, const std::string& url, int timeout_ms) {
  if (!lcm) return true;
  if (may_reconnect(lcm, url, timeout_ms)) {
    lcm_destroy(lcm);
    return true;
  }
  destroy_lcm_detached(lcm, url);
  return false;
}

}  // namespace rsd::drivers
