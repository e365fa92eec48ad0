// A tcpq hub for tests, on 127.0.0.1: a plain socket speaking LCM's tcpq handshake (or, for the
// faults a hub can have, refusing to). Behaviours:
//   Answering: answers every client's hello (LCM reconnects to unsubscribe from a lost
//              connection), sends `first_bytes` to the first client that sends something after
//              the answer (LCM's subscription), holds every connection open until destroyed;
//   Silent:    accepts connections and never answers (a hung hub; LCM's handshake would wait);
//   Deaf:      listens and never accepts (the kernel completes the connection; the same wait).
// within_a_minute() runs a call that must come back and ends the binary if it does not.
// port 0: an ephemeral port; another: that one (SO_REUSEADDR, to stand in for a hub that went).
#pragma once

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <future>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace rsd::test {

class TcpqHub {
 public:
  enum class Mode { Answering, Silent, Deaf };

  explicit TcpqHub(Mode mode = Mode::Answering, std::vector<uint8_t> first_bytes = {}, int port = 0)
      : mode_(mode), bytes_(std::move(first_bytes)) {
    listen_fd_ = socket(AF_INET, SOCK_STREAM, 0);
    const int one = 1;
    setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<uint16_t>(port));
    EXPECT_EQ(bind(listen_fd_, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    EXPECT_EQ(listen(listen_fd_, 4), 0);
    socklen_t n = sizeof a;
    getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&a), &n);
    port_ = ntohs(a.sin_port);
    if (mode_ != Mode::Deaf) thread_ = std::thread([this] { serve(); });
  }
  ~TcpqHub() { close_all(); }
  TcpqHub(const TcpqHub&) = delete;
  TcpqHub& operator=(const TcpqHub&) = delete;

  // The hub goes away: its listener and every connection closed.
  void close_all() {
    stop_listening();
    for (const int c : clients_) close(c);
    clients_.clear();
  }
  // Its port freed for another hub; the connections it has stay open until close_all().
  void stop_listening() {
    if (listen_fd_ < 0) return;
    shutdown(listen_fd_, SHUT_RDWR);  // accept() returns
    if (thread_.joinable()) thread_.join();
    close(listen_fd_);
    listen_fd_ = -1;
  }
  int port() const { return port_; }
  std::string url() const { return "tcpq://127.0.0.1:" + std::to_string(port_); }

 private:
  static void put32(std::vector<uint8_t>& b, uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<uint8_t>(v >> s));
  }
  void serve() {
    for (int c; (c = accept(listen_fd_, nullptr, nullptr)) >= 0;) {
      clients_.push_back(c);
      if (mode_ == Mode::Silent) continue;
      uint8_t hello[8];
      if (recv(c, hello, sizeof hello, MSG_WAITALL) != 8) continue;
      std::vector<uint8_t> out;
      put32(out, 0x287617fa);  // the server's magic
      put32(out, 0x0100);      // protocol version
      (void)send(c, out.data(), out.size(), MSG_NOSIGNAL);
      // The bytes under test go to the first client that stays and speaks (LCM subscribes), not
      // to one that only asked whether the hub answers (drivers/lcm_connect) and left.
      uint8_t next;
      if (!sent_ && !bytes_.empty() && recv(c, &next, 1, MSG_PEEK) == 1) {
        (void)send(c, bytes_.data(), bytes_.size(), MSG_NOSIGNAL);
        sent_ = true;
      }
    }
  }
  Mode mode_;
  std::vector<uint8_t> bytes_;
  bool sent_ = false;  // the serving thread's
  int listen_fd_ = -1, port_ = 0;
  std::vector<int> clients_;  // the serving thread's until it is joined
  std::thread thread_;
};

// Runs `f` and returns its value; a run that does not come back within a minute is the defect
// itself (a thread blocked for good): the binary ends, naming it.
inline int within_a_minute(const std::function<int()>& f, const char* what) {
  auto done = std::async(std::launch::async, f);
  if (done.wait_for(std::chrono::seconds(60)) != std::future_status::ready) {
    std::fprintf(stderr, "%s: still blocked after 60 s\n", what);
    std::_Exit(1);
  }
  return done.get();
}

}  // namespace rsd::test
