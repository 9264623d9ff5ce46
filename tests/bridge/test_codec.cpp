#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "bridge/codec.hpp"
#include "bridge/validation.hpp"
#include "test_support.hpp"

namespace tsmh::bridge {
namespace {

using test::make_state;

template <class Sample>
Sample round_trip(const Sample& in) {
  std::vector<std::uint8_t> bytes;
  encode_sample(in, bytes);
  Sample out;
  Decoder<Sample> d;
  const auto r = d.decode(bytes.data(), bytes.size(), out);
  EXPECT_FALSE(r.has_value()) << (r ? describe(*r, "test") : "");
  return out;
}

TEST(Codec, SlaveStateRoundTrips) {
  SlaveStateSample in = make_state(42, 123456, 3);
  in.x_out[2] = std::nan("");
  const SlaveStateSample out = round_trip(in);
  EXPECT_EQ(out.utime, 123456);
  EXPECT_EQ(out.seq, 42);
  EXPECT_EQ(out.num_joints, 3);
  EXPECT_EQ(out.status, 1);
  for (std::size_t j = 0; j < 3; ++j) {
    EXPECT_EQ(out.x_in[j], in.x_in[j]);
    EXPECT_EQ(out.T1[j], in.T1[j]);
    EXPECT_EQ(out.T3[j], in.T3[j]);
    EXPECT_EQ(out.radius_m[j], in.radius_m[j]);
  }
  EXPECT_TRUE(std::isnan(out.x_out[2]));
  EXPECT_EQ(out.x_in[3], 0.0) << "entries beyond num_joints are zeroed";
}

TEST(Codec, EveryTypeRoundTrips) {
  MasterCommandSample c;
  c.utime = 5;
  c.seq = 6;
  c.num_joints = 2;
  c.position_ref = {0.1, -0.2};
  c.enable = true;
  c.clutch = true;
  const auto c2 = round_trip(c);
  EXPECT_EQ(c2.position_ref[1], -0.2);
  EXPECT_TRUE(c2.enable);
  EXPECT_TRUE(c2.clutch);

  HapticStatusSample h;
  h.seq = 3;
  h.num_joints = 2;
  h.rate_hz = 1000.0;
  h.slave_seq_gaps = 4;
  h.slave_latency_p99_us = 55.5;
  h.torque_cmd = {0.3, 0.4};
  h.flags = 0b10101 | (1 << 12) | (1 << 13);
  h.oscillation_trips = 2;  // delayed teleoperation's fields
  h.oscillation_rms = {0.01, 0.02};
  h.passivity_energy = {-0.003, 0.5};
  h.passivity_dissipated = {0.04, 0.0};
  h.flags |= (1 << 8) | (1 << 9);  // recalibration's fields
  h.calibration_state = 4;
  h.calibration_reason = 2;
  h.calibration_joint = 1;
  h.friction_scale = {1.0, 1.5};
  h.drift_scale = {std::nan(""), 1.45};
  const auto h2 = round_trip(h);
  EXPECT_EQ(h2.calibration_state, 4);
  EXPECT_EQ(h2.calibration_reason, 2);
  EXPECT_EQ(h2.calibration_joint, 1);
  EXPECT_EQ(h2.friction_scale[1], 1.5);
  EXPECT_TRUE(std::isnan(h2.drift_scale[0]));
  EXPECT_EQ(h2.drift_scale[1], 1.45);
  EXPECT_EQ(h2.oscillation_trips, 2);
  EXPECT_EQ(h2.oscillation_rms[1], 0.02);
  EXPECT_EQ(h2.passivity_energy[0], -0.003);
  EXPECT_EQ(h2.passivity_dissipated[0], 0.04);
  EXPECT_EQ(h2.rate_hz, 1000.0);
  EXPECT_EQ(h2.slave_seq_gaps, 4);
  EXPECT_EQ(h2.slave_latency_p99_us, 55.5);
  EXPECT_EQ(h2.torque_cmd[1], 0.4);
  EXPECT_EQ(h2.flags, 0b10101 | (1 << 8) | (1 << 9) | (1 << 12) | (1 << 13));

  CalibrationRequestSample r;
  r.num_joints = 3;
  r.recalibrate = {true, false, true, true};  // the 4th is beyond num_joints
  const auto r2 = round_trip(r);
  EXPECT_TRUE(r2.recalibrate[0]);
  EXPECT_FALSE(r2.recalibrate[1]);
  EXPECT_TRUE(r2.recalibrate[2]);
  EXPECT_FALSE(r2.recalibrate[3]);

  const SlaveTruthSample t = test::make_truth(9, 10, 2);
  const auto t2 = round_trip(t);
  EXPECT_EQ(t2.tau_out[1], t.tau_out[1]);
}

// Overwrites the big-endian num_joints of an encoded message.
void set_num_joints(std::vector<std::uint8_t>& bytes, std::int32_t n) {
  const auto u = static_cast<std::uint32_t>(n);
  for (int i = 0; i < 4; ++i)
    bytes[24 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(u >> (24 - 8 * i));
}

TEST(Decoder, RejectsHostileBytesWithoutCrashingOrAllocatingHuge) {
  std::vector<std::uint8_t> good;
  encode_sample(make_state(1, 2), good);
  Decoder<SlaveStateSample> d;
  SlaveStateSample out;

  auto reason = [&](const std::vector<std::uint8_t>& b) {
    const auto r = d.decode(b.data(), b.size(), out);
    return r ? r->reason : static_cast<RejectReason>(255);
  };

  EXPECT_EQ(reason({}), RejectReason::kDecode) << "empty";
  EXPECT_EQ(reason({good.begin(), good.begin() + 20}), RejectReason::kDecode) << "truncated header";
  EXPECT_EQ(reason({good.begin(), good.end() - 1}), RejectReason::kDecode) << "one byte short";
  auto longer = good;
  longer.push_back(0);
  EXPECT_EQ(reason(longer), RejectReason::kDecode) << "trailing byte";

  auto huge = good;
  set_num_joints(huge, 0x7fffffff);
  EXPECT_EQ(reason(huge), RejectReason::kJointCount) << "2^31-1 joints: must not resize vectors";
  auto negative = good;
  set_num_joints(negative, -1);
  EXPECT_EQ(reason(negative), RejectReason::kJointCount);
  auto zero = good;
  set_num_joints(zero, 0);
  EXPECT_EQ(reason(zero), RejectReason::kJointCount);

  std::vector<std::uint8_t> other;
  MasterCommandSample c;
  c.num_joints = 2;
  encode_sample(c, other);
  const auto r = d.decode(other.data(), other.size(), out);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->reason, RejectReason::kDecode);
  EXPECT_NE(std::string(r->what.data()).find("slave_state_t"), std::string::npos) << r->what.data();

  std::mt19937 rng(7);
  for (int i = 0; i < 2000; ++i) {
    std::vector<std::uint8_t> garbage(rng() % 300);
    for (auto& b : garbage)
      b = static_cast<std::uint8_t>(rng());
    EXPECT_TRUE(d.decode(garbage.data(), garbage.size(), out).has_value()) << "garbage " << i;
  }
  // Valid header, random body of the right length: decodes (content is validate()'s job).
  EXPECT_FALSE(d.decode(good.data(), good.size(), out).has_value());
  EXPECT_EQ(out.seq, 1);
}

TEST(Validation, RejectsNonFiniteAndOutOfRangeNamingTheField) {
  const SlaveStateLimits limits;
  SlaveStateSample s = make_state(3, 4);
  EXPECT_FALSE(validate(s, limits).has_value());

  s.x_out[1] = std::nan("");
  EXPECT_FALSE(validate(s, limits).has_value()) << "x_out NaN: the joint has no encoder";

  s.x_in[1] = std::nan("");
  auto r = validate(s, limits);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->reason, RejectReason::kNonFinite);
  EXPECT_EQ(r->joint, 1);
  r->seq = 3;
  EXPECT_EQ(describe(*r, "ARM1_SLAVE_STATE"),
            "ARM1_SLAVE_STATE seq 3: x_in[1] = nan is not finite");

  s = make_state(3, 4);
  s.x_out[0] = INFINITY;
  ASSERT_TRUE(validate(s, limits).has_value()) << "Inf is never 'not measured'";

  s = make_state(3, 4);
  s.T3[0] = 1e6;
  r = validate(s, limits);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->reason, RejectReason::kOutOfRange);
  EXPECT_STREQ(r->what.data(), "T3");

  s = make_state(3, 4);
  s.radius_m[1] = 0.0;
  r = validate(s, limits);
  ASSERT_TRUE(r.has_value());
  EXPECT_STREQ(r->what.data(), "radius_m");

  // Values beyond num_joints are not looked at.
  s = make_state(3, 4, 1);
  s.x_in[1] = std::nan("");
  EXPECT_FALSE(validate(s, limits).has_value());
}

TEST(Validation, JointCount) {
  EXPECT_FALSE(check_joint_count(2, 0).has_value());
  EXPECT_FALSE(check_joint_count(2, 2).has_value());
  EXPECT_TRUE(check_joint_count(3, 2).has_value());
  EXPECT_TRUE(check_joint_count(0, 0).has_value());
  EXPECT_TRUE(check_joint_count(kMaxJoints + 1, 0).has_value());
}

TEST(Channels, NamesAndRegexEscape) {
  EXPECT_EQ(channel_name("ARM1_", Channel::kSlaveState), "ARM1_SLAVE_STATE");
  EXPECT_EQ(channel_name("", Channel::kHapticStatus), "HAPTIC_STATUS");
  EXPECT_EQ(regex_escape("A.B+C"), "A\\.B\\+C");
  EXPECT_NO_THROW(check_channel_name(std::string(63, 'C')));
  EXPECT_THROW(check_channel_name(std::string(64, 'C')), std::invalid_argument);
  EXPECT_THROW(check_channel_name(""), std::invalid_argument);
}

}  // namespace
}  // namespace tsmh::bridge
