#include "bridge/log_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <unordered_map>

#include "bridge/channels.hpp"
#include "bridge/codec.hpp"
#include "bridge/log_events.hpp"

namespace tsmh::bridge {
namespace {

constexpr unsigned char kSyncWord[4] = {0xED, 0xA1, 0xDA, 0x01};

struct StateRow {
  std::int64_t event = 0;
  std::int64_t seq = 0;
  std::int64_t utime = 0;
  double x_in = 0, x_out = 0, T1 = 0, T3 = 0, radius = 0;
};

struct TruthRow {
  std::int64_t event = 0;
  double tau_out = 0;
};

std::string channel_summary(const std::map<std::string, std::size_t>& seen) {
  if (seen.empty()) return "the log has no events";
  std::string s = "channels in the log:";
  for (const auto& [name, count] : seen)
    s += " " + name + " (" + std::to_string(count) + ")";
  return s;
}

}  // namespace

bool is_lcm_log(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char head[4] = {};
  if (!in.read(reinterpret_cast<char*>(head), sizeof head)) return false;
  return std::equal(std::begin(head), std::end(head), std::begin(kSyncWord));
}

JointSeries read_joint_series(const std::filesystem::path& path, int joint, std::string_view prefix,
                              const LogReadOptions& options) {
  const std::string file = path.string();
  if (joint < 0 || joint >= static_cast<int>(kMaxJoints))
    throw LogError(file, "joint " + std::to_string(joint) + " is outside 0.." +
                             std::to_string(kMaxJoints - 1));
  if (!std::filesystem::is_regular_file(path)) throw LogError(file, "no such file");
  if (!is_lcm_log(path))
    throw LogError(file, "not an LCM log (it does not start with LCM's event sync word)");
  std::optional<MappedFile> mapped;
  try {
    mapped.emplace(file);
  } catch (const std::runtime_error& e) {
    throw LogError(file, e.what());
  }
  return read_joint_series(mapped->bytes(), file, joint, prefix, options);
}

namespace {

// What one pass over the log found for one joint.
struct Collected {
  std::vector<StateRow> states;
  std::unordered_map<std::int64_t, std::vector<TruthRow>> truths;  // by seq
  std::map<std::string, std::size_t> seen;                         // events per channel
  int max_joints_seen = 0;
  std::size_t lacking_joint = 0;      // SLAVE_STATE events without this joint
  std::size_t signed_unverified = 0;  // MAC present, no key to verify it
};

// The key to verify with, or nullptr. With a key, a log in which no event
// carries a MAC predates authentication (or unkeyed senders recorded it):
// read as unsigned, and say so. One with any MAC is verified event by
// event: an unsigned event among signed ones is left out (injected, or a
// sender without the key).
const LinkKey* key_for(std::span<const std::uint8_t> bytes, const std::string& state_channel,
                       const std::string& truth_channel, const LogReadOptions& options,
                       JointSeries& out) {
  if (options.verify_key == nullptr || options.skip_mac) return options.verify_key;
  LogEventReader scan(bytes);
  LogEvent e;
  while (scan.next(e))
    if ((e.channel == state_channel || e.channel == truth_channel) &&
        has_auth_trailer(e.data.data(), e.data.size()))
      return options.verify_key;
  out.no_macs = true;
  return nullptr;
}

// The payload size of an event to use, or nullopt to leave it out (its MAC).
std::optional<std::size_t> authentic_size(const LogEvent& ev, const LinkKey* key,
                                          const LogReadOptions& options, JointSeries& out,
                                          Collected& c) {
  const std::size_t size = ev.data.size();
  const std::size_t trailer_size = auth_trailer_size(ev.data.data(), size);
  const bool has_mac = trailer_size != 0;
  if (options.skip_mac) return size - trailer_size;
  if (key != nullptr) {
    switch (verify_stored(*key, ev.channel, ev.data.data(), size)) {
      case AuthVerdict::kOk:
        return size - trailer_size;
      case AuthVerdict::kMissing:
        ++out.skipped_no_mac;
        return std::nullopt;
      default:
        ++out.skipped_bad_mac;
        return std::nullopt;
    }
  }
  if (has_mac) {
    ++c.signed_unverified;
    return std::nullopt;
  }
  return size;
}

// One pass: the joint's valid state rows and truth values.
Collected collect(LogEventReader& log, const std::string& state_channel,
                  const std::string& truth_channel, int joint, const LinkKey* key,
                  const LogReadOptions& options, JointSeries& out) {
  const auto j = static_cast<std::size_t>(joint);
  Collected c;
  Decoder<SlaveStateSample> state_decoder;
  Decoder<SlaveTruthSample> truth_decoder;
  SlaveStateSample state;
  SlaveTruthSample truth;
  LogEvent event;
  for (const LogEvent* ev = &event; log.next(event);) {
    ++c.seen[std::string(ev->channel)];
    if (ev->channel != state_channel && ev->channel != truth_channel) continue;
    ++(ev->channel == state_channel ? out.state_messages : out.truth_messages);
    const auto authentic = authentic_size(*ev, key, options, out, c);
    if (!authentic) continue;
    const std::size_t size = *authentic;
    if (ev->channel == state_channel) {
      if (state_decoder.decode(ev->data.data(), size, state)) {
        ++out.skipped_invalid;
        continue;
      }
      c.max_joints_seen = std::max(c.max_joints_seen, state.num_joints);
      if (joint >= state.num_joints) {
        ++c.lacking_joint;
        continue;
      }
      StateRow r{ev->eventnum,   state.seq,   state.utime, state.x_in[j],
                 state.x_out[j], state.T1[j], state.T3[j], state.radius_m[j]};
      const bool x_out_ok = std::isfinite(r.x_out) || std::isnan(r.x_out);
      if (!std::isfinite(r.x_in) || !std::isfinite(r.T1) || !std::isfinite(r.T3) ||
          !std::isfinite(r.radius) || !x_out_ok) {
        ++out.skipped_invalid;
        continue;
      }
      c.states.push_back(r);
    } else {
      if (truth_decoder.decode(ev->data.data(), size, truth) || joint >= truth.num_joints ||
          !std::isfinite(truth.tau_out[j])) {
        continue;  // unusable truth: its state row is dropped below for lack of a match
      }
      c.truths[truth.seq].push_back({ev->eventnum, truth.tau_out[j]});
    }
  }
  return c;
}

// Why nothing is usable, as precisely as the pass can tell (always throws).
[[noreturn]] void throw_nothing_usable(const std::string& file, const std::string& state_channel,
                                       int joint, const Collected& c, const JointSeries& out) {
  if (out.skipped_no_mac + out.skipped_bad_mac > 0)
    throw LogError(file, "no " + state_channel +
                             " event is authentic: " + std::to_string(out.skipped_no_mac) +
                             " without a MAC, " + std::to_string(out.skipped_bad_mac) +
                             " whose MAC does not verify with the key given (another "
                             "installation's key?); --skip-mac uses them unverified");
  if (c.lacking_joint > 0)
    throw LogError(file, "joint " + std::to_string(joint) + " does not exist: " + state_channel +
                             " has " + std::to_string(c.max_joints_seen) + " joint(s)");
  if (out.state_messages > 0)
    throw LogError(file, "none of the " + std::to_string(out.state_messages) + " " + state_channel +
                             " messages is usable (undecodable or NaN/Inf for joint " +
                             std::to_string(joint) + ")");
  throw LogError(file, "no " + state_channel + " messages (prefix '" + out.prefix + "'); " +
                           channel_summary(c.seen));
}

// The truth for a state row: matched by seq; after a slave restart a seq can
// repeat, so the truth event closest in the log to the state event.
const TruthRow* truth_for(const StateRow& r, const Collected& c) {
  auto it = c.truths.find(r.seq);
  if (it == c.truths.end()) return nullptr;
  const TruthRow* best = &it->second.front();
  // Distances in double: hostile event numbers must not overflow.
  const auto distance = [&](const TruthRow& t) {
    return std::fabs(static_cast<double>(t.event) - static_cast<double>(r.event));
  };
  for (const TruthRow& t : it->second)
    if (distance(t) < distance(*best)) best = &t;
  return best;
}

// The rows in time order, one radius, truth matched when there is any.
void assemble(const Collected& c, const std::string& file, const std::string& state_channel,
              const std::string& truth_channel, int joint, JointSeries& out) {
  const bool have_truth = !c.truths.empty();
  bool x_out_has_nan = false;
  std::int64_t last_utime = 0;
  for (const StateRow& r : c.states) {
    if (!out.t.empty() && r.utime <= last_utime) {
      ++out.skipped_not_increasing;
      continue;
    }
    double tau_out = 0;
    if (have_truth) {
      const TruthRow* truth = truth_for(r, c);
      if (truth == nullptr) {
        ++out.rows_without_truth;
        continue;
      }
      tau_out = truth->tau_out;
    }
    if (out.t.empty()) {
      out.first_utime = r.utime;
      out.radius_m = r.radius;
      if (!(r.radius > 0))
        throw LogError(file, "event " + std::to_string(r.event) + " " + state_channel +
                                 " radius_m[" + std::to_string(joint) +
                                 "] = " + std::to_string(r.radius) + " is not positive");
    } else if (std::abs(r.radius - out.radius_m) > 1e-12 * std::abs(out.radius_m)) {
      throw LogError(file, "event " + std::to_string(r.event) + " " + state_channel + " radius_m[" +
                               std::to_string(joint) + "] changes from " +
                               std::to_string(out.radius_m) + " to " + std::to_string(r.radius) +
                               "; one CSV holds one radius");
    }
    // In double (a hostile utime must not overflow), and strictly increasing
    // as doubles too: far from the first row two utimes can round to one t.
    const double t = (static_cast<double>(r.utime) - static_cast<double>(out.first_utime)) * 1e-6;
    if (!out.t.empty() && !(t > out.t.back())) {
      ++out.skipped_not_increasing;
      continue;
    }
    last_utime = r.utime;
    out.t.push_back(t);
    out.x_in.push_back(r.x_in);
    out.x_out.push_back(r.x_out);
    out.T1.push_back(r.T1);
    out.T3.push_back(r.T3);
    if (have_truth) out.tau_out.push_back(tau_out);
    x_out_has_nan = x_out_has_nan || std::isnan(r.x_out);
  }
  if (out.t.empty())
    throw LogError(file, "no " + state_channel + " message of joint " + std::to_string(joint) +
                             " has a matching " + truth_channel + " (matched by seq)");
  // The CSV contract has no NaN: a joint without an encoder has no x_out column.
  if (x_out_has_nan) out.x_out.clear();
}

}  // namespace

JointSeries read_joint_series(std::span<const std::uint8_t> bytes, const std::string& file,
                              int joint, std::string_view prefix, const LogReadOptions& options) {
  if (joint < 0 || joint >= static_cast<int>(kMaxJoints))
    throw LogError(file, "joint " + std::to_string(joint) + " is outside 0.." +
                             std::to_string(kMaxJoints - 1));
  if (bytes.size() < 4 || !std::equal(bytes.begin(), bytes.begin() + 4, std::begin(kSyncWord)))
    throw LogError(file, "not an LCM log (it does not start with LCM's event sync word)");
  // Our own reader: liblcm's trusts the length fields.
  LogEventReader log(bytes);
  const std::string state_channel = channel_name(prefix, Channel::kSlaveState);
  const std::string truth_channel = channel_name(prefix, Channel::kSlaveTruth);

  JointSeries out;
  out.source = file;
  out.joint = joint;
  out.prefix = std::string(prefix);
  const LinkKey* key = key_for(bytes, state_channel, truth_channel, options, out);
  const Collected c = collect(log, state_channel, truth_channel, joint, key, options, out);

  // Damage is an error unless the caller accepts it; then it is reported
  // (JointSeries::damage) with the number of events lost.
  out.damage = log.damage();
  if (out.damage.any() && !options.accept_damage)
    throw LogError(file, out.damage.describe() +
                             ". The log is damaged (cut off while recording, or corrupt); to "
                             "use the intact events anyway, pass --accept-truncated");
  if (c.signed_unverified > 0)
    throw LogError(file, std::to_string(c.signed_unverified) + " " + state_channel + "/" +
                             truth_channel +
                             " events carry a MAC (recorded from authenticated senders) and no "
                             "key was given to verify them: pass --key FILE (the installation's "
                             "link key) to use only authentic events, or --skip-mac to use them "
                             "unverified");
  if (c.states.empty()) throw_nothing_usable(file, state_channel, joint, c, out);
  assemble(c, file, state_channel, truth_channel, joint, out);
  return out;
}

}  // namespace tsmh::bridge
