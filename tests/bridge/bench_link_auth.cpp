// bench_link_auth: what message authentication costs per message
// (bridge/link_auth.hpp; docs/bridge.md "Authentication"). Not run by ctest.
//   sign:   MessageSigner::sign (HMAC-SHA-512-256 over channel + payload +
//           trailer header), in the Sender's publish thread
//   verify: MessageVerifier::verify (MAC, freshness, replay window), in the
//           Receiver's receive thread
//   session: LinkSession::observe (bridge/link_session.hpp) on a bound
//           session, after verify in the receive thread
// for the encoded 2- and 8-joint SLAVE_STATE. Each call timed alone with a
// CLOCK_MONOTONIC pair (whose own cost is printed), and the mean of
// back-to-back calls. Neither runs in the 1 kHz loop thread.
// Usage: bench_link_auth [--count N] (default 200000)
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "bridge/codec.hpp"
#include "bridge/link_auth.hpp"
#include "bridge/link_session.hpp"
#include "realtime/clock.hpp"
#include "realtime/quantile.hpp"
#include "test_samples.hpp"

namespace {

using namespace tsmh::bridge;

using tsmh::realtime::percentiles;

void print(const char* what, const std::vector<double>& ns, double mean_ns) {
  const auto r = percentiles(ns);
  std::printf("  %-40s p50 %7.0f  p99 %7.0f  p99.9 %7.0f  max %8.0f  mean(back-to-back) %6.0f ns\n",
              what, r.p50, r.p99, r.p999, r.max, mean_ns);
}

void bench(int joints, int count) {
  const auto key = std::make_shared<const LinkKey>(LinkKey::generate());
  MessageSigner signer(key);
  MessageVerifier verifier(key);
  const std::string channel = "ARM1_SLAVE_STATE";
  std::vector<std::uint8_t> payload;
  encode_sample(test::make_state(1, 1000, joints), payload);
  const std::size_t n = payload.size();

  // Every message signed for real (its own sequence) so verify sees a stream.
  std::vector<std::vector<std::uint8_t>> messages(static_cast<std::size_t>(count));
  std::vector<double> sign_ns, verify_ns, timer_ns;
  sign_ns.reserve(messages.size());
  verify_ns.reserve(messages.size());
  for (auto& m : messages) {
    m = payload;
    m.resize(n + kAuthTrailerBytes);
    const std::int64_t t0 = tsmh::realtime::monotonic_now_ns();
    signer.sign(channel, m.data(), n, m.data() + n);
    const std::int64_t t1 = tsmh::realtime::monotonic_now_ns();
    sign_ns.push_back(static_cast<double>(t1 - t0));
    timer_ns.push_back(static_cast<double>(tsmh::realtime::monotonic_now_ns() - t1));
  }
  const std::int64_t now_us = tsmh::realtime::wall_clock_utime();
  std::size_t ok = 0;
  for (const auto& m : messages) {
    const std::int64_t t0 = tsmh::realtime::monotonic_now_ns();
    ok += verifier.verify(channel, m.data(), m.size(), now_us).verdict == AuthVerdict::kOk;
    verify_ns.push_back(static_cast<double>(tsmh::realtime::monotonic_now_ns() - t0));
  }
  // Back-to-back means (no timer inside the loop).
  std::vector<std::uint8_t> scratch = messages.front();
  const std::int64_t s0 = tsmh::realtime::monotonic_now_ns();
  for (int i = 0; i < count; ++i)
    signer.sign(channel, scratch.data(), n, scratch.data() + n);
  const double sign_mean = static_cast<double>(tsmh::realtime::monotonic_now_ns() - s0) / count;
  MessageVerifier fresh(key);
  const std::int64_t v0 = tsmh::realtime::monotonic_now_ns();
  for (const auto& m : messages)
    ok += fresh.verify(channel, m.data(), m.size(), now_us).verdict == AuthVerdict::kOk;
  const double verify_mean = static_cast<double>(tsmh::realtime::monotonic_now_ns() - v0) / count;

  // The session check of a bound session: the peer's messages name us.
  MessageSigner mine(key);
  LinkSession session(mine);
  std::vector<AuthTrailer> trailers(messages.size());
  for (std::size_t i = 0; i < trailers.size(); ++i)
    trailers[i] = {signer.sender_id(), i + 1, now_us, mine.sender_id()};
  std::vector<double> session_ns;
  session_ns.reserve(trailers.size());
  std::size_t accepted = 0;
  for (const auto& t : trailers) {
    const std::int64_t t0 = tsmh::realtime::monotonic_now_ns();
    accepted += session.observe(t, t0) == SessionVerdict::kAccept;
    session_ns.push_back(static_cast<double>(tsmh::realtime::monotonic_now_ns() - t0));
  }
  const std::int64_t o0 = tsmh::realtime::monotonic_now_ns();
  for (const auto& t : trailers)
    accepted += session.observe(t, o0) == SessionVerdict::kAccept;
  const double session_mean = static_cast<double>(tsmh::realtime::monotonic_now_ns() - o0) / count;

  std::printf(
      "\nSLAVE_STATE %d joints: payload %zu bytes + %zu trailer; %d messages, %zu verified\n",
      joints, n, kAuthTrailerBytes, count, ok);
  print("sign (publish thread)", sign_ns, sign_mean);
  print("verify (receive thread)", verify_ns, verify_mean);
  std::printf("  (session: %zu of %zu accepted)\n", accepted, 2 * trailers.size());
  print("session check (receive thread)", session_ns, session_mean);
  print("timer alone (clock_gettime pair)", timer_ns, 0);
}

}  // namespace

int main(int argc, char** argv) {
  int count = 200000;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--count") == 0 && i + 1 < argc) {
      count = std::atoi(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: bench_link_auth [--count N]\n");
      return 2;
    }
  }
  if (count < 100) count = 100;
  std::printf("bench_link_auth: HMAC-SHA-512-256 (libsodium), per message, ns\n");
  bench(2, count);
  bench(8, count);
  return 0;
}
