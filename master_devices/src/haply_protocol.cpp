#include "master_devices/haply_protocol.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "realtime/enum_names.hpp"

namespace tsmh::master_devices::haply {

BoardConfig board_preset(std::string_view name) {
  BoardConfig c;
  c.joints = 2;
  if (name == "gen2") {
    c.wiring[0] = {2, Rotation::kCcw, Rotation::kCcw, 241.0, 10752.0};
    c.wiring[1] = {1, Rotation::kCw, Rotation::kCw, -61.0, 10752.0};
  } else if (name == "gen3") {
    c.wiring[0] = {2, Rotation::kCw, Rotation::kCcw, 180.0, 4880.0};
    c.wiring[1] = {1, Rotation::kCw, Rotation::kCcw, 0.0, 4880.0};
  } else {
    throw std::invalid_argument("'" + std::string(name) +
                                "' is not a known board (expected one of: " + board_preset_names() +
                                ")");
  }
  return c;
}

std::string board_preset_names() {
  return "gen2, gen3";
}

std::string validate(const BoardConfig& c) {
  if (c.joints < 1 || c.joints > kPorts) return "joints must be 1.." + std::to_string(kPorts);
  for (std::size_t j = 0; j < c.joints; ++j) {
    const JointWiring& w = c.wiring[j];
    const std::string who = "joint " + std::to_string(j) + ": ";
    if (w.port < 1 || w.port > static_cast<int>(kPorts))
      return who + "port " + std::to_string(w.port) + " is not 1.." + std::to_string(kPorts);
    for (std::size_t k = 0; k < j; ++k)
      if (c.wiring[k].port == w.port)
        return who + "port " + std::to_string(w.port) + " is also joint " + std::to_string(k) +
               "'s";
    if (!(w.counts_per_rev > 0.0) || !std::isfinite(w.counts_per_rev))
      return who + "counts_per_rev must be > 0";
    if (!std::isfinite(w.offset_deg)) return who + "offset_deg must be finite";
  }
  return "";
}

std::array<std::size_t, kPorts> port_order(const BoardConfig& c) {
  std::array<std::size_t, kPorts> order{};
  std::size_t slot = 0;
  for (int port = 1; port <= static_cast<int>(kPorts); ++port)
    for (std::size_t j = 0; j < c.joints; ++j)
      if (c.wiring[j].port == port) order[slot++] = j;
  return order;
}

void put_float(std::uint8_t* out, float v) noexcept {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  for (int i = 0; i < 4; ++i)
    out[i] = static_cast<std::uint8_t>(bits >> (8 * i));
}

float get_float(const std::uint8_t* in) noexcept {
  std::uint32_t bits = 0;
  for (int i = 0; i < 4; ++i)
    bits |= static_cast<std::uint32_t>(in[i]) << (8 * i);
  float v = 0.0f;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

std::vector<std::uint8_t> encode_reset(std::uint8_t device_id) {
  return {kCommandReset, device_id};
}

namespace {

// Bit p-1 set for each used port p: hAPI builds it by shifting right once per
// port and setting 0x08, which leaves port 1 in bit 0.
std::uint8_t port_mask(const BoardConfig& c) {
  std::uint8_t mask = 0;
  for (std::size_t j = 0; j < c.joints; ++j)
    mask = static_cast<std::uint8_t>(mask | (1U << (c.wiring[j].port - 1)));
  return mask;
}

}  // namespace

std::vector<std::uint8_t> encode_setup(const BoardConfig& c) {
  const auto order = port_order(c);
  std::vector<std::uint8_t> out{kCommandSetup, c.device_id};
  out.push_back(port_mask(c));  // motors
  for (std::size_t s = 0; s < c.joints; ++s)
    out.push_back(static_cast<std::uint8_t>(c.wiring[order[s]].motor));
  out.push_back(port_mask(c));  // encoders
  for (std::size_t s = 0; s < c.joints; ++s)
    out.push_back(static_cast<std::uint8_t>(c.wiring[order[s]].encoder));
  out.push_back(0);  // analog sensors
  out.push_back(0);  // PWM pins
  for (std::size_t s = 0; s < c.joints; ++s) {
    std::uint8_t f[4];
    put_float(f, static_cast<float>(c.wiring[order[s]].offset_deg));
    out.insert(out.end(), f, f + 4);
    put_float(f, static_cast<float>(c.wiring[order[s]].counts_per_rev));
    out.insert(out.end(), f, f + 4);
  }
  return out;
}

std::size_t encode_state(const BoardConfig& c, const JointArray& tau_nm,
                         std::uint8_t* out) noexcept {
  const auto order = port_order(c);
  out[0] = kCommandState;
  out[1] = c.device_id;
  for (std::size_t s = 0; s < c.joints; ++s) {
    const double t = tau_nm[order[s]];
    put_float(out + 2 + 4 * s, std::isfinite(t) ? static_cast<float>(t) : 0.0f);
  }
  return 2 + 4 * c.joints;
}

std::string_view to_string(ReplyError e) {
  return realtime::enum_name<ReplyError::kNotFinite>(
      e, {"none", "wrong length", "wrong device id", "angle not finite"});
}

ReplyError decode_reply(const BoardConfig& c, const std::uint8_t* in, std::size_t n,
                        JointArray& angles_deg) noexcept {
  if (n != reply_size(c)) return ReplyError::kWrongLength;
  if (in[0] != c.device_id) return ReplyError::kWrongDeviceId;
  const auto order = port_order(c);
  JointArray a{};
  for (std::size_t s = 0; s < c.joints; ++s) {
    const float v = get_float(in + 1 + 4 * s);
    if (!std::isfinite(v)) return ReplyError::kNotFinite;
    a[order[s]] = static_cast<double>(v);
  }
  angles_deg = a;
  return ReplyError::kNone;
}

}  // namespace tsmh::master_devices::haply
