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

void put(const JointArray& a, std::int32_t n, std::vector<double>& v) {
  v.assign(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(joints(n)));
}

void get(const std::vector<double>& v, std::int32_t n, JointArray& a) noexcept {
  const std::size_t k = std::min(joints(n), v.size());
  std::copy_n(v.begin(), k, a.begin());
  std::fill(a.begin() + static_cast<std::ptrdiff_t>(k), a.end(), 0.0);
}

}  // namespace

void to_message(const SlaveStateSample& s, tsmh::slave_state_t& m) {
  m.utime = s.utime;
  m.seq = s.seq;
  m.num_joints = s.num_joints;
  put(s.x_in, s.num_joints, m.x_in);
  put(s.x_out, s.num_joints, m.x_out);
  put(s.T1, s.num_joints, m.T1);
  put(s.T3, s.num_joints, m.T3);
  put(s.radius_m, s.num_joints, m.radius_m);
  m.status = s.status;
}

void to_message(const SlaveTruthSample& s, tsmh::slave_truth_t& m) {
  m.utime = s.utime;
  m.seq = s.seq;
  m.num_joints = s.num_joints;
  put(s.tau_out, s.num_joints, m.tau_out);
  put(s.friction, s.num_joints, m.friction);
  put(s.tau_in, s.num_joints, m.tau_in);
  put(s.x_out, s.num_joints, m.x_out);
  put(s.contact_force, s.num_joints, m.contact_force);
  put(s.indentation, s.num_joints, m.indentation);
}

void to_message(const MasterCommandSample& s, tsmh::master_command_t& m) {
  m.utime = s.utime;
  m.seq = s.seq;
  m.num_joints = s.num_joints;
  put(s.position_ref, s.num_joints, m.position_ref);
  m.enable = s.enable;
  m.clutch = s.clutch;
}

void to_message(const HapticStatusSample& s, tsmh::haptic_status_t& m) {
  m.utime = s.utime;
  m.seq = s.seq;
  m.num_joints = s.num_joints;
  m.state = s.state;
  m.feedback_source = s.feedback_source;
  m.rate_hz = s.rate_hz;
  m.lateness_p50_us = s.lateness_p50_us;
  m.lateness_p99_us = s.lateness_p99_us;
  m.lateness_max_us = s.lateness_max_us;
  m.compute_p99_us = s.compute_p99_us;
  m.overruns = s.overruns;
  m.slave_age_ms = s.slave_age_ms;
  m.slave_rejected = s.slave_rejected;
  m.slave_seq_gaps = s.slave_seq_gaps;
  m.slave_latency_p99_us = s.slave_latency_p99_us;
  m.flags = s.flags;
  put(s.tau_in, s.num_joints, m.tau_in);
  put(s.tau_out_est, s.num_joints, m.tau_out_est);
  put(s.friction_est, s.num_joints, m.friction_est);
  put(s.torque_cmd, s.num_joints, m.torque_cmd);
  put(s.master_q, s.num_joints, m.master_q);
  m.oscillation_trips = s.oscillation_trips;
  put(s.oscillation_rms, s.num_joints, m.oscillation_rms);
  put(s.passivity_energy, s.num_joints, m.passivity_energy);
  put(s.passivity_dissipated, s.num_joints, m.passivity_dissipated);
  m.calibration_state = s.calibration_state;
  m.calibration_reason = s.calibration_reason;
  m.calibration_joint = s.calibration_joint;
  put(s.friction_scale, s.num_joints, m.friction_scale);
  put(s.drift_scale, s.num_joints, m.drift_scale);
}

void to_message(const CalibrationRequestSample& s, tsmh::calibration_request_t& m) {
  m.utime = s.utime;
  m.seq = s.seq;
  m.num_joints = s.num_joints;
  const auto n =
      static_cast<std::size_t>(std::clamp(s.num_joints, 0, static_cast<int>(kMaxJoints)));
  m.recalibrate.assign(s.recalibrate.begin(), s.recalibrate.begin() + static_cast<long>(n));
}

void from_message(const tsmh::calibration_request_t& m, CalibrationRequestSample& s) noexcept {
  s.utime = m.utime;
  s.seq = m.seq;
  s.num_joints = m.num_joints;
  s.recalibrate = {};
  for (std::size_t j = 0; j < m.recalibrate.size() && j < kMaxJoints; ++j)
    s.recalibrate[j] = m.recalibrate[j] != 0;
}

void from_message(const tsmh::slave_state_t& m, SlaveStateSample& s) noexcept {
  s.utime = m.utime;
  s.seq = m.seq;
  s.num_joints = m.num_joints;
  get(m.x_in, m.num_joints, s.x_in);
  get(m.x_out, m.num_joints, s.x_out);
  get(m.T1, m.num_joints, s.T1);
  get(m.T3, m.num_joints, s.T3);
  get(m.radius_m, m.num_joints, s.radius_m);
  s.status = m.status;
}

void from_message(const tsmh::slave_truth_t& m, SlaveTruthSample& s) noexcept {
  s.utime = m.utime;
  s.seq = m.seq;
  s.num_joints = m.num_joints;
  get(m.tau_out, m.num_joints, s.tau_out);
  get(m.friction, m.num_joints, s.friction);
  get(m.tau_in, m.num_joints, s.tau_in);
  get(m.x_out, m.num_joints, s.x_out);
  get(m.contact_force, m.num_joints, s.contact_force);
  get(m.indentation, m.num_joints, s.indentation);
}

void from_message(const tsmh::master_command_t& m, MasterCommandSample& s) noexcept {
  s.utime = m.utime;
  s.seq = m.seq;
  s.num_joints = m.num_joints;
  get(m.position_ref, m.num_joints, s.position_ref);
  s.enable = m.enable != 0;
  s.clutch = m.clutch != 0;
}

void from_message(const tsmh::haptic_status_t& m, HapticStatusSample& s) noexcept {
  s.utime = m.utime;
  s.seq = m.seq;
  s.num_joints = m.num_joints;
  s.state = m.state;
  s.feedback_source = m.feedback_source;
  s.rate_hz = m.rate_hz;
  s.lateness_p50_us = m.lateness_p50_us;
  s.lateness_p99_us = m.lateness_p99_us;
  s.lateness_max_us = m.lateness_max_us;
  s.compute_p99_us = m.compute_p99_us;
  s.overruns = m.overruns;
  s.slave_age_ms = m.slave_age_ms;
  s.slave_rejected = m.slave_rejected;
  s.slave_seq_gaps = m.slave_seq_gaps;
  s.slave_latency_p99_us = m.slave_latency_p99_us;
  s.flags = m.flags;
  get(m.tau_in, m.num_joints, s.tau_in);
  get(m.tau_out_est, m.num_joints, s.tau_out_est);
  get(m.friction_est, m.num_joints, s.friction_est);
  get(m.torque_cmd, m.num_joints, s.torque_cmd);
  get(m.master_q, m.num_joints, s.master_q);
  s.oscillation_trips = m.oscillation_trips;
  get(m.oscillation_rms, m.num_joints, s.oscillation_rms);
  get(m.passivity_energy, m.num_joints, s.passivity_energy);
  get(m.passivity_dissipated, m.num_joints, s.passivity_dissipated);
  s.calibration_state = m.calibration_state;
  s.calibration_reason = m.calibration_reason;
  s.calibration_joint = m.calibration_joint;
  get(m.friction_scale, m.num_joints, s.friction_scale);
  get(m.drift_scale, m.num_joints, s.drift_scale);
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
