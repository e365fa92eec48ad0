// arv-fake-gv-camera-0.8 on 127.0.0.1 for tests, only ever inside a private network
// namespace (tests/drivers/run_in_netns.sh) so that nothing it or Aravis sends leaves loopback.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>

extern char** environ;

namespace rsd::test {

using namespace std::chrono_literals;

// True when this process's network namespace has loopback only: a private one.
inline bool only_loopback() {
  std::ifstream dev("/proc/net/dev");
  std::string line;
  int n = 0;
  bool others = false;
  while (std::getline(dev, line))
    if (++n > 2) {
      std::istringstream in(line.substr(0, line.find(':')));
      std::string name;
      in >> name;
      others |= name != "lo";
    }
  return n > 2 && !others;
}

// Something bound to UDP 127.0.0.1:3956 (or any address), GVCP's port, in this namespace.
inline bool gvcp_port_bound() {
  std::ifstream udp("/proc/net/udp");
  std::string line;
  while (std::getline(udp, line))
    if (line.find(" 0100007F:0F74 ") != std::string::npos || line.find(" 00000000:0F74 ") != std::string::npos)
      return true;
  return false;
}

// arv-fake-gv-camera-0.8 -i 127.0.0.1, up once its GVCP port is bound, killed when done.
class FakeGvCamera {
 public:
  FakeGvCamera() {
    posix_spawn_file_actions_t quiet;
    posix_spawn_file_actions_init(&quiet);
    posix_spawn_file_actions_addopen(&quiet, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&quiet, 2, "/dev/null", O_WRONLY, 0);
    char prog[] = "arv-fake-gv-camera-0.8", i[] = "-i", addr[] = "127.0.0.1";
    char* argv[] = {prog, i, addr, nullptr};
    const int rc = posix_spawnp(&pid_, prog, &quiet, nullptr, argv, environ);
    posix_spawn_file_actions_destroy(&quiet);
    if (rc != 0) throw std::runtime_error(std::string("cannot run arv-fake-gv-camera-0.8 (aravis-tools): ") + std::strerror(rc));
    wait_until_up();
  }
  ~FakeGvCamera() { kill(); }
  FakeGvCamera(const FakeGvCamera&) = delete;
  FakeGvCamera& operator=(const FakeGvCamera&) = delete;

  void kill() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }

 private:
  void wait_until_up() {
    for (int i = 0; i < 100; ++i) {
      if (gvcp_port_bound()) return;
      if (waitpid(pid_, nullptr, WNOHANG) == pid_) {
        pid_ = -1;
        throw std::runtime_error("arv-fake-gv-camera-0.8 -i 127.0.0.1 exited at start");
      }
      std::this_thread::sleep_for(50ms);
    }
    kill();
    throw std::runtime_error("arv-fake-gv-camera-0.8 did not bind 127.0.0.1:3956 within 5 s");
  }
  pid_t pid_ = -1;
};


}  // namespace rsd::test
