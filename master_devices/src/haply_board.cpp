#include "master_devices/haply_board.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

namespace tsmh::master_devices::haply {

long BoardEmulator::frame_length() const {
  const std::size_t n = buffer_.size();
  if (n < 2) return 0;
  switch (buffer_[0]) {
    case kCommandReset:
      return 2;
    case kCommandSetup: {
      // [1][id][motor mask][dirs][encoder mask][dirs][sensors][pins][pwms][pins][floats]
      std::size_t at = 2;
      if (n <= at) return 0;
      at += 1 + static_cast<std::size_t>(std::popcount(static_cast<unsigned>(buffer_[at] & 0x0F)));
      if (n <= at) return 0;
      const auto encoders =
          static_cast<std::size_t>(std::popcount(static_cast<unsigned>(buffer_[at] & 0x0F)));
      at += 1 + encoders;
      if (n <= at) return 0;
      at += 1 + buffer_[at];
      if (n <= at) return 0;
      at += 1 + buffer_[at];
      at += 8 * encoders;
      return n >= at ? static_cast<long>(at) : 0;
    }
    case kCommandState: {
      // The firmware reads one torque per motor set up for this device id.
      const std::size_t motors =
          configured_ && buffer_[1] == config_.device_id ? config_.joints : 0;
      const std::size_t len = 2 + 4 * motors;
      return n >= len ? static_cast<long>(len) : 0;
    }
    default:
      return -1;
  }
}

void BoardEmulator::receive(const std::uint8_t* data, std::size_t n,
                            std::vector<std::uint8_t>& out) {
  buffer_.insert(buffer_.end(), data, data + n);
  for (;;) {
    const long len = frame_length();
    if (len == 0) return;
    if (len < 0) {
      buffer_.erase(buffer_.begin());
      continue;
    }
    apply(buffer_.data(), static_cast<std::size_t>(len), out);
    buffer_.erase(buffer_.begin(), buffer_.begin() + len);
  }
}

void BoardEmulator::apply(const std::uint8_t* f, std::size_t n, std::vector<std::uint8_t>& out) {
  if (f[0] == kCommandReset) {
    ++resets_;
    configured_ = false;  // the ports forget their device; the PWM outputs keep their duty
    return;
  }
  if (f[0] == kCommandSetup) {
    ++setups_;
    last_setup_.assign(f, f + n);
    BoardConfig c;
    c.device_id = f[1];
    const unsigned motor_mask = f[2] & 0x0F;
    std::size_t at = 3;
    std::array<Rotation, kPorts> motor_dir{};
    std::array<int, kPorts> ports{};
    std::size_t joints = 0;
    for (int p = 1; p <= static_cast<int>(kPorts); ++p)
      if (motor_mask & (1U << (p - 1))) ports[joints++] = p;
    for (std::size_t s = 0; s < joints; ++s)
      motor_dir[s] = static_cast<Rotation>(f[at++]);
    const unsigned encoder_mask = f[at++] & 0x0F;
    std::array<Rotation, kPorts> encoder_dir{};
    const auto encoders = static_cast<std::size_t>(std::popcount(encoder_mask));
    for (std::size_t s = 0; s < encoders; ++s)
      encoder_dir[s] = static_cast<Rotation>(f[at++]);
    at += 1 + f[at];  // analog sensors
    at += 1 + f[at];  // PWM pins
    // Kept in port order (slot s = the s-th used port): the board cannot
    // know which joint of the host's mechanism a port drives.
    c.joints = joints;
    for (std::size_t s = 0; s < joints; ++s) {
      JointWiring& w = c.wiring[s];
      w.port = ports[s];
      w.motor = motor_dir[s];
      w.encoder = encoder_dir[s];
      w.offset_deg = get_float(f + at + 8 * s);
      w.counts_per_rev = get_float(f + at + 8 * s + 4);
    }
    config_ = c;
    // Setting up does not touch the PWM outputs: a motor keeps the duty of
    // the last state command until the next one (as a reset does).
    configured_ = encoders == joints && joints > 0;
    return;
  }
  // State: torques in port order, then the reply with the angles.
  ++states_;
  if (!configured_ || f[1] != config_.device_id) {
    if (!silent_) out.push_back(f[1]);
    return;
  }
  std::array<double, kPorts> requested{};
  double largest = 0.0;
  for (std::size_t s = 0; s < config_.joints; ++s) {
    requested[s] = get_float(f + 2 + 4 * s);
    largest = std::max(largest, std::abs(requested[s]));
  }
  largest_requested_nm_ = std::max(largest_requested_nm_, largest);
  const double k = largest > max_torque_nm_ ? max_torque_nm_ / largest : 1.0;
  torque_ = {};
  for (std::size_t s = 0; s < config_.joints; ++s)
    torque_[static_cast<std::size_t>(config_.wiring[s].port - 1)] = k * requested[s];
  if (silent_) return;
  out.push_back(config_.device_id);
  for (std::size_t s = 0; s < config_.joints; ++s) {
    // The encoder counts from the setup's offset; the board reports degrees.
    const JointWiring& w = config_.wiring[s];
    const double deg = q_rad_[static_cast<std::size_t>(w.port - 1)] * 180.0 / std::numbers::pi;
    const double counts = std::round((deg - w.offset_deg) * w.counts_per_rev / 360.0);
    std::uint8_t b[4];
    put_float(b, static_cast<float>(w.offset_deg + counts * 360.0 / w.counts_per_rev));
    out.insert(out.end(), b, b + 4);
  }
}

}  // namespace tsmh::master_devices::haply
