#include "lcmtypes/message_decoder.hpp"

#include <cstdarg>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <tsmh/calibration_request_t.hpp>
#include <tsmh/haptic_status_t.hpp>
#include <tsmh/master_command_t.hpp>
#include <tsmh/master_force_t.hpp>
#include <tsmh/master_state_t.hpp>
#include <tsmh/slave_state_t.hpp>
#include <tsmh/slave_truth_t.hpp>
#include <vector>

#include "realtime/enum_names.hpp"

namespace tsmh::lcmtypes {
namespace {

std::uint64_t read_be(const unsigned char* p, int bytes) noexcept {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i)
    v = (v << 8) | p[i];
  return v;
}

void write_be(std::uint64_t v, int bytes, unsigned char* p) noexcept {
  for (int i = bytes - 1; i >= 0; --i, v >>= 8)
    p[i] = static_cast<unsigned char>(v & 0xff);
}

__attribute__((format(printf, 3, 4))) DecodeError make_error(DecodeFault fault, std::size_t size,
                                                             const char* format, ...) noexcept {
  DecodeError e;
  e.fault = fault;
  e.size = size;
  va_list args;
  va_start(args, format);
  std::vsnprintf(e.what.data(), e.what.size(), format, args);
  va_end(args);
  return e;
}

}  // namespace

bool read_header(const void* data, std::size_t size, WireHeader& out) noexcept {
  if (data == nullptr || size < kWireHeaderBytes) return false;
  const auto* p = static_cast<const unsigned char*>(data);
  out.hash = static_cast<std::int64_t>(read_be(p, 8));
  out.utime = static_cast<std::int64_t>(read_be(p + 8, 8));
  out.seq = static_cast<std::int64_t>(read_be(p + 16, 8));
  out.num_joints = static_cast<std::int32_t>(static_cast<std::uint32_t>(read_be(p + 24, 4)));
  return true;
}

std::string_view fault_name(DecodeFault fault) noexcept {
  return realtime::enum_name<DecodeFault::kMalformed>(
      fault, {"truncated_header", "type_hash", "joint_count", "size", "malformed"}, "unknown");
}

template <class Message>
MessageDecoder<Message>::MessageDecoder(JointRange joints) : joints_(joints) {
  if (joints.min < 0 || joints.min > joints.max || joints.max > kMaxJointLimit)
    throw std::invalid_argument(std::string(Message::getTypeName()) + " decoder: joint range " +
                                std::to_string(joints.min) + ".." + std::to_string(joints.max) +
                                " is not within 0.." + std::to_string(kMaxJointLimit));
  // lcm-gen sizes every array by num_joints alone, so two sizes give the layout.
  Message probe{};
  probe.num_joints = 0;
  fixed_bytes_ = static_cast<std::size_t>(probe.getEncodedSize());
  probe.num_joints = 1;
  per_joint_bytes_ = static_cast<std::size_t>(probe.getEncodedSize()) - fixed_bytes_;
  // Decode an all-zero message of `max` joints once: lcm-gen resizes the
  // arrays to it, and later (smaller or equal) messages reuse that capacity.
  std::vector<unsigned char> zeros(encoded_size(joints.max), 0);
  write_be(static_cast<std::uint64_t>(Message::getHash()), 8, zeros.data());
  write_be(static_cast<std::uint32_t>(joints.max), 4, zeros.data() + 24);
  if (msg_.decode(zeros.data(), 0, static_cast<int>(zeros.size())) !=
      static_cast<int>(zeros.size()))
    throw std::logic_error(std::string(Message::getTypeName()) +
                           " decoder: lcm-gen's layout is not fixed + per joint");
}

template <class Message>
std::optional<DecodeError> MessageDecoder<Message>::decode(const void* data, std::size_t size,
                                                           Trailing trailing) noexcept {
  WireHeader h;
  if (!read_header(data, size, h))
    return make_error(DecodeFault::kTruncatedHeader, size,
                      "truncated: %zu bytes, the header needs %zu", size, kWireHeaderBytes);
  if (h.hash != Message::getHash()) {
    auto e = make_error(DecodeFault::kTypeHash, size, "not a %s (type hash differs)",
                        Message::getTypeName());
    return e;
  }
  if (h.num_joints < joints_.min || h.num_joints > joints_.max) {
    auto e = joints_.min == joints_.max
                 ? make_error(DecodeFault::kJointCount, size, "num_joints %d, expected %d",
                              static_cast<int>(h.num_joints), static_cast<int>(joints_.min))
                 : make_error(DecodeFault::kJointCount, size, "num_joints %d outside %d..%d",
                              static_cast<int>(h.num_joints), static_cast<int>(joints_.min),
                              static_cast<int>(joints_.max));
    e.seq = h.seq;
    e.num_joints = h.num_joints;
    return e;
  }
  // num_joints is now at most kMaxJointLimit: the size below cannot overflow.
  const std::size_t expected = encoded_size(h.num_joints);
  if (size < expected || (size > expected && trailing == Trailing::kReject)) {
    auto e = make_error(DecodeFault::kSize, size, "%s: %zu bytes, %zu expected for %d joints",
                        size < expected ? "truncated" : "trailing bytes", size, expected,
                        static_cast<int>(h.num_joints));
    e.seq = h.seq;
    e.num_joints = h.num_joints;
    e.expected = expected;
    return e;
  }
  // The arrays already hold max joints' capacity: lcm-gen's resize() does not allocate.
  if (msg_.decode(data, 0, static_cast<int>(expected)) != static_cast<int>(expected)) {
    auto e = make_error(DecodeFault::kMalformed, size, "lcm decode failed");
    e.seq = h.seq;
    e.num_joints = h.num_joints;
    return e;
  }
  return std::nullopt;
}

template class MessageDecoder<tsmh::slave_state_t>;
template class MessageDecoder<tsmh::slave_truth_t>;
template class MessageDecoder<tsmh::master_command_t>;
template class MessageDecoder<tsmh::master_state_t>;
template class MessageDecoder<tsmh::master_force_t>;
template class MessageDecoder<tsmh::haptic_status_t>;
template class MessageDecoder<tsmh::calibration_request_t>;

}  // namespace tsmh::lcmtypes
