#pragma once
// The Haply board's serial protocol (the 2DIY's USB CDC-ACM board), as
// Haply's open-source hAPI (Java: Board.java, Device.java) and its board
// firmware publish it; docs/master-devices.md, "haply", says which facts come
// from where. Our own code; pure and allocation-free on the real-time path
// (encode_state, ReplyParser), so both the driver and the device-side
// emulator (haply_board.hpp) use it.
//
// Host -> board, one frame per command, no length and no checksum:
//   [command u8][device id u8][command bytes...][float32 little-endian...]
//   0 reset   no payload; the board answers nothing
//   1 setup   motor ports (bit p-1 = port p) + one rotation byte per motor,
//             encoder ports + one rotation byte per encoder, analog sensor
//             count (0) + pins, PWM pin count (0) + pins; then per encoder,
//             in port order, its offset (deg) and resolution (counts/rev) as
//             floats; the board answers nothing
//   2 state   PWM pulses (none here), then one torque (N m) per motor, in
//             port order; the board answers with a reply
// Board -> host, only after a state command:
//   [device id u8][float32 LE per analog sensor (none)][float32 LE angle per
//   encoder, in port order, degrees]

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "master_devices/types.hpp"

namespace tsmh::master_devices::haply {

inline constexpr std::uint8_t kCommandReset = 0;
inline constexpr std::uint8_t kCommandSetup = 1;
inline constexpr std::uint8_t kCommandState = 2;
/// Motor/encoder ports on the board.
inline constexpr std::size_t kPorts = 4;
/// Largest frame either way for kPorts motors.
inline constexpr std::size_t kMaxFrame = 2 + 4 * kPorts + 64;

/// hAPI's rotation codes (CW = 0, CCW = 1).
enum class Rotation : std::uint8_t { kCw = 0, kCcw = 1 };

/// One mechanism joint (hAPI's actuator/encoder index j + 1): on which board
/// port its motor and encoder sit and how the board turns counts into degrees.
struct JointWiring {
  int port = 0;  ///< 1..kPorts
  Rotation motor = Rotation::kCcw;
  Rotation encoder = Rotation::kCcw;
  double offset_deg = 0.0;      ///< the angle the encoder reads at setup (the rest pose)
  double counts_per_rev = 0.0;  ///< encoder resolution
};

struct BoardConfig {
  std::uint8_t device_id = 5;  ///< any; hAPI's examples use 5
  std::size_t joints = 2;
  std::array<JointWiring, kPorts> wiring{};
};

/// The 2DIY's wiring as Haply's examples set it up: `gen2` (ports 2 and 1,
/// offsets 241 and -61 deg, 10752 counts) and `gen3` (offsets 180 and 0 deg,
/// 4880 counts; its motors turn the other way).
BoardConfig board_preset(std::string_view name);  ///< throws std::invalid_argument
/// "gen2, gen3"
std::string board_preset_names();

/// Empty when valid, else what is wrong ("joint 1: port 5 is not 1..4").
std::string validate(const BoardConfig& c);

/// Joint index of each wire slot (port order): wire slot s carries joint
/// order[s]. `joints` entries are valid.
std::array<std::size_t, kPorts> port_order(const BoardConfig& c);

std::vector<std::uint8_t> encode_reset(std::uint8_t device_id = 0);
std::vector<std::uint8_t> encode_setup(const BoardConfig& c);
/// A state command carrying `tau_nm[j]` for joint j (non-finite sent as 0).
/// Returns the frame's length (<= kMaxFrame). Real-time safe.
std::size_t encode_state(const BoardConfig& c, const JointArray& tau_nm,
                         std::uint8_t* out) noexcept;
/// Length of the board's reply to a state command.
constexpr std::size_t reply_size(const BoardConfig& c) noexcept {
  return 1 + 4 * c.joints;
}

enum class ReplyError : std::uint8_t { kNone, kWrongLength, kWrongDeviceId, kNotFinite };
std::string_view to_string(ReplyError e);

/// Decodes a reply into joint angles in degrees (joint order). Real-time safe.
ReplyError decode_reply(const BoardConfig& c, const std::uint8_t* in, std::size_t n,
                        JointArray& angles_deg) noexcept;

/// little-endian float32, as hAPI's FloatToBytes / BytesToFloat lay them out
void put_float(std::uint8_t* out, float v) noexcept;
float get_float(const std::uint8_t* in) noexcept;

}  // namespace tsmh::master_devices::haply
