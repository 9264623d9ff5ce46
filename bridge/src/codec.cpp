#include "bridge/codec.hpp"

#include <algorithm>
#include <lcm/lcm-cpp.hpp>

#include "bridge/link_auth.hpp"
#include "bridge/validation.hpp"

namespace tsmh::bridge {
namespace {

std::size_t joints(std::int32_t n) noexcept {
  return static_cast<std::size_t>(std::clamp(n, 0, static_cast<int>(kMaxJoints)));
}

// Every message starts with these.
template <class S, class M, class F>
void header(S& s, M& m, F& f) {
  f(s.utime, m.utime), f(s.seq, m.seq), f(s.num_joints, m.num_joints);
}

// One field list per message, walked in both directions: `f(sample_field,
// message_field)` for each field, so a field added to a message is added in
// one place and both directions follow.
template <class S, class M, class F>
void fields(S& s, M& m, F&& f, tsmh::slave_state_t* /*tag*/) {
  header(s, m, f);
  f(s.x_in, m.x_in), f(s.x_out, m.x_out), f(s.T1, m.T1), f(s.T3, m.T3);
  f(s.radius_m, m.radius_m), f(s.status, m.status);
}

template <class S, class M, class F>
void fields(S& s, M& m, F&& f, tsmh::slave_truth_t* /*tag*/) {
  header(s, m, f);
  f(s.tau_out, m.tau_out), f(s.friction, m.friction), f(s.tau_in, m.tau_in);
  f(s.x_out, m.x_out), f(s.contact_force, m.contact_force), f(s.indentation, m.indentation);
}

template <class S, class M, class F>
void fields(S& s, M& m, F&& f, tsmh::master_command_t* /*tag*/) {
  header(s, m, f);
  f(s.position_ref, m.position_ref), f(s.enable, m.enable), f(s.clutch, m.clutch);
}

template <class S, class M, class F>
void fields(S& s, M& m, F&& f, tsmh::haptic_status_t* /*tag*/) {
  header(s, m, f);
  f(s.state, m.state), f(s.feedback_source, m.feedback_source), f(s.rate_hz, m.rate_hz);
  f(s.lateness_p50_us, m.lateness_p50_us), f(s.lateness_p99_us, m.lateness_p99_us);
  f(s.lateness_max_us, m.lateness_max_us), f(s.compute_p99_us, m.compute_p99_us);
  f(s.overruns, m.overruns), f(s.slave_age_ms, m.slave_age_ms);
  f(s.slave_rejected, m.slave_rejected), f(s.slave_seq_gaps, m.slave_seq_gaps);
  f(s.slave_latency_p99_us, m.slave_latency_p99_us), f(s.flags, m.flags);
  f(s.tau_in, m.tau_in), f(s.tau_out_est, m.tau_out_est), f(s.friction_est, m.friction_est);
  f(s.torque_cmd, m.torque_cmd), f(s.master_q, m.master_q);
  f(s.oscillation_trips, m.oscillation_trips), f(s.oscillation_rms, m.oscillation_rms);
  f(s.passivity_energy, m.passivity_energy), f(s.passivity_dissipated, m.passivity_dissipated);
  f(s.calibration_state, m.calibration_state), f(s.calibration_reason, m.calibration_reason);
  f(s.calibration_joint, m.calibration_joint), f(s.friction_scale, m.friction_scale);
  f(s.drift_scale, m.drift_scale);
}

template <class S, class M, class F>
void fields(S& s, M& m, F&& f, tsmh::calibration_request_t* /*tag*/) {
  header(s, m, f);
  f(s.recalibrate, m.recalibrate);
}

// Sample -> message: scalars as they are, arrays as their first num_joints
// entries (the sample's count, clamped to kMaxJoints).
struct ToMessage {
  std::size_t n;
  template <class A, class B>
  void operator()(const A& from, B& to) const {
    to = static_cast<B>(from);
  }
  template <class T, std::size_t N, class B>
  void operator()(const std::array<T, N>& from, std::vector<B>& to) const {
    to.resize(n);
    for (std::size_t j = 0; j < n; ++j)
      to[j] = static_cast<B>(from[j]);
  }
};

// Message -> sample: arrays of the message's num_joints entries (never more
// than it holds or kMaxJoints), the rest zero.
struct FromMessage {
  std::size_t n;
  template <class A, class B>
  void operator()(A& to, const B& from) const noexcept {
    to = static_cast<A>(from);
  }
  template <class T, std::size_t N, class B>
  void operator()(std::array<T, N>& to, const std::vector<B>& from) const noexcept {
    const std::size_t k = std::min(n, from.size());
    for (std::size_t j = 0; j < N; ++j)
      to[j] = j < k ? static_cast<T>(from[j]) : T{};
  }
};

template <class Sample, class Message>
void copy_to(const Sample& s, Message& m) {
  fields(s, m, ToMessage{joints(s.num_joints)}, static_cast<Message*>(nullptr));
}

template <class Message, class Sample>
void copy_from(const Message& m, Sample& s) noexcept {
  fields(s, m, FromMessage{joints(m.num_joints)}, static_cast<Message*>(nullptr));
}

}  // namespace

void to_message(const SlaveStateSample& s, tsmh::slave_state_t& m) {
  copy_to(s, m);
}
void to_message(const SlaveTruthSample& s, tsmh::slave_truth_t& m) {
  copy_to(s, m);
}
void to_message(const MasterCommandSample& s, tsmh::master_command_t& m) {
  copy_to(s, m);
}
void to_message(const HapticStatusSample& s, tsmh::haptic_status_t& m) {
  copy_to(s, m);
}

void to_message(const CalibrationRequestSample& s, tsmh::calibration_request_t& m) {
  copy_to(s, m);
}

void from_message(const tsmh::slave_state_t& m, SlaveStateSample& s) noexcept {
  copy_from(m, s);
}
void from_message(const tsmh::slave_truth_t& m, SlaveTruthSample& s) noexcept {
  copy_from(m, s);
}
void from_message(const tsmh::master_command_t& m, MasterCommandSample& s) noexcept {
  copy_from(m, s);
}
void from_message(const tsmh::haptic_status_t& m, HapticStatusSample& s) noexcept {
  copy_from(m, s);
}
void from_message(const tsmh::calibration_request_t& m, CalibrationRequestSample& s) noexcept {
  copy_from(m, s);
}

template <class Sample>
std::optional<Rejection> Decoder<Sample>::decode(const void* data, std::size_t size,
                                                 Sample& out) noexcept {
  const auto error = decoder_.decode(data, size);
  if (!error) {
    from_message(decoder_.message(), out);
    return std::nullopt;
  }
  std::optional<Rejection> r;
  if (error->fault == lcmtypes::DecodeFault::kJointCount)
    r = check_joint_count(error->num_joints, 0);
  if (!r) r = make_rejection(RejectReason::kDecode, error->what.data(), static_cast<double>(size));
  r->seq = error->seq;
  return r;
}

template <class Sample>
void encode_sample(const Sample& s, std::vector<std::uint8_t>& bytes) {
  typename SampleTraits<Sample>::Message m;
  to_message(s, m);
  bytes.resize(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
}

template <class Sample>
int publish_sample(lcm::LCM& lcm, const std::string& channel, const Sample& s,
                   MessageSigner* signer) {
  if (signer == nullptr) {
    typename SampleTraits<Sample>::Message m;
    to_message(s, m);
    return lcm.publish(channel, &m);
  }
  std::vector<std::uint8_t> bytes;
  encode_sample(s, bytes);
  const std::size_t size = bytes.size();
  bytes.resize(size + kAuthTrailerBytes);
  signer->sign(channel, bytes.data(), size, bytes.data() + size);
  return lcm.publish(channel, bytes.data(), static_cast<unsigned int>(bytes.size()));
}

#define TSMH_BRIDGE_INSTANTIATE(S)                                      \
  template class Decoder<S>;                                            \
  template void encode_sample<S>(const S&, std::vector<std::uint8_t>&); \
  template int publish_sample<S>(lcm::LCM&, const std::string&, const S&, MessageSigner*);
TSMH_BRIDGE_INSTANTIATE(SlaveStateSample)
TSMH_BRIDGE_INSTANTIATE(SlaveTruthSample)
TSMH_BRIDGE_INSTANTIATE(MasterCommandSample)
TSMH_BRIDGE_INSTANTIATE(HapticStatusSample)
TSMH_BRIDGE_INSTANTIATE(CalibrationRequestSample)
#undef TSMH_BRIDGE_INSTANTIATE

}  // namespace tsmh::bridge
