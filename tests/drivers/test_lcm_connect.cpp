// A tcpq hub that accepts the connection and never answers (issue 38): LCM's tcpq provider waits
// for the hub's answer with a blocking recv() and no timeout, in lcm_create and in every
// implicit reconnect (publish, subscribe, unsubscribe after a loss). drivers/lcm_connect asks
// the hub first. Each outcome of the question against a hub built to give it, and the lcm
// source's open failing with the hub's fault named instead of hanging. (The publisher and the
// velocity input: tests/daemon/test_lcm_hub_faults.cpp.)
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <string>
#include <thread>

#include "drivers/lcm_connect.hpp"
#include "drivers/lcm_source.hpp"
#include "tests/support/tcpq_hub.hpp"

namespace rsd::drivers {
namespace {

using test::TcpqHub;

// A port where nothing listens: bound, then released.
int free_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t n = sizeof a;
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n);
  close(fd);
  return ntohs(a.sin_port);
}

// Asks with a timeout long enough for any answer on a busy machine (an answer is an event); the
// silent hubs' cases pass a short one, since they wait for all of it.
HubProbe probe(const std::string& url, int timeout_ms = 20000) {
  HubProbe p;
  test::within_a_minute([&] { return p = probe_tcpq_hub(url, timeout_ms), 0; }, "probe_tcpq_hub");
  return p;
}

TEST(LcmConnect, AnAnsweringHubAnswers) {
  TcpqHub hub;
  const HubProbe p = probe(hub.url());
  EXPECT_EQ(p.answer, HubAnswer::Answered) << p.why;
  EXPECT_TRUE(p.safe_to_connect());
  std::string why;
  lcm_t* lcm = create_lcm(hub.url(), why, 20000);
  ASSERT_NE(lcm, nullptr) << why;
  EXPECT_GE(lcm_get_fileno(lcm), 0);
  lcm_destroy(lcm);
}

TEST(LcmConnect, SilentAndDeafHubsAreToldApartFromAnswerersAndNotConnectedTo) {
  for (const TcpqHub::Mode m : {TcpqHub::Mode::Silent, TcpqHub::Mode::Deaf}) {
    TcpqHub hub(m);
    const HubProbe p = probe(hub.url(), 300);
    EXPECT_EQ(p.answer, HubAnswer::Silent) << p.why;
    EXPECT_FALSE(p.safe_to_connect());
    EXPECT_NE(p.why.find("127.0.0.1:" + std::to_string(hub.port())), std::string::npos) << p.why;
    EXPECT_NE(p.why.find("did not answer tcpq's hello (0 of 8 bytes)"), std::string::npos) << p.why;
    std::string why;
    lcm_t* lcm = nullptr;
    test::within_a_minute([&] { return lcm = create_lcm(hub.url(), why, 300), 0; }, "create_lcm");
    EXPECT_EQ(lcm, nullptr);
    EXPECT_EQ(why, p.why);
  }
}

TEST(LcmConnect, NothingListeningIsSafeToConnectToAndFailsAtOnce) {
  const std::string url = "tcpq://127.0.0.1:" + std::to_string(free_port());
  const HubProbe p = probe(url);
  EXPECT_EQ(p.answer, HubAnswer::Refused) << p.why;
  EXPECT_TRUE(p.safe_to_connect());
  EXPECT_NE(p.why.find("Connection refused"), std::string::npos) << p.why;
}

TEST(LcmConnect, OtherProvidersAndBadAddressesAreNotAsked) {
  EXPECT_EQ(probe_tcpq_hub("memq://").answer, HubAnswer::NotTcpq);
  EXPECT_EQ(probe_tcpq_hub("file:///tmp/x.lcmlog?mode=w").answer, HubAnswer::NotTcpq);
  const HubProbe p = probe_tcpq_hub("tcpq://127.0.0.1:99999");
  EXPECT_EQ(p.answer, HubAnswer::BadAddress);
  EXPECT_NE(p.why.find("port '99999' is not 0..65535"), std::string::npos) << p.why;
  std::string why;
  EXPECT_EQ(create_lcm("tcpq://127.0.0.1:99999", why), nullptr);
  EXPECT_EQ(why, p.why);
  lcm_t* memq = create_lcm("memq://", why);
  ASSERT_NE(memq, nullptr);
  EXPECT_TRUE(why.empty());
  EXPECT_TRUE(may_reconnect(memq, "memq://"));
  lcm_destroy(memq);
}

TEST(LcmConnect, SomethingElseOnThePortIsAWrongAnswerThatLcmRefusesAtOnce) {
  // A server that answers eight bytes that are not tcpq's: LCM's handshake fails without waiting.
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(listen(fd, 2), 0);
  socklen_t n = sizeof a;
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n);
  std::thread server([fd] {
    const int c = accept(fd, nullptr, nullptr);
    if (c < 0) return;
    (void)send(c, "HTTP/1.0", 8, MSG_NOSIGNAL);
    char buf[8];
    (void)recv(c, buf, sizeof buf, MSG_WAITALL);
    close(c);
  });
  const HubProbe p = probe("tcpq://127.0.0.1:" + std::to_string(ntohs(a.sin_port)));
  server.join();
  close(fd);
  EXPECT_EQ(p.answer, HubAnswer::WrongAnswer) << p.why;
  EXPECT_TRUE(p.safe_to_connect());
}

TEST(LcmConnect, TheLcmSourceFailsItsOpenOnASilentHubNamingIt) {
  TcpqHub hub(TcpqHub::Mode::Silent);
  LcmSourceConfig cfg;
  cfg.url = hub.url();
  LcmSource source(cfg);
  std::string what;
  test::within_a_minute(
      [&] {
        try {
          source.open();
        } catch (const CameraError& e) {
          what = e.what();
        }
        return 0;
      },
      "LcmSource::open");
  EXPECT_NE(what.find("did not answer tcpq's hello"), std::string::npos) << what;
}

}  // namespace
}  // namespace rsd::drivers
