// The lcm transport as a hostile hub peer drives it (issue 38): after tcpq's handshake the hub
// sends the input (after its first byte) as the rest of the stream, then closes the connection
// or holds it open (the first byte's low bit). handle_lcm() must come back every time, with
// messages, nothing or a lost connection, never blocking (libFuzzer's timeout) nor allocating
// what a peer claims (its malloc limit); what it delivers goes through the decoders the lcm
// source and the velocity input use. The hub is a plain socket on 127.0.0.1, one per process.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <rsd/velocity_t.hpp>

#include <chrono>
#include <cstdlib>
#include <future>
#include <thread>
#include <vector>

#include "drivers/lcm_receive.hpp"
#include "formats/image_t_codec.hpp"
#include "tests/fuzz/fuzz_input.hpp"

namespace {

// The hub's listening socket, made on the first input.
int listener(int& port) {
  static int fd = -1, bound_port = 0;
  if (fd < 0) {
    fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t n = sizeof a;
    if (fd < 0 || bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || listen(fd, 4) != 0 ||
        getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n) != 0)
      std::abort();  // the machine, not the input: no loopback socket
    bound_port = ntohs(a.sin_port);
  }
  port = bound_port;
  return fd;
}

void put32(std::vector<uint8_t>& b, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<uint8_t>(v >> s));
}

// Closes with a reset, not a FIN: thousands of inputs leave no TIME_WAIT behind.
void close_now(int c) {
  linger l{1, 0};
  (void)setsockopt(c, SOL_SOCKET, SO_LINGER, &l, sizeof l);
  close(c);
}

// The hub: answers tcpq's handshake of every client that connects until `done` is ready (the
// provider reconnects after a lost connection to unsubscribe), sends `stream` to the first and
// then, not holding it open, ends that stream. Reading on until then keeps the client's own
// writes (its subscription) from resetting a connection before it read what was sent.
void serve(int listen_fd, std::vector<uint8_t> stream, bool hold_open, std::shared_future<void> done) {
  std::vector<int> clients;
  while (done.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
    pollfd p{listen_fd, POLLIN, 0};
    if (poll(&p, 1, 2) <= 0) continue;
    const int c = accept4(listen_fd, nullptr, nullptr, SOCK_CLOEXEC);
    if (c < 0) continue;
    clients.push_back(c);
    uint8_t hello[8];
    if (recv(c, hello, sizeof hello, MSG_WAITALL) != 8) continue;
    std::vector<uint8_t> out;
    put32(out, 0x287617fa);  // the server's magic
    put32(out, 0x0100);      // protocol version
    if (clients.size() == 1) out.insert(out.end(), stream.begin(), stream.end());
    (void)send(c, out.data(), out.size(), MSG_NOSIGNAL);
    if (clients.size() == 1 && !hold_open) (void)shutdown(c, SHUT_WR);
  }
  for (const int c : clients) close_now(c);
}

void on_message(const lcm_recv_buf_t* rbuf, const char*, void*) {
  const auto* data = static_cast<const uint8_t*>(rbuf->data);
  std::string why;
  bot_core::image_t img;
  rsd::formats::RecordedFrame frame;
  (void)rsd::formats::decode_frame(data, rbuf->data_size, img, frame, why);
  rsd::velocity_t v;
  (void)rsd::formats::decode_checked(data, rbuf->data_size, v, why);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  int port = 0;
  const int listen_fd = listener(port);
  std::promise<void> finished;
  std::thread hub(serve, listen_fd, std::vector<uint8_t>(data + 1, data + size), (data[0] & 1) != 0,
                  finished.get_future().share());
  lcm_t* lcm = lcm_create(("tcpq://127.0.0.1:" + std::to_string(port)).c_str());
  if (lcm) {
    lcm_subscription_t* sub = lcm_subscribe(lcm, ".*", on_message, nullptr);
    // Short waits: a message that is there is handled at once, one cut short ends in 5 ms.
    for (int i = 0, st = 1; i < 64 && st > 0; ++i) st = rsd::drivers::handle_lcm(lcm, i == 0 ? 50 : 5, 5);
    lcm_unsubscribe(lcm, sub);  // as the lcm source does (tcpq frees a channel's name only so)
    lcm_destroy(lcm);
  }
  finished.set_value();
  hub.join();
  return 0;
}
