#include "bridge/rejection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace tsmh::bridge {

std::string_view reason_name(RejectReason reason) noexcept {
  switch (reason) {
    case RejectReason::kDecode:
      return "decode";
    case RejectReason::kJointCount:
      return "joint_count";
    case RejectReason::kNonFinite:
      return "non_finite";
    case RejectReason::kOutOfRange:
      return "out_of_range";
    case RejectReason::kTimeBackwards:
      return "time_backwards";
    case RejectReason::kImplausible:
      return "implausible_step";
    case RejectReason::kUnauthenticated:
      return "unauthenticated";
    case RejectReason::kBadMac:
      return "bad_mac";
    case RejectReason::kStale:
      return "stale";
    case RejectReason::kReplayed:
      return "replayed";
    case RejectReason::kOtherSession:
      return "other_session";
    case RejectReason::kSessionEnded:
      return "session_ended";
  }
  return "unknown";
}

Rejection make_rejection(RejectReason reason, std::string_view what, double value,
                         std::int32_t joint) noexcept {
  Rejection r;
  r.reason = reason;
  r.value = value;
  r.joint = joint;
  const std::size_t n = std::min(what.size(), r.what.size() - 1);
  std::copy_n(what.data(), n, r.what.data());
  r.what[n] = '\0';
  return r;
}

std::string describe(const Rejection& r, std::string_view channel) {
  // Built with += only: GCC 12's -Wrestrict misfires on chains of operator+.
  std::string field(r.what.data());
  if (r.joint >= 0) {
    field += '[';
    field += std::to_string(r.joint);
    field += ']';
  }
  char value[64];
  std::snprintf(value, sizeof value, "%.17g", r.value);

  std::string out(channel);
  if (r.seq >= 0) {
    out += " seq ";
    out += std::to_string(r.seq);
  }
  out += ": ";
  switch (r.reason) {
    case RejectReason::kDecode:
      out += "cannot decode: ";
      out += field;
      break;
    case RejectReason::kJointCount:
      out += "joint count ";
      out += value;
      out += " rejected (";
      out += field;
      out += ')';
      break;
    case RejectReason::kNonFinite:
      out += field;
      out += " = ";
      out += value;
      out += " is not finite";
      break;
    case RejectReason::kOutOfRange:
      out += field;
      out += " = ";
      out += value;
      out += " is outside its configured range";
      break;
    case RejectReason::kTimeBackwards:
      out += "utime ";
      out += value;
      out += " us is not after the previous message's (";
      out += field;
      out += ')';
      break;
    case RejectReason::kImplausible:
      out += field;
      out += " stepped by ";
      out += value;
      out += " since the last accepted sample: faster than its configured limit";
      break;
    case RejectReason::kUnauthenticated:
      out += "not authenticated (a sender without the link key, or too old a program): ";
      out += field;
      break;
    case RejectReason::kBadMac:
      out += "MAC does not match (wrong link key, or altered on the way): ";
      out += field;
      break;
    case RejectReason::kStale:
      out += "sent ";
      out += value;
      out +=
          " us from this host's clock, outside the freshness window (a recording, or clocks "
          "not synchronised): ";
      out += field;
      break;
    case RejectReason::kReplayed:
      out += "replayed: ";
      out += field;
      out += " already seen or older than the replay window";
      break;
    case RejectReason::kOtherSession:
      out +=
          "another session (a second keyed sender on this session's channel, a restarted "
          "peer or a replay of an older session): ";
      out += field;
      out += "; the session ends in FAULT";
      break;
    case RejectReason::kSessionEnded:
      out += "the session has ended: ";
      out += field;
      break;
  }
  return out;
}

}  // namespace tsmh::bridge
