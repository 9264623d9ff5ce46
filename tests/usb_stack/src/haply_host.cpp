// Host side of the `haply_acm` case: our `haply` driver, through the driver
// registry as haptic-server builds it, on the /dev/ttyACM0 that cdc_acm made
// of the emulated board's CDC-ACM gadget (usb_stack_haply_board). Phases,
// each a RESULT line:
//   acm_open      open(): reset + setup + the first reply over the real stack
//   acm_stream    2 s of a 1 kHz loop with torque enabled: samples keep
//                 coming, no fault, the board applies the commanded torque
//   acm_watchdog  the board stops answering (CONTROL.silent): read() goes
//                 stale and the board receives zero torque; it answers again:
//                 OK with the torque back, without re-enabling
//   acm_unplug    the gadget is unbound from the UDC (the cable pulled):
//                 FAULT "link lost" with zero torque
//
// usb_stack_haply_host --port /dev/ttyACM0 --control /tmp/haply --gadget haply

#include <time.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>

#include "guest_report.hpp"
#include "master_devices/builtin_drivers.hpp"
#include "master_devices/clock.hpp"
#include "master_devices/haply_device.hpp"

namespace md = tsmh::master_devices;
using tsmh::usb_stack::metric;
using tsmh::usb_stack::result;

namespace {

std::int64_t now_ns() {
  return md::monotonic_clock()->now_ns();
}

struct BoardState {
  unsigned long long states = 0;
  double port[4] = {0, 0, 0, 0};
};

BoardState board_state(const std::string& control) {
  BoardState s;
  std::ifstream in(control + ".state");
  std::string word;
  in >> word >> s.states >> word >> s.port[0] >> s.port[1] >> s.port[2] >> s.port[3];
  return s;
}

/// Runs a 1 kHz loop (absolute deadlines) for up to `seconds`, commanding
/// `tau` on joint 0, until `done(reading)` holds. Returns whether it did.
template <class Done>
bool loop(md::Device& d, double tau0, double seconds, Done done) {
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  const std::int64_t end = now_ns() + static_cast<std::int64_t>(seconds * 1e9);
  while (now_ns() < end) {
    next.tv_nsec += 1'000'000;
    if (next.tv_nsec >= 1'000'000'000) {
      next.tv_nsec -= 1'000'000'000;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    const md::DeviceReading r = d.read(now_ns());
    md::JointArray tau{};
    tau[0] = tau0;
    d.write_torque(tau);
    if (done(r)) return true;
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  std::string port = "/dev/ttyACM0", control = "/tmp/haply", gadget = "haply";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--port")) port = argv[i + 1];
    if (!std::strcmp(argv[i], "--control")) control = argv[i + 1];
    if (!std::strcmp(argv[i], "--gadget")) gadget = argv[i + 1];
  }
  md::DriverRegistry registry;
  md::register_builtin_drivers(registry);
  std::unique_ptr<md::Device> dev;
  const std::int64_t t_open = now_ns();
  try {
    dev = registry.create("haply", YAML::Load("{port: " + port + ", command_timeout_ms: 500}"));
    dev->open();
  } catch (const std::exception& e) {
    result("acm_open", false, e.what());
    return 0;
  }
  result("acm_open", true,
         port + ": handshake over cdc_acm in " + std::to_string((now_ns() - t_open) / 1'000'000) +
             " ms");

  // Stream: 2 s with torque enabled (0.05 N m on joint 0, which is port 2).
  dev->set_enabled(true);
  std::uint64_t first_seq = 0, last_seq = 0;
  long ticks = 0, ok_ticks = 0, faults = 0;
  bool applied = false;
  loop(*dev, 0.05, 2.0, [&](const md::DeviceReading& r) {
    ++ticks;
    if (!first_seq) first_seq = r.sequence;
    last_seq = r.sequence;
    ok_ticks += r.status == md::DeviceStatus::kOk;
    faults += r.status == md::DeviceStatus::kFault;
    if (ticks % 50 == 0) applied = applied || std::abs(board_state(control).port[1] - 0.05) < 1e-6;
    return false;
  });
  const double replies_per_s = static_cast<double>(last_seq - first_seq) / 2.0;
  metric("acm_replies_per_s", replies_per_s, "1/s");
  metric("acm_ok_ticks", 100.0 * static_cast<double>(ok_ticks) / static_cast<double>(ticks), "%");
  result("acm_stream", faults == 0 && last_seq > first_seq + 100 && applied,
         std::to_string(last_seq - first_seq) + " replies in 2 s, " + std::to_string(ok_ticks) +
             "/" + std::to_string(ticks) + " ticks OK, " + std::to_string(faults) +
             " faulted, board applied 0.05 N m: " + (applied ? "yes" : "no") + " (" +
             dev->last_error() + ")");

  // Watchdog: the board goes silent but still takes commands.
  std::ofstream(control + ".silent").put('1');
  const std::int64_t t_silent = now_ns();
  std::int64_t t_stale = 0, t_zero = 0;
  const bool zeroed = loop(*dev, 0.05, 5.0, [&](const md::DeviceReading& r) {
    if (!t_stale && r.status == md::DeviceStatus::kDisconnected && r.stale) t_stale = now_ns();
    if (!t_zero && board_state(control).port[1] == 0.0) t_zero = now_ns();
    return t_stale && t_zero;
  });
  std::remove((control + ".silent").c_str());
  bool resumed = false;
  if (zeroed) {
    resumed = loop(*dev, 0.05, 5.0, [&](const md::DeviceReading& r) {
      return r.status == md::DeviceStatus::kOk &&
             std::abs(board_state(control).port[1] - 0.05) < 1e-6;
    });
    metric("acm_watchdog_stale_ms", static_cast<double>(t_stale - t_silent) / 1e6, "ms");
    metric("acm_watchdog_zero_torque_ms", static_cast<double>(t_zero - t_silent) / 1e6, "ms");
  }
  result(
      "acm_watchdog", zeroed && resumed,
      std::string("silent board: stale after ") + std::to_string((t_stale - t_silent) / 1'000'000) +
          " ms, zero torque at the board after " + std::to_string((t_zero - t_silent) / 1'000'000) +
          " ms (watchdog 20 ms); answering again: " +
          (resumed ? "OK with torque, not re-enabled" : "did not resume"));

  // Unplug: unbind the gadget while the loop keeps commanding torque.
  const std::int64_t t_unbind = now_ns();
  std::ofstream("/sys/kernel/config/usb_gadget/" + gadget + "/UDC") << "\n";
  std::int64_t t_fault = 0;
  md::DeviceReading last;
  loop(*dev, 0.05, 5.0, [&](const md::DeviceReading& r) {
    last = r;
    if (r.status == md::DeviceStatus::kFault) t_fault = now_ns();
    return t_fault != 0;
  });
  const bool unplug_ok = t_fault && last.fault == md::FaultCode::kLinkLost &&
                         last.tau_commanded[0] == 0.0 && !last.enabled;
  if (t_fault) metric("acm_unplug_fault_ms", static_cast<double>(t_fault - t_unbind) / 1e6, "ms");
  result("acm_unplug", unplug_ok,
         (t_fault ? "FAULT " + std::string(md::to_string(last.fault)) + " " +
                        std::to_string((t_fault - t_unbind) / 1'000'000) + " ms after the unbind"
                  : std::string("no FAULT within 5 s")) +
             ": " + dev->last_error());
  dev->close();
  return 0;
}
