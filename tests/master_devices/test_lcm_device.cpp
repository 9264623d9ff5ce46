// The lcm driver against an "external driver" in the same process, over an
// in-memory LCM provider (memq://), so no network or multicast route is needed.
// Host time is a ManualClock: timeouts are tested by advancing it, exactly.
// The only real waits are for the device's LCM thread to answer a message.

#include <gtest/gtest.h>

#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <mutex>
#include <thread>
#include <tsmh/master_force_t.hpp>
#include <tsmh/master_state_t.hpp>
#include <vector>

#include "driver_rules.hpp"
#include "master_devices/clock.hpp"
#include "master_devices/lcm_device.hpp"

namespace tsmh::master_devices {
namespace {

using namespace std::chrono_literals;

struct ForceLog {
  std::mutex mutex;
  std::vector<tsmh::master_force_t> forces;
  void on_force(const lcm::ReceiveBuffer*, const std::string&, const tsmh::master_force_t* msg) {
    std::lock_guard lock(mutex);
    forces.push_back(*msg);
  }
  tsmh::master_force_t last() {
    std::lock_guard lock(mutex);
    return forces.empty() ? tsmh::master_force_t{} : forces.back();
  }
  std::size_t count() {
    std::lock_guard lock(mutex);
    return forces.size();
  }
};

struct Rig {
  std::shared_ptr<ManualClock> clock = std::make_shared<ManualClock>();
  std::shared_ptr<lcm::LCM> lcm = std::make_shared<lcm::LCM>("memq://");
  ForceLog log;
  std::unique_ptr<LcmDevice> device;
  std::int64_t seq = 0;

  explicit Rig(LcmSettings s = {}) {
    if (s.peak_torque_nm[0] == 0.0) {
      for (std::size_t j = 0; j < s.dof; ++j) {
        s.peak_torque_nm[j] = 0.3;
        s.continuous_torque_nm[j] = 0.15;
        s.position_min_rad[j] = -1;
        s.position_max_rad[j] = 1;
      }
    }
    lcm->subscribe(s.force_channel(), &ForceLog::on_force, &log);
    device = std::make_unique<LcmDevice>(s, lcm, clock);
    device->open();
  }

  std::int64_t now() const { return clock->now_ns(); }

  // Publishes a MASTER_STATE and waits until the device's LCM thread has
  // answered it (real sleeps: that thread must run).
  void send_state(double q0, double q1, int buttons = 1, int status = 0, int num_joints = 2) {
    tsmh::master_state_t m;
    m.utime = now() / 1000;
    m.seq = seq++;
    m.num_joints = num_joints;
    m.q.assign(static_cast<std::size_t>(num_joints), 0.0);
    m.qd.assign(static_cast<std::size_t>(num_joints), 0.0);
    m.q[0] = q0;
    if (num_joints > 1) m.q[1] = q1;
    m.buttons = buttons;
    m.status = status;
    const std::size_t before = log.count();
    const std::uint64_t rejected = device->rejected_messages();
    lcm->publish(device_state_channel, &m);
    for (int i = 0; i < 500 && log.count() == before && device->rejected_messages() == rejected;
         ++i) {
      std::this_thread::sleep_for(1ms);
    }
  }
  std::string device_state_channel = "MASTER_STATE";
};

TEST(LcmDevice, StateInForceOut) {
  Rig rig;
  rig.send_state(0.25, -0.5, /*dead-man + clutch*/ 5);
  DeviceReading r = rig.device->read(rig.now());
  EXPECT_EQ(r.status, DeviceStatus::kOk);
  EXPECT_DOUBLE_EQ(r.q[0], 0.25);
  EXPECT_DOUBLE_EQ(r.q[1], -0.5);
  EXPECT_TRUE(r.buttons.dead_man);
  EXPECT_TRUE(r.buttons.clutch);
  EXPECT_FALSE(r.buttons.e_stop);
  // Disabled: the answer carries zero torque and enable = false.
  tsmh::master_force_t f = rig.log.last();
  EXPECT_EQ(f.num_joints, 2);
  EXPECT_FALSE(f.enable);
  EXPECT_EQ(f.torque[0], 0.0);

  rig.device->set_enabled(true);
  rig.device->write_torque(JointArray{0.1, 9.0});
  rig.send_state(0.25, -0.5);
  f = rig.log.last();
  EXPECT_TRUE(f.enable);
  EXPECT_DOUBLE_EQ(f.torque[0], 0.1);
  EXPECT_DOUBLE_EQ(f.torque[1], 0.3) << "clamped to peak";
  r = rig.device->read(rig.now());
  EXPECT_TRUE(r.enabled);
  EXPECT_DOUBLE_EQ(r.tau_commanded[1], 0.3);
}

TEST(LcmDevice, NamesItsJointsJoint1AndJoint2) {
  Rig rig;
  EXPECT_EQ(rig.device->spec().joint_names[0], "joint1");
  EXPECT_EQ(rig.device->spec().joint_names[1], "joint2");
}

TEST(LcmDevice, RejectsMalformedStateMessages) {
  Rig rig;
  rig.send_state(0.1, 0.1, 1, 0, /*num_joints*/ 3);
  EXPECT_EQ(rig.device->rejected_messages(), 1u);
  EXPECT_NE(rig.device->last_error().find("MASTER_STATE: num_joints 3, expected 2"),
            std::string::npos)
      << rig.device->last_error();
  rig.send_state(std::nan(""), 0.1);
  EXPECT_EQ(rig.device->rejected_messages(), 2u);
  rig.send_state(0.1, 0.1, 0x10);
  EXPECT_EQ(rig.device->rejected_messages(), 3u);
  EXPECT_EQ(rig.device->read(rig.now()).status, DeviceStatus::kDisconnected)
      << "nothing valid received yet";
}

// The lcm driver is the one place MASTER_STATE is checked after decoding
// (lcmtypes' decoder does the bytes): bytes that are no master_state_t, and
// non-finite angles or velocities, are counted, named in last_error() and
// never answered.
TEST(LcmDevice, RejectsUndecodableAndNonFiniteStateAndNamesWhy) {
  Rig rig;
  const std::uint8_t garbage[5] = {1, 2, 3, 4, 5};
  rig.lcm->publish(rig.device_state_channel, garbage, sizeof garbage);
  for (int i = 0; i < 500 && rig.device->rejected_messages() == 0; ++i)
    std::this_thread::sleep_for(1ms);
  EXPECT_EQ(rig.device->rejected_messages(), 1u);
  EXPECT_NE(rig.device->last_error().find("MASTER_STATE: truncated: 5 bytes, the header needs 28"),
            std::string::npos)
      << rig.device->last_error();

  rig.send_state(0.1, std::numeric_limits<double>::infinity());
  EXPECT_EQ(rig.device->rejected_messages(), 2u);
  EXPECT_NE(rig.device->last_error().find("q[1] or qd[1] is not finite"), std::string::npos)
      << rig.device->last_error();
  EXPECT_EQ(rig.log.count(), 0u) << "a rejected MASTER_STATE is never answered";
}

// A 2-joint body whose num_joints says 2^28: lcm-gen's decode() resized q and
// qd to 2^28 doubles (2 GiB each) on the driver's thread, and haptic-server
// died. Refused from the raw bytes, counted, named, never answered; the next
// good message is used.
TEST(LcmDevice, AMasterStateClaiming2pow28JointsIsRefusedFromItsRawBytes) {
  Rig rig;
  tsmh::master_state_t m;
  m.num_joints = 2;
  m.q.assign(2, 0.5);
  m.qd.assign(2, 0.0);
  m.buttons = 1;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  bytes[24] = 0x10;  // num_joints, big-endian at 24..27: 0x10000000
  bytes[27] = 0x00;
  rig.lcm->publish(rig.device_state_channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  for (int i = 0; i < 500 && rig.device->rejected_messages() == 0; ++i)
    std::this_thread::sleep_for(1ms);
  EXPECT_EQ(rig.device->rejected_messages(), 1u);
  EXPECT_EQ(rig.device->last_rejection(), "MASTER_STATE: num_joints 268435456, expected 2");
  EXPECT_EQ(rig.log.count(), 0u);
  rig.send_state(0.25, 0.0);
  EXPECT_EQ(rig.log.count(), 1u);
  EXPECT_DOUBLE_EQ(rig.device->read(rig.now()).q[0], 0.25);
}

// The url setting is read by the one strict LCM URL parser: LCM would send
// this one with TTL 1.
TEST(LcmDevice, AnAmbiguousUrlIsASettingsError) {
  DriverRegistry registry;
  register_lcm_driver(registry);
  try {
    registry.create("lcm", YAML::Load("url: 'udpm://239.255.76.67:7667?ttl=0&ttl=1'\n"),
                    DriverContext{"server.yaml", "device.settings", {}});
    FAIL();
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("device.settings.url"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("option 'ttl' is given twice"), std::string::npos)
        << e.what();
  }
}

TEST(LcmDevice, ExternalFaultLatchesAndStaleStateDisconnects) {
  LcmSettings s;
  s.stale_timeout_ms = 200;
  Rig rig(s);
  rig.device->set_enabled(true);
  rig.device->write_torque(JointArray{0.1, 0.1});
  rig.send_state(0, 0, 1, /*fault*/ 1);
  EXPECT_EQ(rig.device->status(), DeviceStatus::kFault);
  EXPECT_FALSE(rig.log.last().enable);
  EXPECT_TRUE(rig.device->clear_fault());
  rig.send_state(0, 0);
  EXPECT_EQ(rig.device->read(rig.now()).status, DeviceStatus::kOk);
  rig.clock->advance(200'000'000);  // MASTER_STATE stops
  EXPECT_EQ(rig.device->read(rig.now()).status, DeviceStatus::kOk) << "200 ms: within the bound";
  rig.clock->advance(1'000'000);
  EXPECT_EQ(rig.device->read(rig.now()).status, DeviceStatus::kDisconnected);
}

TEST(LcmDevice, CommandsOlderThanTheTimeoutAreAnsweredWithZero) {
  LcmSettings s;
  s.command_timeout_ms = 20;
  s.stale_timeout_ms = 2000;  // not what this test is about
  Rig rig(s);
  rig.device->set_enabled(true);
  rig.device->write_torque(JointArray{0.1, -0.1});
  rig.send_state(0, 0);
  EXPECT_TRUE(rig.log.last().enable);
  EXPECT_DOUBLE_EQ(rig.log.last().torque[0], 0.1);
  rig.clock->advance(20'000'000);  // the loop stops writing
  rig.send_state(0, 0);
  EXPECT_DOUBLE_EQ(rig.log.last().torque[0], 0.1) << "exactly 20 ms old still drives";
  rig.clock->advance(1'000'000);
  rig.send_state(0, 0);
  EXPECT_FALSE(rig.log.last().enable);
  EXPECT_EQ(rig.log.last().torque[0], 0.0);
  EXPECT_EQ(rig.log.last().torque[1], 0.0);
  EXPECT_EQ(rig.device->read(rig.now()).tau_commanded[0], 0.0);
}

TEST(LcmDevice, ChannelPrefixAndRegistration) {
  LcmSettings s;
  s.channel_prefix = "LEFT_";
  EXPECT_EQ(s.state_channel(), "LEFT_MASTER_STATE");
  EXPECT_EQ(s.force_channel(), "LEFT_MASTER_FORCE");
  Rig rig(s);
  rig.device_state_channel = "LEFT_MASTER_STATE";
  rig.send_state(0.3, 0.0);
  EXPECT_DOUBLE_EQ(rig.device->read(rig.now()).q[0], 0.3);

  DriverRegistry registry;
  register_lcm_driver(registry);
  EXPECT_TRUE(registry.has("lcm"));
  try {
    registry.create("lcm", YAML::Load("dof: 0\n"),
                    DriverContext{"server.yaml", "device.settings", {}});
    FAIL();
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("server.yaml: device.settings.dof: must be 1 .. 8"),
              std::string::npos);
  }
}

// A stand-in for the link key's MAC (haptic-server plugs in the bridge's;
// tests/haptics checks the real one end to end): the trailer is the channel
// name's length and a tag byte, which is enough to see the plumbing refuse
// what does not verify and sign what goes out.
class TagAuth final : public LcmMessageAuth {
 public:
  LcmAuthResult verify(const std::string& channel, const std::uint8_t* data, std::size_t size,
                       std::string& why) noexcept override {
    if (size >= 2 && data[size - 2] == static_cast<std::uint8_t>(channel.size()) &&
        data[size - 1] == kTag)
      return {LcmAuthResult::Verdict::kUse, size - 2};
    why = "no tag";
    return {};
  }
  std::size_t trailer_size() const noexcept override { return 2; }
  void sign(const std::string& channel, const std::uint8_t*, std::size_t,
            std::uint8_t* trailer) noexcept override {
    trailer[0] = static_cast<std::uint8_t>(channel.size());
    trailer[1] = kTag;
  }
  static constexpr std::uint8_t kTag = 0xA5;
};

TEST(LcmDevice, WithAuthOnlyVerifiedStateIsUsedAndForceIsSigned) {
  LcmSettings s;
  s.auth = std::make_shared<TagAuth>();
  Rig rig(s);
  struct RawLog {  // filled by the device's LCM thread
    std::mutex mutex;
    std::vector<std::vector<std::uint8_t>> messages;
  } raw;
  auto* sub = rig.lcm->subscribeFunction<RawLog*>(
      "MASTER_FORCE",
      [](const lcm::ReceiveBuffer* rb, const std::string&, RawLog* out) {
        const auto* p = static_cast<const std::uint8_t*>(rb->data);
        const std::lock_guard lock(out->mutex);
        out->messages.emplace_back(p, p + rb->data_size);
      },
      &raw);
  // Unsigned MASTER_STATE: dropped and counted, never read.
  rig.send_state(0.25, -0.5);
  EXPECT_EQ(rig.device->rejected_messages(), 1u);
  EXPECT_NE(rig.device->last_error().find("MASTER_STATE: not authenticated: no tag"),
            std::string::npos)
      << rig.device->last_error();
  EXPECT_EQ(rig.device->read(realtime::monotonic_now_ns()).status, DeviceStatus::kDisconnected);
  EXPECT_EQ(rig.log.count(), 0u) << "no MASTER_FORCE answers a rejected MASTER_STATE";

  // Signed: used, and the answer carries the trailer after a decodable payload.
  tsmh::master_state_t m{};
  m.utime = realtime::monotonic_now_ns() / 1000;
  m.seq = 1;
  m.num_joints = 2;
  m.q = {0.25, -0.5};
  m.qd = {0.0, 0.0};
  m.buttons = 1;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()) + 2);
  m.encode(bytes.data(), 0, m.getEncodedSize());
  TagAuth().sign("MASTER_STATE", nullptr, 0, bytes.data() + bytes.size() - 2);
  rig.lcm->publish("MASTER_STATE", bytes.data(), static_cast<unsigned>(bytes.size()));
  for (int i = 0; i < 500 && rig.log.count() == 0; ++i)
    std::this_thread::sleep_for(1ms);
  EXPECT_DOUBLE_EQ(rig.device->read(realtime::monotonic_now_ns()).q[0], 0.25);
  ASSERT_EQ(rig.log.count(), 1u) << "typed decoders ignore the trailer";
  rig.device->close();  // its thread handles the shared LCM: stop it before unsubscribing
  rig.lcm->unsubscribe(sub);
  ASSERT_EQ(raw.messages.size(), 1u);
  const auto& f = raw.messages.front();
  ASSERT_GE(f.size(), 2u);
  EXPECT_EQ(f[f.size() - 2], std::string("MASTER_FORCE").size());
  EXPECT_EQ(f[f.size() - 1], TagAuth::kTag);
}

// The session verdicts (haptic-server plugs in the bridge's LinkSession;
// tests/haptics checks the real one end to end): a hello is answered with a
// zero, disabled force and not used; another session faults the device.
class SessionTagAuth final : public LcmMessageAuth {
 public:
  LcmAuthResult verify(const std::string&, const std::uint8_t* data, std::size_t size,
                       std::string& why) noexcept override {
    using Verdict = LcmAuthResult::Verdict;
    if (size < 1) return {};
    switch (data[size - 1]) {
      case kUse:
        return {Verdict::kUse, size - 1};
      case kHello:
        return {Verdict::kHandshake, size - 1};
      case kOther:
        why = "another master session";
        return {Verdict::kOtherSession, 0};
    }
    why = "no tag";
    return {};
  }
  std::size_t trailer_size() const noexcept override { return 1; }
  void sign(const std::string&, const std::uint8_t*, std::size_t,
            std::uint8_t* trailer) noexcept override {
    trailer[0] = kUse;
  }
  static constexpr std::uint8_t kUse = 1, kHello = 2, kOther = 3;
};

void publish_tagged(lcm::LCM& lcm, double q0, std::uint8_t tag) {
  tsmh::master_state_t m{};
  m.num_joints = 2;
  m.q = {q0, 0.0};
  m.qd = {0.0, 0.0};
  m.buttons = 1;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()) + 1);
  m.encode(bytes.data(), 0, m.getEncodedSize());
  bytes.back() = tag;
  lcm.publish("MASTER_STATE", bytes.data(), static_cast<unsigned>(bytes.size()));
}

TEST(LcmDevice, AHelloIsAnsweredButNotUsedAndAnotherSessionFaults) {
  LcmSettings s;
  s.auth = std::make_shared<SessionTagAuth>();
  Rig rig(s);
  rig.device->set_enabled(true);
  rig.device->write_torque({0.2, 0.2});
  publish_tagged(*rig.lcm, 0.4, SessionTagAuth::kHello);
  for (int i = 0; i < 500 && rig.log.count() == 0; ++i)
    std::this_thread::sleep_for(1ms);
  ASSERT_EQ(rig.log.count(), 1u) << "a hello is answered: the master learns our id";
  EXPECT_FALSE(rig.log.last().enable);
  EXPECT_EQ(rig.log.last().torque[0], 0.0);
  EXPECT_EQ(rig.device->read(rig.now()).status, DeviceStatus::kDisconnected)
      << "its content is not used";

  publish_tagged(*rig.lcm, 0.1, SessionTagAuth::kUse);
  for (int i = 0; i < 500 && rig.log.count() == 1; ++i)
    std::this_thread::sleep_for(1ms);
  EXPECT_DOUBLE_EQ(rig.device->read(rig.now()).q[0], 0.1);

  const std::uint64_t rejected = rig.device->rejected_messages();
  publish_tagged(*rig.lcm, 0.9, SessionTagAuth::kOther);
  for (int i = 0; i < 500 && rig.device->rejected_messages() == rejected; ++i)
    std::this_thread::sleep_for(1ms);
  const DeviceReading r = rig.device->read(rig.now());
  EXPECT_EQ(r.status, DeviceStatus::kFault);
  EXPECT_EQ(r.fault, FaultCode::kOtherSession);
  EXPECT_DOUBLE_EQ(r.q[0], 0.1) << "another session's state is never used";
  EXPECT_NE(rig.device->last_error().find("another master session"), std::string::npos);
}

TEST(LcmDevice, KeepsTheSharedFaultRules) {
  Rig rig;
  rig.send_state(0.1, 0.2);
  testing::expect_shared_fault_rules(
      {*rig.device, [&] { return rig.now(); },
       [&] { return rig.log.last().torque.empty() ? 0.0 : rig.log.last().torque[0]; },
       [&] { rig.send_state(0.1, 0.2); }},
      0.05);
}

}  // namespace
}  // namespace tsmh::master_devices
