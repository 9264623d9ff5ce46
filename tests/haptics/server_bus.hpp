#pragma once
// The test's side of a haptic-server session over udpm: the master console
// (signed MASTER_STATE at 1 kHz through the server's `lcm` driver, dead-man
// held, the handle swinging so that the slave moves and its tendons pull)
// and a listener of MASTER_FORCE, MASTER_COMMAND and SLAVE_STATE that keeps
// the newest of each by arrival and, after mark(), when each first showed
// torque off, a hold, a holding slave.

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <string>
#include <thread>
#include <tsmh/master_command_t.hpp>
#include <tsmh/master_force_t.hpp>
#include <tsmh/master_state_t.hpp>
#include <tsmh/slave_state_t.hpp>
#include <vector>

#include "bridge/link_auth.hpp"
#include "realtime/clock.hpp"
#include "session_answer.hpp"
#include "test_link_key.hpp"

namespace tsmh::haptics::test {

/// What the bus carries, newest first by arrival (not by seq: a message that
/// arrives after the hold must count as the last one).
struct Seen {
  bool force_enable = false;
  std::array<double, 2> torque{};
  std::uint64_t forces = 0;
  bool command_enable = false;
  std::uint64_t commands = 0;
  std::int32_t slave_status = 0;
  std::uint64_t slave_states = 0;
  // After mark() (CLOCK_MONOTONIC ns; 0: not yet): the first MASTER_FORCE
  // with enable 0, the first with 0 N m on both joints, the first
  // MASTER_COMMAND with enable 0, the first SLAVE_STATE with the holding bit.
  std::int64_t mark_ns = 0;
  std::int64_t force_disabled_ns = 0;
  std::int64_t force_zero_ns = 0;
  std::int64_t command_hold_ns = 0;
  std::int64_t slave_holding_ns = 0;
};

/// The console: publishes signed MASTER_STATE at 1 kHz (dead-man held, the
/// handle swinging +-0.4 rad so the slave moves and the tendons pull), and
/// listens to MASTER_FORCE, MASTER_COMMAND and SLAVE_STATE.
class Bus {
 public:
  /// `console`: also publish MASTER_STATE (false: another program is the console).
  Bus(std::string url, std::string prefix, bool console = true)
      : url_(std::move(url)), prefix_(std::move(prefix)), lcm_(url_) {
    lcm_.subscribe(prefix_ + "MASTER_FORCE", &Bus::on_force, this);
    lcm_.subscribe(prefix_ + "MASTER_COMMAND", &Bus::on_command, this);
    lcm_.subscribe(prefix_ + "SLAVE_STATE", &Bus::on_state, this);
    listener_ = std::thread([this] {
      while (running_)
        lcm_.handleTimeout(10);
    });
    if (console) console_ = std::thread([this] { run_console(); });
  }
  ~Bus() {
    running_ = false;
    if (console_.joinable()) console_.join();
    listener_.join();
  }
  Seen seen() {
    std::lock_guard lock(mutex_);
    return seen_;
  }
  /// Starts timing the firsts (Seen::*_ns) from now.
  void mark() {
    std::lock_guard lock(mutex_);
    seen_.mark_ns = realtime::monotonic_now_ns();
    seen_.force_disabled_ns = seen_.force_zero_ns = seen_.command_hold_ns = seen_.slave_holding_ns =
        0;
  }

 private:
  void run_console() {
    lcm::LCM out(url_);
    const auto signer = test_signer();
    // The console's session with the server's lcm driver (docs/bridge.md "Sessions").
    const SessionAnswer answer(url_, prefix_ + "MASTER_FORCE", test_link_key(), signer.get());
    const std::string channel = prefix_ + "MASTER_STATE";
    tsmh::master_state_t m{};
    m.num_joints = 2;
    m.q.assign(2, 0.0);
    m.qd.assign(2, 0.0);
    m.buttons = 1;  // dead-man
    std::vector<std::uint8_t> bytes;
    auto next = std::chrono::steady_clock::now();
    const auto start = next;
    std::int64_t seq = 0;
    while (running_) {
      const double t =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      for (std::size_t j = 0; j < 2; ++j) {
        m.q[j] = 0.4 * std::sin(2.0 * M_PI * 0.5 * t);
        m.qd[j] = 0.4 * M_PI * std::cos(2.0 * M_PI * 0.5 * t);
      }
      m.utime = realtime::monotonic_utime();
      m.seq = seq++;
      const int size = m.getEncodedSize();
      bytes.resize(static_cast<std::size_t>(size) + (signer ? bridge::kAuthTrailerBytes : 0));
      m.encode(bytes.data(), 0, size);
      if (signer)
        signer->sign(channel, bytes.data(), static_cast<std::size_t>(size), bytes.data() + size);
      out.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
      next += std::chrono::milliseconds(1);
      std::this_thread::sleep_until(next);
      if (std::chrono::steady_clock::now() > next + std::chrono::milliseconds(50))
        next = std::chrono::steady_clock::now();
    }
  }

  // lcm-gen's decoders read the fields they know and leave the MAC trailer.
  void on_force(const lcm::ReceiveBuffer*, const std::string&, const tsmh::master_force_t* m) {
    if (m->num_joints != 2) return;
    std::lock_guard lock(mutex_);
    seen_.force_enable = m->enable != 0;
    seen_.torque = {m->torque[0], m->torque[1]};
    ++seen_.forces;
    if (seen_.mark_ns == 0) return;
    const std::int64_t now = realtime::monotonic_now_ns();
    if (!seen_.force_enable && seen_.force_disabled_ns == 0) seen_.force_disabled_ns = now;
    if (m->torque[0] == 0.0 && m->torque[1] == 0.0 && seen_.force_zero_ns == 0)
      seen_.force_zero_ns = now;
  }
  void on_command(const lcm::ReceiveBuffer*, const std::string&, const tsmh::master_command_t* m) {
    std::lock_guard lock(mutex_);
    seen_.command_enable = m->enable != 0;
    ++seen_.commands;
    if (seen_.mark_ns != 0 && !seen_.command_enable && seen_.command_hold_ns == 0)
      seen_.command_hold_ns = realtime::monotonic_now_ns();
  }
  void on_state(const lcm::ReceiveBuffer*, const std::string&, const tsmh::slave_state_t* m) {
    std::lock_guard lock(mutex_);
    seen_.slave_status = m->status;
    ++seen_.slave_states;
    if (seen_.mark_ns != 0 && (m->status & 2) != 0 && seen_.slave_holding_ns == 0)
      seen_.slave_holding_ns = realtime::monotonic_now_ns();
  }

  std::string url_;
  std::string prefix_;
  lcm::LCM lcm_;
  std::mutex mutex_;
  Seen seen_;
  std::atomic<bool> running_{true};
  std::thread listener_;
  std::thread console_;
};

}  // namespace tsmh::haptics::test
