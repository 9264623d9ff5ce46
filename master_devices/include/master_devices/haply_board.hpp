#pragma once
// The Haply board's device side, emulated: it reads the host's bytes as the
// board's firmware does (reset, setup, state commands; haply_protocol.hpp),
// answers every state command with its encoders' angles, and keeps the motor
// torques it was last given, limited as the firmware limits them (|torque|
// at most its MAX_TORQUE, both scaled together when one is above). Pure and
// single-threaded: a test feeds it the bytes a pty carried, a USB gadget
// program the bytes /dev/ttyGS0 carried. The handle's pose is set by the
// caller (a hand that holds it). A board knows ports, not joints: angles and
// torques here are per port (index port - 1); the driver's wiring says which
// joint sits on which port.

#include <cstdint>
#include <vector>

#include "master_devices/haply_protocol.hpp"

namespace tsmh::master_devices::haply {

class BoardEmulator {
 public:
  /// `max_torque_nm`: the firmware's MAX_TORQUE (0.123 N m on Haply's
  /// Arduino-based board).
  explicit BoardEmulator(double max_torque_nm = 0.123) : max_torque_nm_(max_torque_nm) {}

  /// Bytes from the host; the replies go to the end of `out`. Bytes of an
  /// unknown command are skipped one at a time (as the firmware, which reads
  /// one byte as the command and ignores what it does not know).
  void receive(const std::uint8_t* data, std::size_t n, std::vector<std::uint8_t>& out);

  /// The true angle of the joint on each port, rad, in hAPI's convention
  /// (the encoders report it in degrees, quantized, once set up).
  void set_port_angles(const std::array<double, kPorts>& q_rad) { q_rad_ = q_rad; }
  /// Stop answering (a hung firmware, a lost reply stream) or answer again;
  /// commands are still read and applied.
  void set_silent(bool silent) { silent_ = silent; }

  bool configured() const { return configured_; }
  const BoardConfig& config() const { return config_; }
  /// Per port, N m, after the firmware's limit: what the motors apply.
  const std::array<double, kPorts>& port_torques() const { return torque_; }
  /// Largest |torque| any state command asked for (before the firmware's limit).
  double largest_requested_nm() const { return largest_requested_nm_; }
  std::uint64_t resets() const { return resets_; }
  std::uint64_t setups() const { return setups_; }
  std::uint64_t states() const { return states_; }
  const std::vector<std::uint8_t>& last_setup_frame() const { return last_setup_; }

 private:
  /// Bytes of the frame at the start of the buffer: 0 when incomplete, -1
  /// when the command byte is unknown.
  long frame_length() const;
  void apply(const std::uint8_t* f, std::size_t n, std::vector<std::uint8_t>& out);

  double max_torque_nm_;
  std::vector<std::uint8_t> buffer_;
  BoardConfig config_;
  bool configured_ = false;
  bool silent_ = false;
  std::array<double, kPorts> q_rad_{};
  std::array<double, kPorts> torque_{};
  double largest_requested_nm_ = 0.0;
  std::uint64_t resets_ = 0, setups_ = 0, states_ = 0;
  std::vector<std::uint8_t> last_setup_;
};

}  // namespace tsmh::master_devices::haply
