// Opening and reopening an LCM connection without ever waiting for good (issue 38).
//
// LCM's tcpq provider connects to its hub and then waits for the hub's 8-byte answer with a
// blocking recv() and no timeout. It does so in lcm_create, and again, implicitly, in
// lcm_publish, lcm_subscribe and lcm_unsubscribe on an instance that lost its hub. A hub that
// accepts the TCP connection and never answers (a hung hub, another program on its port, a
// listener whose queue is full) would hold that thread, and with it the daemon's shutdown, for
// good. Before each of those calls rsd asks the hub itself, on a socket of its own and with a
// timeout: connect, send tcpq's client hello, read the answer (probe_tcpq_hub). Only a hub that
// answered, or an address where nothing listens (LCM's own connect then fails at once), is left
// to LCM. A hub that answers rsd's question and then not LCM's, within the instant between
// them, is not covered: that needs a hub built to deceive.
//
// Thread contract: probe_tcpq_hub and create_lcm have no state; may_reconnect reads the
// instance's descriptor and must be called from the thread that makes the call it guards (one
// instance's publishing thread holds its publisher's lock); destroy_lcm when no other thread
// uses the instance any more.
#pragma once

#include <lcm/lcm.h>

#include <string>

namespace rsd::drivers {

// How long a hub may take to answer tcpq's hello (a hub on a loaded machine answers in
// microseconds; half a second is generous, and leaves most of the unit's 2 s stop timeout).
inline constexpr int kHubAnswerTimeoutMs = 500;

enum class HubAnswer {
  NotTcpq,     // another provider (memq://, file://, udpm://): nothing to ask
  Answered,    // the hub answered tcpq's hello
  Refused,     // nothing listens there (LCM's connect fails at once, without waiting)
  Silent,      // connected, no whole answer within the timeout, or a listener that never accepted
  WrongAnswer, // something answered (or closed the connection), not a tcpq hub: LCM fails at once
  BadAddress,  // the URL's host or port cannot be used (LCM refuses it too)
};

struct HubProbe {
  HubAnswer answer = HubAnswer::NotTcpq;
  std::string why;  // for the log: what was asked where, what came back
  // Whether a call into LCM that connects comes back (connected or failed) without waiting.
  bool safe_to_connect() const { return answer != HubAnswer::Silent; }
};

// Asks the tcpq hub of `url` (tcpq://HOST[:PORT], LCM's default 127.0.0.1:7700) for its answer,
// waiting at most timeout_ms in all. Other URLs: NotTcpq.
HubProbe probe_tcpq_hub(const std::string& url, int timeout_ms = kHubAnswerTimeoutMs);

// lcm_create(url) unless the URL's hub would hold it: then nullptr, with `why` saying what the
// hub did (LCM's own failures: nullptr, `why` empty).
lcm_t* create_lcm(const std::string& url, std::string& why, int timeout_ms = kHubAnswerTimeoutMs);

// Whether `lcm` is a tcpq instance (made from `url`) that lost its hub: the next call that
// sends reconnects it.
bool lost_tcpq_hub(lcm_t* lcm, const std::string& url);

// Before a call that reconnects a tcpq instance that lost its hub (lcm_publish, lcm_subscribe,
// lcm_unsubscribe, and lcm_destroy, which unsubscribes what is left): true when the call cannot
// wait for good (the instance is connected, is not tcpq, or its hub answers now or is gone).
bool may_reconnect(lcm_t* lcm, const std::string& url, int timeout_ms = kHubAnswerTimeoutMs);

// lcm_destroy(lcm), which unsubscribes every subscription left and so reconnects an instance
// that lost its hub: when that would wait for a silent hub, the instance is destroyed on a
// thread of its own instead (it ends when the hub answers or closes, or with the process), and
// the caller goes on at once. No callback of the instance runs after this returns either way
// (LCM calls them only from lcm_handle). Returns false when destroying was left to that thread.
bool destroy_lcm(lcm_t* lcm, const std::string& url, int timeout_ms = kHubAnswerTimeoutMs);
// The background half of destroy_lcm, for a caller that has already asked the hub.
void destroy_lcm_detached(lcm_t* lcm, const std::string& url);

}  // namespace rsd::drivers
