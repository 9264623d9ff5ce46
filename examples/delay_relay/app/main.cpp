// lcm-delay-relay: runs the slave "far away". Two LCM networks,
// the slave's and the server's; every message on a matching channel is
// forwarded to the other network after a constant delay plus jitter, or
// dropped, per direction (link_impairment.hpp). The payload is forwarded
// byte for byte on the same channel name, so whatever the sender put in it
// (a MAC trailer included) arrives unchanged.
//
//   lcm-delay-relay --slave-url URL --server-url URL [--delay-ms D]
//                   [--jitter-ms J] [--drop F] [--seed N] [--duration S]
//                   [--to-slave-delay-ms ...] [--to-server-delay-ms ...] ...
//
// Single-threaded: ppoll() on both LCM sockets with the time to the next
// release as its timeout. Not real-time: release times are honoured to the
// scheduler's wake-up latency (tens of microseconds here), far below the
// delays it models.

#include <poll.h>
#include <signal.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <bridge/host_only.hpp>
#include <bridge/lcm_url.hpp>
#include <bridge/stop_signals.hpp>
#include <cstdint>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <realtime/clock.hpp>
#include <string>
#include <tsmh/version.hpp>
#include <vector>

#include "delay_relay/link_impairment.hpp"
#include "files/cli_numbers.hpp"
#include "tsmh/cli_words.hpp"

namespace {

using tsmh::delay_relay::DelayLine;
using tsmh::delay_relay::ImpairmentParams;

struct Message {
  std::string channel;
  std::vector<std::uint8_t> bytes;
  std::int64_t arrival_ns = 0;
};

/// One direction: messages taken from `from`, released to `to`.
struct Direction {
  Direction(const char* label, const ImpairmentParams& p, std::uint64_t seed, lcm::LCM& target)
      : name(label), line(p, seed), to(target) {}
  const char* name;
  DelayLine<Message> line;
  lcm::LCM& to;
  std::vector<std::int64_t> delays_ns;  // measured, for the summary

  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const auto* data = static_cast<const std::uint8_t*>(rbuf->data);
    Message m{channel, std::vector<std::uint8_t>(data, data + rbuf->data_size),
              tsmh::realtime::monotonic_now_ns()};
    line.push(m.arrival_ns, std::move(m));
  }
  void release(std::int64_t now_ns) {
    Message m;
    while (line.pop_due(now_ns, m)) {
      to.publish(m.channel, m.bytes.data(), static_cast<unsigned>(m.bytes.size()));
      delays_ns.push_back(tsmh::realtime::monotonic_now_ns() - m.arrival_ns);
    }
  }
  void summary() {
    std::sort(delays_ns.begin(), delays_ns.end());
    const auto pct = [&](double q) {
      return delays_ns.empty() ? 0.0
                               : static_cast<double>(delays_ns[static_cast<std::size_t>(
                                     q * static_cast<double>(delays_ns.size() - 1))]) *
                                     1e-6;
    };
    const auto& l = line.link();
    const double total = static_cast<double>(l.passed() + l.dropped());
    std::fprintf(stderr,
                 "lcm-delay-relay: %s: %llu forwarded, %llu dropped (%.2f %%), %zu in flight; "
                 "delay min %.2f p50 %.2f max %.2f ms\n",
                 name, static_cast<unsigned long long>(l.passed()),
                 static_cast<unsigned long long>(l.dropped()),
                 total > 0 ? 100.0 * static_cast<double>(l.dropped()) / total : 0.0,
                 line.in_flight(), pct(0.0), pct(0.5), pct(1.0));
  }
};

}  // namespace

int main(int argc, char** argv) {
  const sigset_t stop_set = tsmh::bridge::block_terminating_signals();
  CLI::App app{
      "Forwards LCM messages between the slave's and the server's network with delay, "
      "jitter and loss per direction (docs/virtual-slave.md, 'Far away')."};
  app.set_version_flag("--version", std::string("lcm-delay-relay ") + TSMH_VERSION);
  std::string slave_url, server_url;
  std::string to_slave_re = ".*MASTER_COMMAND";
  std::string to_server_re = ".*SLAVE_STATE|.*SLAVE_TRUTH";
  double delay_ms = 0, jitter_ms = 0, drop = 0, duration_s = 0;
  // A direction's own --delay-ms, --jitter-ms and --drop; -1: the common one.
  struct Overrides {
    const char* name;
    const char* help;
    double delay_ms = -1, jitter_ms = -1, drop = -1;
  };
  Overrides to_slave_set{"to-slave", "override for server -> slave"};
  Overrides to_server_set{"to-server", "override for slave -> server"};
  std::uint64_t seed = 1;
  app.add_option("--slave-url", slave_url, "LCM URL the slave publishes and listens on")
      ->required();
  app.add_option("--server-url", server_url, "LCM URL haptic-server uses")->required();
  app.add_option("--delay-ms", delay_ms, "one-way delay, each direction (ms)");
  app.add_option("--jitter-ms", jitter_ms, "+- uniform jitter on the delay (ms, <= delay)");
  app.add_option("--drop", drop, "fraction of messages lost, each direction (0..1)");
  for (Overrides* d : {&to_slave_set, &to_server_set}) {
    const std::string option = std::string("--") + d->name;
    app.add_option(option + "-delay-ms", d->delay_ms, d->help);
    app.add_option(option + "-jitter-ms", d->jitter_ms, d->help);
    app.add_option(option + "-drop", d->drop, d->help);
  }
  app.add_option("--to-slave-channels", to_slave_re, "channel regex relayed server -> slave");
  app.add_option("--to-server-channels", to_server_re, "channel regex relayed slave -> server");
  app.add_option("--seed", seed, "random seed (same seed, same drops and jitter)");
  app.add_option("--duration", duration_s, "stop after S seconds (0: until a stop signal)")
      ->check(tsmh::files::finite_range(0.0, 1e7, "s"));
  // A typo is named with the nearest option (tsmh/cli_words.hpp).
  if (const int rc = tsmh::cli_words::check_words(app, argc, argv)) return rc;
  CLI11_PARSE(app, argc, argv);

  const auto impairment = [&](const Overrides& d) {
    const auto pick = [](double over, double base) { return over >= 0 ? over : base; };
    const ImpairmentParams p{pick(d.delay_ms, delay_ms) * 1e-3, pick(d.jitter_ms, jitter_ms) * 1e-3,
                             pick(d.drop, drop)};
    tsmh::delay_relay::validate(p, d.name);
    return p;
  };
  try {
    const ImpairmentParams to_slave = impairment(to_slave_set);
    const ImpairmentParams to_server = impairment(to_server_set);
    if (slave_url == server_url)
      throw std::invalid_argument(
          "--slave-url and --server-url must differ (the relay would "
          "receive what it forwards)");
    auto slave_lcm = tsmh::bridge::open_lcm(slave_url);
    auto server_lcm = tsmh::bridge::open_lcm(server_url);
    // Different seeds per direction, both derived from --seed.
    Direction down("server -> slave", to_slave, seed * 2 + 1, *slave_lcm);
    Direction up("slave -> server", to_server, seed * 2 + 2, *server_lcm);
    server_lcm->subscribeFunction<Direction*>(
        to_slave_re,
        [](const lcm::ReceiveBuffer* rb, const std::string& ch, Direction* d) {
          d->on_message(rb, ch);
        },
        &down);
    slave_lcm->subscribeFunction<Direction*>(
        to_server_re,
        [](const lcm::ReceiveBuffer* rb, const std::string& ch, Direction* d) {
          d->on_message(rb, ch);
        },
        &up);
    // Both sides with ttl=0 stay on this host for receiving too (bridge/
    // host_only.hpp): the relay must not carry another host's datagrams to
    // programs that confine their own sockets. Forwarded bytes are not
    // re-encoded, so authenticated messages keep their MAC trailer.
    for (const auto& [url, lcm] :
         {std::pair{slave_url, slave_lcm.get()}, std::pair{server_url, server_lcm.get()}}) {
      if (const auto port = tsmh::bridge::host_only_udpm_port(url)) {
        lcm->getFileno();  // LCM creates its receive socket here at the latest
        if (tsmh::bridge::restrict_udp_port_to_host(*port) == 0)
          throw std::runtime_error("cannot confine LCM's socket for '" + url + "' to this host");
      }
    }
    std::fprintf(stderr,
                 "lcm-delay-relay: %s <-> %s; to slave ('%s') %.1f +- %.1f ms, drop %.3f; to "
                 "server ('%s') %.1f +- %.1f ms, drop %.3f; seed %llu\n",
                 server_url.c_str(), slave_url.c_str(), to_slave_re.c_str(), to_slave.delay_s * 1e3,
                 to_slave.jitter_s * 1e3, to_slave.drop_fraction, to_server_re.c_str(),
                 to_server.delay_s * 1e3, to_server.jitter_s * 1e3, to_server.drop_fraction,
                 static_cast<unsigned long long>(seed));

    const std::int64_t start = tsmh::realtime::monotonic_now_ns();
    const std::int64_t end =
        duration_s > 0 ? start + static_cast<std::int64_t>(duration_s * 1e9) : INT64_MAX;
    while (!tsmh::bridge::terminating_signal_pending(stop_set)) {
      std::int64_t now = tsmh::realtime::monotonic_now_ns();
      if (now >= end) break;
      down.release(now);
      up.release(now);
      // Sleep until a socket is readable, the next release, or 50 ms (to
      // notice a stop signal).
      const std::int64_t wake =
          std::min({down.line.next_release_ns(), up.line.next_release_ns(), now + 50'000'000, end});
      const std::int64_t wait_ns = std::max<std::int64_t>(0, wake - now);
      const timespec ts{static_cast<time_t>(wait_ns / 1'000'000'000),
                        static_cast<long>(wait_ns % 1'000'000'000)};
      pollfd fds[2] = {{server_lcm->getFileno(), POLLIN, 0}, {slave_lcm->getFileno(), POLLIN, 0}};
      if (ppoll(fds, 2, &ts, nullptr) > 0) {
        if (fds[0].revents & POLLIN) server_lcm->handleTimeout(0);
        if (fds[1].revents & POLLIN) slave_lcm->handleTimeout(0);
      }
    }
    down.summary();
    up.summary();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lcm-delay-relay: error: %s\n", e.what());
    return 2;
  }
  return 0;
}
