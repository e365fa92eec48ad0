// A hub peer that sends part of a message (issue 38, defect 1): the header and half a channel
// name, or a channel length of 0x7FFFFFFF, and then nothing. LCM's tcpq provider read the rest
// with blocking recv() calls, so the receiving thread (the lcm source's capture, the velocity
// input) stopped for good and SIGTERM could not end the daemon. handle_lcm() must come back
// with a lost connection instead, and the lcm source fail its open with a CameraError (the
// service then retries with backoff). The hub here is a plain socket speaking tcpq's handshake.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <future>
#include <iterator>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "drivers/lcm_receive.hpp"
#include "drivers/lcm_source.hpp"
#include "tests/support/tcpq_hub.hpp"

namespace rsd::drivers {
namespace {

// A hub that answers every client and sends the bytes under test to the first.
struct PartialHub : test::TcpqHub {
  explicit PartialHub(std::vector<uint8_t> bytes) : TcpqHub(Mode::Answering, std::move(bytes)) {}
};

// A publish message's header: type 1, a channel of `length` bytes, of which `sent` follow.
std::vector<uint8_t> partial_message(uint32_t length, const std::string& sent) {
  std::vector<uint8_t> b = {0, 0, 0, 1};
  for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<uint8_t>(length >> s));
  b.insert(b.end(), sent.begin(), sent.end());
  return b;
}

void expect_lost_not_blocked(const std::vector<uint8_t>& bytes) {
  PartialHub hub(bytes);
  lcm_t* lcm = lcm_create(hub.url().c_str());
  ASSERT_NE(lcm, nullptr);
  lcm_subscription_t* sub = lcm_subscribe(lcm, "RSD_RAW", [](const lcm_recv_buf_t*, const char*, void*) {}, nullptr);
  const int r = test::within_a_minute(
      [&] {
        int st = 0;
        while ((st = handle_lcm(lcm, 100)) == 0) {}  // until the partial message is read
        return st;
      },
      "handle_lcm");
  EXPECT_LT(r, 0) << "a partial message must end in a lost connection";
  EXPECT_LT(handle_lcm(lcm, 10), 0) << "and the lost connection is not handled again";
  lcm_unsubscribe(lcm, sub);
  lcm_destroy(lcm);
}

TEST(LcmReceive, HalfAChannelNameEndsInALostConnection) { expect_lost_not_blocked(partial_message(7, "RSD")); }

// LCM sizes its buffers by what the peer claims: a channel of 0x7FFFFFFF + 1 bytes asked realloc
// for 2^64 - 2^31 bytes (AddressSanitizer aborted on it), a payload of 4 GB - 1 failed its
// realloc, after which the provider read on from the middle of that message as if a new one
// began. handle_lcm() looks at the header first and drops the connection before either.
TEST(LcmReceive, AChannelOf2GBEndsInALostConnection) { expect_lost_not_blocked(partial_message(0x7FFFFFFF, "RSD_RAW")); }

TEST(LcmReceive, AChannelOf256MBEndsInALostConnection) { expect_lost_not_blocked(partial_message(0x10000000, "RSD_RAW")); }

TEST(LcmReceive, APayloadOf4GBEndsInALostConnection) {
  std::vector<uint8_t> b = partial_message(7, "RSD_RAW");
  for (const uint8_t v : {0xFF, 0xFF, 0xFF, 0xFF, 1, 2, 3}) b.push_back(v);
  expect_lost_not_blocked(b);
}

TEST(LcmReceive, APayloadJustOverTheLimitEndsInALostConnection) {
  std::vector<uint8_t> b = partial_message(7, "RSD_RAW");
  for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<uint8_t>((kLcmMaxMessageBytes + 1) >> s));
  expect_lost_not_blocked(b);
}

// And the guard refuses nothing rsd takes: whole messages, the largest channel name, a payload
// of several MB, one after another, arrive whole and in order.
TEST(LcmReceive, WholeMessagesUpToTheLimitsArriveIntact) {
  const std::string longest(kLcmMaxChannelBytes, 'C');
  std::vector<std::pair<std::string, std::vector<uint8_t>>> sent = {
      {"RSD_VELOCITY", std::vector<uint8_t>(40, 7)}, {longest, std::vector<uint8_t>(3, 1)}, {"RSD_RAW", std::vector<uint8_t>(6 << 20)}};
  for (size_t i = 0; i < sent[2].second.size(); ++i) sent[2].second[i] = static_cast<uint8_t>(i * 2654435761u >> 24);
  std::vector<uint8_t> stream;
  for (const auto& [channel, payload] : sent) {
    std::vector<uint8_t> m = partial_message(static_cast<uint32_t>(channel.size()), channel);
    for (int s = 24; s >= 0; s -= 8) m.push_back(static_cast<uint8_t>(payload.size() >> s));
    m.insert(m.end(), payload.begin(), payload.end());
    stream.insert(stream.end(), m.begin(), m.end());
  }
  PartialHub hub(stream);
  lcm_t* lcm = lcm_create(hub.url().c_str());
  ASSERT_NE(lcm, nullptr);
  std::vector<std::pair<std::string, std::vector<uint8_t>>> got;
  lcm_subscription_t* sub = lcm_subscribe(
      lcm, ".*",
      [](const lcm_recv_buf_t* r, const char* channel, void* user) {
        const auto* d = static_cast<const uint8_t*>(r->data);
        static_cast<decltype(got)*>(user)->emplace_back(channel, std::vector<uint8_t>(d, d + r->data_size));
      },
      &got);
  test::within_a_minute(
      [&] {
        while (got.size() < sent.size() && handle_lcm(lcm, 100) >= 0) {}
        return 0;
      },
      "handle_lcm");
  EXPECT_EQ(got, sent);
  lcm_unsubscribe(lcm, sub);
  lcm_destroy(lcm);
}

TEST(LcmReceive, TheLcmSourceFailsItsOpenInsteadOfHanging) {
  PartialHub hub(partial_message(7, "RSD"));
  LcmSourceConfig cfg;
  cfg.url = hub.url();
  cfg.open_timeout_s = 30;  // longer than the guard: the loss must end the open, not this
  LcmSource source(cfg);
  const int threw = test::within_a_minute(
      [&] {
        try {
          source.open();
        } catch (const CameraError&) {
          return 1;
        }
        return 0;
      },
      "LcmSource::open");
  EXPECT_EQ(threw, 1);
}

// Whether thread `tid` of this process is asleep (blocked in a call), from /proc.
bool asleep(pid_t tid) {
  std::ifstream stat("/proc/self/task/" + std::to_string(tid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  const size_t close = text.rfind(')');  // the state follows the command's name
  return close != std::string::npos && close + 2 < text.size() && text[close + 2] == 'S';
}

// LCM's tcpq provider is not thread-safe: a publish that loses the hub closes the socket and
// marks it -1, and a receive that then enters the provider reconnects inside lcm_handle, to
// whatever hub took the port; one that never answers held the velocity input's thread for good,
// and the publishers, writing into that connection, until they blocked too (LcmHubFaults, once
// in a clean-clone run). With the publishers' lock, the receive that was waiting for the lost
// connection's last bytes sees the publish's -1 and never enters the provider. In order: the
// receive waits in its poll; a publish fails (the socket shut for writing) under the lock; a
// silent hub takes the port; then the old hub's connection closes, waking the receive.
TEST(LcmReceive, AReceiveNeverReconnectsAConnectionAPublishLostMeanwhile) {
  test::TcpqHub hub;
  const int port = hub.port();
  lcm_t* lcm = lcm_create(hub.url().c_str());
  ASSERT_NE(lcm, nullptr);
  const int fd = lcm_get_fileno(lcm);
  ASSERT_GE(fd, 0);
  std::mutex publishing;
  std::atomic<pid_t> tid{0};
  std::promise<int> received;
  std::thread receiver([&] {
    tid = static_cast<pid_t>(syscall(SYS_gettid));
    received.set_value(handle_lcm(lcm, 600000, kLcmPartialMessageTimeoutMs, &publishing));
  });
  while (tid == 0 || !asleep(tid)) std::this_thread::yield();  // in its poll: nothing to read yet
  std::unique_ptr<test::TcpqHub> silent;
  {
    std::lock_guard lock(publishing);
    shutdown(fd, SHUT_WR);
    const uint8_t byte = 0;
    EXPECT_NE(lcm_publish(lcm, "X", &byte, 1), 0);
    EXPECT_LT(lcm_get_fileno(lcm), 0);  // the provider closed it
    hub.stop_listening();
    silent = std::make_unique<test::TcpqHub>(test::TcpqHub::Mode::Silent, std::vector<uint8_t>{}, port);
    hub.close_all();  // the receive wakes (the socket it polls is the closed one's)
  }
  auto got = received.get_future();
  EXPECT_EQ(test::within_a_minute([&] { return got.get(); }, "the receive after the publish lost the hub"), -1);
  receiver.join();
  EXPECT_LT(lcm_get_fileno(lcm), 0);  // not connected again
  lcm_destroy(lcm);
}

}  // namespace
}  // namespace rsd::drivers
