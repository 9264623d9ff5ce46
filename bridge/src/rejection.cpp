#include "bridge/rejection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "realtime/enum_names.hpp"

namespace tsmh::bridge {

std::string_view reason_name(RejectReason reason) noexcept {
  return realtime::enum_name<RejectReason::kSessionEnded>(
      reason,
      {"decode", "joint_count", "non_finite", "out_of_range", "time_backwards", "implausible_step",
       "unauthenticated", "bad_mac", "stale", "replayed", "other_session", "session_ended"},
      "unknown");
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

namespace {

// What a rejection means, per reason: "{field}" and "{value}" stand for the
// rejected field (with its joint) and value.
std::string_view explanation(RejectReason reason) noexcept {
  return realtime::enum_name<RejectReason::kSessionEnded>(
      reason,
      {"cannot decode: {field}", "joint count {value} rejected ({field})",
       "{field} = {value} is not finite", "{field} = {value} is outside its configured range",
       "utime {value} us is not after the previous message's ({field})",
       "{field} stepped by {value} since the last accepted sample: faster than its configured "
       "limit",
       "not authenticated (a sender without the link key, or too old a program): {field}",
       "MAC does not match (wrong link key, or altered on the way): {field}",
       "sent {value} us from this host's clock, outside the freshness window (a recording, or "
       "clocks not synchronised): {field}",
       "replayed: {field} already seen or older than the replay window",
       "another session (a second keyed sender on this session's channel, a restarted peer or a "
       "replay of an older session): {field}; the session ends in FAULT",
       "the session has ended: {field}"},
      "");
}

// Appends `text` with its "{field}" and "{value}" filled in. Built with +=
// only: GCC 12's -Wrestrict misfires on chains of operator+.
void expand(std::string& out, std::string_view text, std::string_view field,
            std::string_view value) {
  constexpr std::string_view kField = "{field}", kValue = "{value}";
  while (!text.empty()) {
    const std::size_t brace = text.find('{');
    out += text.substr(0, brace);
    if (brace == std::string_view::npos) return;
    text.remove_prefix(brace);
    if (text.substr(0, kField.size()) == kField) {
      out += field;
      text.remove_prefix(kField.size());
    } else if (text.substr(0, kValue.size()) == kValue) {
      out += value;
      text.remove_prefix(kValue.size());
    } else {
      out += '{';
      text.remove_prefix(1);
    }
  }
}

}  // namespace

std::string describe(const Rejection& r, std::string_view channel) {
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
  expand(out, explanation(r.reason), field, value);
  return out;
}

}  // namespace tsmh::bridge
