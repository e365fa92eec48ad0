// The daemon's own LCM instance (lcm.url) against a tcpq hub that accepts and never answers
// (issue 38): LCM would wait for the hub's answer for good in lcm_create, and again when a
// publish or an unsubscribe reconnects an instance that lost its hub. The publisher refuses to
// start naming the hub's fault; after a loss, publishing goes on (what it sends is lost, as LCM
// loses it without a hub) and the velocity input ends; neither waits for the silent hub. The
// velocity input receives under the publisher's lock (drivers/lcm_receive.hpp): without it, a
// receive that entered LCM's provider just after a publish lost the hub connected to the silent
// one, and publishing blocked (once, in a clean-clone run).
#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>
#include <string>

#include "daemon/lcm_publisher.hpp"
#include "daemon/velocity_buffer.hpp"
#include "daemon/velocity_input.hpp"
#include "tests/support/tcpq_hub.hpp"

namespace rsd {
namespace {

using test::TcpqHub;

const drivers::FrameFormat kFormat{64, 48, dsp::PixelFormat::Mono8};

TEST(LcmHubFaults, ThePublisherRefusesToStartOnASilentHubNamingIt) {
  TcpqHub hub(TcpqHub::Mode::Silent);
  std::string what;
  test::within_a_minute(
      [&] {
        try {
          daemon::LcmPublisher pub(hub.url(), {}, kFormat);
        } catch (const std::runtime_error& e) {
          what = e.what();
        }
        return 0;
      },
      "LcmPublisher");
  EXPECT_NE(what.find("lcm: cannot open '" + hub.url() + "': tcpq hub 127.0.0.1:"), std::string::npos) << what;
  EXPECT_NE(what.find("did not answer tcpq's hello"), std::string::npos) << what;
}

TEST(LcmHubFaults, AfterTheHubIsReplacedByASilentOnePublishingAndStoppingNeverWait) {
  auto hub = std::make_unique<TcpqHub>();
  const std::string url = hub->url();
  const int port = hub->port();
  auto pub = std::make_unique<daemon::LcmPublisher>(url, daemon::Channels{}, kFormat);
  daemon::VelocityBuffer buffer;
  auto vin = std::make_unique<daemon::VelocityInput>(pub->handle(), "RSD_VELOCITY", buffer, daemon::VelocityInputConfig{}, url,
                                                        &pub->lcm_lock());
  vin->start();
  hub->close_all();  // the hub goes; something that never answers takes its port
  TcpqHub silent(TcpqHub::Mode::Silent, {}, port);
  const int lost = test::within_a_minute(
      [&] {
        // Publishing notices the loss (a write to a closed connection) within a few messages;
        // every publish after it would reconnect to the silent hub.
        int n = 0;
        while (lcm_get_fileno(pub->handle()) >= 0 && n < 10000) pub->publish_health(), ++n;
        for (int i = 0; i < 50; ++i) pub->publish_health();
        return lcm_get_fileno(pub->handle()) < 0 ? 1 : 0;
      },
      "publishing after the hub was lost");
  EXPECT_EQ(lost, 1) << "the connection to the gone hub was never found lost";
  test::within_a_minute([&] { return vin.reset(), pub.reset(), 0; }, "stopping the velocity input and the publisher");
}

}  // namespace
}  // namespace rsd
