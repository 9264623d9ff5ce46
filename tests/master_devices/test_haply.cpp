// The `haply` driver (Haply 2DIY over its USB serial board): the protocol's
// bytes as hAPI lays them out, the board emulator, and the driver against the
// emulator behind a real pty (handshake, kinematics, force, limits, command
// timeout, the host-side watchdog, unplug, workspace). Real time where the
// driver's I/O thread and the pty must run; waits are bounded and generous,
// and nothing here asserts how fast.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>

#include "driver_rules.hpp"
#include "master_devices/builtin_drivers.hpp"
#include "master_devices/haply_board.hpp"
#include "master_devices/haply_device.hpp"
#include "master_devices/mapped_device.hpp"
#include "pty_board.hpp"

namespace md = tsmh::master_devices;
namespace haply = tsmh::master_devices::haply;
using md::testing::PtyBoard;
using md::testing::wait_until;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::vector<std::uint8_t> floats(std::initializer_list<float> v) {
  std::vector<std::uint8_t> out;
  for (float f : v) {
    std::uint8_t b[4];
    haply::put_float(b, f);
    out.insert(out.end(), b, b + 4);
  }
  return out;
}

std::vector<std::uint8_t> cat(std::vector<std::uint8_t> a, const std::vector<std::uint8_t>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace

// ---- protocol ----

TEST(HaplyProtocol, FloatsAreLittleEndianIeee) {
  std::uint8_t b[4];
  haply::put_float(b, 1.0f);  // 0x3f800000
  EXPECT_EQ(b[0], 0x00);
  EXPECT_EQ(b[1], 0x00);
  EXPECT_EQ(b[2], 0x80);
  EXPECT_EQ(b[3], 0x3f);
  EXPECT_EQ(haply::get_float(b), 1.0f);
}

TEST(HaplyProtocol, SetupFramesAreHapisLayout) {
  // gen3: actuator 1 CW on port 2, actuator 2 CW on port 1; encoder 1 CCW,
  // offset 180, 4880 counts, port 2; encoder 2 CCW, offset 0, port 1. The
  // board reads ports in order: port 1 (joint 2) first.
  const auto gen3 = haply::encode_setup(haply::board_preset("gen3"));
  const auto want3 =
      cat({1, 5, 0x03, 0, 0, 0x03, 1, 1, 0, 0}, floats({0.f, 4880.f, 180.f, 4880.f}));
  EXPECT_EQ(gen3, want3);
  // gen2: actuator 1 CCW port 2, actuator 2 CW port 1; encoders 241 / -61 deg, 10752 counts.
  const auto gen2 = haply::encode_setup(haply::board_preset("gen2"));
  const auto want2 =
      cat({1, 5, 0x03, 0, 1, 0x03, 0, 1, 0, 0}, floats({-61.f, 10752.f, 241.f, 10752.f}));
  EXPECT_EQ(gen2, want2);
  EXPECT_EQ(haply::encode_reset(), (std::vector<std::uint8_t>{0, 0}));
}

TEST(HaplyProtocol, StateCarriesTorquesInPortOrderAndRepliesDecodeToJoints) {
  const auto c = haply::board_preset("gen3");
  std::uint8_t f[haply::kMaxFrame];
  md::JointArray tau{};
  tau[0] = 0.05;  // joint 0 sits on port 2
  tau[1] = -0.02;
  ASSERT_EQ(haply::encode_state(c, tau, f), 10U);
  EXPECT_EQ(std::vector<std::uint8_t>(f, f + 10), cat({2, 5}, floats({-0.02f, 0.05f})));
  tau[0] = std::nan("");
  haply::encode_state(c, tau, f);
  EXPECT_EQ(haply::get_float(f + 6), 0.0f) << "a NaN torque goes out as 0";

  const auto reply = cat({5}, floats({12.5f, 170.0f}));  // port 1 (joint 1), port 2 (joint 0)
  md::JointArray deg{};
  ASSERT_EQ(haply::decode_reply(c, reply.data(), reply.size(), deg), haply::ReplyError::kNone);
  EXPECT_FLOAT_EQ(deg[0], 170.0);
  EXPECT_FLOAT_EQ(deg[1], 12.5);
}

TEST(HaplyProtocol, MalformedRepliesAreRejectedAndLeaveTheAnglesAlone) {
  const auto c = haply::board_preset("gen3");
  md::JointArray deg{};
  deg[0] = 7.0;
  auto good = cat({5}, floats({1.f, 2.f}));
  EXPECT_EQ(haply::decode_reply(c, good.data(), good.size() - 1, deg),
            haply::ReplyError::kWrongLength);
  auto other = good;
  other[0] = 6;
  EXPECT_EQ(haply::decode_reply(c, other.data(), other.size(), deg),
            haply::ReplyError::kWrongDeviceId);
  auto nan = cat({5}, floats({1.f, std::numeric_limits<float>::infinity()}));
  EXPECT_EQ(haply::decode_reply(c, nan.data(), nan.size(), deg), haply::ReplyError::kNotFinite);
  EXPECT_EQ(deg[0], 7.0);
}

TEST(HaplyProtocol, WiringErrorsNameTheJoint) {
  auto c = haply::board_preset("gen3");
  c.wiring[1].port = 2;
  EXPECT_EQ(haply::validate(c), "joint 1: port 2 is also joint 0's");
  c.wiring[1].port = 5;
  EXPECT_EQ(haply::validate(c), "joint 1: port 5 is not 1..4");
  EXPECT_THROW(haply::board_preset("gen9"), std::invalid_argument);
}

// ---- the board emulator ----

TEST(HaplyBoard, AnswersWithQuantizedAnglesAndLimitsTorquesAsTheFirmware) {
  haply::BoardEmulator board;
  const auto c = haply::board_preset("gen3");
  std::vector<std::uint8_t> out;
  const auto setup = haply::encode_setup(c);
  board.receive(setup.data(), setup.size(), out);
  ASSERT_TRUE(board.configured());
  EXPECT_TRUE(out.empty()) << "setup is not answered";
  board.set_port_angles({30.0 * kDeg, 150.0 * kDeg, 0, 0});
  md::JointArray tau{};
  tau[0] = 0.3;  // joint 0 -> port 2: above the firmware's 0.123 N m
  tau[1] = -0.1;
  std::uint8_t f[haply::kMaxFrame];
  const std::size_t n = haply::encode_state(c, tau, f);
  // Split across two writes: the board reads a stream, not packets.
  board.receive(f, 3, out);
  EXPECT_TRUE(out.empty());
  board.receive(f + 3, n - 3, out);
  md::JointArray deg{};
  ASSERT_EQ(haply::decode_reply(c, out.data(), out.size(), deg), haply::ReplyError::kNone);
  EXPECT_NEAR(deg[0], 150.0, 360.0 / 4880.0);
  EXPECT_NEAR(deg[1], 30.0, 360.0 / 4880.0);
  // Both scaled by 0.123 / 0.3: the direction of the force is kept.
  EXPECT_NEAR(board.port_torques()[1], 0.123, 1e-6);
  EXPECT_NEAR(board.port_torques()[0], -0.1 * 0.123 / 0.3, 1e-6);
}

// ---- the driver over a pty ----

namespace {

YAML::Node settings_for(const PtyBoard& board, const std::string& extra = "") {
  return YAML::Load("{port: " + board.path() + extra + "}");
}

std::unique_ptr<md::Device> make(const YAML::Node& settings) {
  md::DriverRegistry registry;
  md::register_builtin_drivers(registry);
  md::DriverContext ctx;
  ctx.source = "server.yaml";
  ctx.path = "device.settings";
  return registry.create("haply", settings, ctx);
}

// A pose in the middle of the gen3 workspace, on whole encoder counts (813 of
// 4880 from the offsets 0 and 180 deg), so the board reports it exactly.
constexpr double kMidDeg = 813.0 * 360.0 / 4880.0;  // 59.98 deg
const std::array<double, haply::kPorts> kMidPorts{kMidDeg * kDeg, (180.0 - kMidDeg) * kDeg, 0, 0};

md::DeviceReading fresh_reading(md::Device& d) {
  md::DeviceReading r;
  wait_until([&] {
    r = d.read(md::monotonic_clock()->now_ns());
    return r.fresh && r.status == md::DeviceStatus::kOk;
  });
  return r;
}

}  // namespace

TEST(HaplyDriver, HandshakeSetsUpTheBoardAndReadsItsAngles) {
  PtyBoard board;
  board.with([](haply::BoardEmulator& b) { b.set_port_angles(kMidPorts); });
  auto dev = make(settings_for(board));
  dev->open();
  board.with([](haply::BoardEmulator& b) {
    EXPECT_GE(b.resets(), 1U);
    EXPECT_EQ(b.last_setup_frame(), haply::encode_setup(haply::board_preset("gen3")));
  });
  EXPECT_EQ(dev->spec().driver, "haply");
  EXPECT_EQ(dev->spec().model, "haply-2diy");
  const md::DeviceReading r = fresh_reading(*dev);
  ASSERT_EQ(r.status, md::DeviceStatus::kOk);
  EXPECT_FALSE(r.enabled) << "comes up disabled";
  EXPECT_NEAR(r.q[0], (180.0 - kMidDeg) * kDeg, 1e-6);  // joint 0 on port 2
  EXPECT_NEAR(r.q[1], kMidDeg * kDeg, 1e-6);
  const auto seq = r.sequence;
  ASSERT_TRUE(
      wait_until([&] { return dev->read(md::monotonic_clock()->now_ns()).sequence > seq + 20; }));
  dev->close();
}

TEST(HaplyDriver, ABoardThatNeverAnswersIsAnOpenErrorNamingThePort) {
  PtyBoard board;
  board.with([](haply::BoardEmulator& b) { b.set_silent(true); });
  auto dev = make(settings_for(board, ", open_timeout_ms: 200"));
  try {
    dev->open();
    FAIL() << "open() succeeded without a reply";
  } catch (const md::DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find(board.path()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("did not answer within 200 ms"), std::string::npos)
        << e.what();
  }
}

TEST(HaplyDriver, AHandleFarOutsideTheWorkspaceIsRefusedAtOpen) {
  PtyBoard board;
  // Elbows crossed: the handle below the motors, 7 cm under the workspace.
  board.with([](haply::BoardEmulator& b) { b.set_port_angles({180.0 * kDeg, 0.0, 0, 0}); });
  auto dev = make(settings_for(board));
  try {
    dev->open();
    FAIL() << "open() accepted a handle outside the workspace";
  } catch (const md::DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("outside haply-2diy's workspace"), std::string::npos)
        << e.what();
  }
}

TEST(HaplyDriver, TorqueIsZeroWhileDisabledClampedWhenEnabledAndZeroAfterTheCommandTimeout) {
  PtyBoard board;
  board.with([](haply::BoardEmulator& b) { b.set_port_angles(kMidPorts); });
  auto dev = make(settings_for(board, ", command_timeout_ms: 50"));
  dev->open();
  auto port_torque = [&](std::size_t port) {
    return board.with([&](haply::BoardEmulator& b) { return b.port_torques()[port - 1]; });
  };
  md::JointArray tau{};
  tau[0] = 0.05;
  tau[1] = -5.0;  // far above the profile's 0.1 N m
  fresh_reading(*dev);
  dev->write_torque(tau);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the I/O thread runs
  EXPECT_EQ(port_torque(2), 0.0) << "disabled: nothing reaches the motors";
  dev->set_enabled(true);
  fresh_reading(*dev);
  // Keep commanding (the loop would, every ms) until the board has it.
  ASSERT_TRUE(wait_until([&] {
    dev->read(md::monotonic_clock()->now_ns());
    dev->write_torque(tau);
    return std::abs(port_torque(2) - 0.05) < 1e-6 && std::abs(port_torque(1) + 0.1) < 1e-6;
  })) << port_torque(2)
      << " " << port_torque(1);
  // The loop stops calling write_torque(): after the command timeout the board gets zero.
  ASSERT_TRUE(wait_until([&] { return port_torque(1) == 0.0 && port_torque(2) == 0.0; }));
  // close() leaves the board with zero torque too.
  ASSERT_TRUE(wait_until([&] {
    dev->read(md::monotonic_clock()->now_ns());
    dev->write_torque(tau);
    return port_torque(2) != 0.0;
  }));
  dev->close();
  EXPECT_EQ(port_torque(1), 0.0);
  EXPECT_EQ(port_torque(2), 0.0);
}

TEST(HaplyDriver, NoCommandEverReachesTheBoardAboveTheProfilesLimit) {
  PtyBoard board;
  board.with([](haply::BoardEmulator& b) { b.set_port_angles(kMidPorts); });
  auto dev = make(settings_for(board));
  dev->open();
  dev->set_enabled(true);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1e6, 1e6);
  const double specials[] = {std::nan(""), std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(), 1e300};
  for (int i = 0; i < 300; ++i) {
    dev->read(md::monotonic_clock()->now_ns());
    md::JointArray tau{};
    tau[0] = i % 7 == 0 ? specials[i % 4] : u(rng);
    tau[1] = u(rng);
    dev->write_torque(tau);
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  const double largest =
      board.with([](haply::BoardEmulator& b) { return b.largest_requested_nm(); });
  EXPECT_GT(largest, 0.09) << "torque did reach the board";
  EXPECT_LE(largest, 0.1 + 1e-6);
  dev->close();
}

TEST(HaplyDriver, ThroughItsMappingTheForceIsTheJacobianTransposeOfTheSlaveTorque) {
  PtyBoard board;
  board.with([](haply::BoardEmulator& b) { b.set_port_angles(kMidPorts); });
  // x -> slave joint 0 at 10 rad/m, y -> slave joint 1 at -8 rad/m.
  auto dev = make(settings_for(board,
                               ", mapping: {joints: [{axis: x, scale: 10}, {axis: y, scale: -8}], "
                               "buttons: {dead_man: held}}"));
  auto* mapped = dynamic_cast<md::MappedDevice*>(dev.get());
  ASSERT_NE(mapped, nullptr);
  EXPECT_EQ(dev->spec().dof, 2U);
  EXPECT_NEAR(dev->spec().peak_torque_nm[0], 3.0 / 10, 1e-12);  // force limit / |scale|
  dev->open();
  dev->set_enabled(true);
  const md::DeviceReading r = fresh_reading(*dev);
  EXPECT_TRUE(r.buttons.dead_man) << "dead_man: held";

  // Independent of the driver: the handle from the reported motor angles.
  const md::MasterProfile profile = md::builtin_haply_profile("haply-2diy");
  md::JointArray q{}, x{};
  md::Jacobian J{};
  q[0] = (180.0 - kMidDeg) * kDeg;
  q[1] = kMidDeg * kDeg;
  ASSERT_TRUE(md::forward_kinematics(profile.kinematics, q, x, J));
  const double cx = 0.5 * (profile.workspace_min[0] + profile.workspace_max[0]);
  const double cy = 0.5 * (profile.workspace_min[1] + profile.workspace_max[1]);
  EXPECT_NEAR(r.q[0], 10.0 * (x[0] - cx), 1e-6);
  EXPECT_NEAR(r.q[1], -8.0 * (x[1] - cy), 1e-6);

  md::JointArray tau_slave{};
  tau_slave[0] = 0.01;
  tau_slave[1] = 0.02;
  auto port_torques = [&] {
    return board.with([](haply::BoardEmulator& b) { return b.port_torques(); });
  };
  ASSERT_TRUE(wait_until([&] {
    dev->read(md::monotonic_clock()->now_ns());
    dev->write_torque(tau_slave);
    return port_torques()[1] != 0.0;
  }));
  const auto pt = port_torques();
  const double tau_m0 = pt[1], tau_m1 = pt[0];  // joint 0 on port 2, joint 1 on port 1
  // Virtual work, by finite differences of the forward kinematics alone:
  // for a small motor motion dq, tau_motor . dq = tau_slave . dv.
  for (int axis = 0; axis < 2; ++axis) {
    const double h = 1e-6;
    md::JointArray q2 = q, x2{};
    q2[static_cast<std::size_t>(axis)] += h;
    ASSERT_TRUE(md::forward_kinematics(profile.kinematics, q2, x2, J));
    const double dv0 = 10.0 * (x2[0] - x[0]), dv1 = -8.0 * (x2[1] - x[1]);
    const double motor_work = (axis == 0 ? tau_m0 : tau_m1) * h;
    const double slave_work = tau_slave[0] * dv0 + tau_slave[1] * dv1;
    // Torques cross the wire as float32: 1e-6 relative.
    EXPECT_NEAR(motor_work, slave_work, 1e-5 * std::abs(slave_work)) << "motor " << axis;
  }
  dev->close();
}

TEST(HaplyDriver, WatchdogZeroesTorqueWhileTheBoardIsSilentAndResumesWhenItAnswers) {
  PtyBoard board;
  board.with([](haply::BoardEmulator& b) { b.set_port_angles(kMidPorts); });
  auto dev = make(settings_for(board, ", watchdog_ms: 20, command_timeout_ms: 1000"));
  dev->open();
  dev->set_enabled(true);
  md::JointArray tau{};
  tau[0] = 0.05;
  auto torque = [&] {
    return board.with([](haply::BoardEmulator& b) { return b.port_torques()[1]; });
  };
  ASSERT_TRUE(wait_until([&] {
    dev->read(md::monotonic_clock()->now_ns());
    dev->write_torque(tau);
    return torque() > 0.04;
  }));
  // The board stops answering but still takes commands (its replies are lost).
  board.with([](haply::BoardEmulator& b) { b.set_silent(true); });
  md::DeviceReading r;
  ASSERT_TRUE(wait_until([&] {
    r = dev->read(md::monotonic_clock()->now_ns());
    dev->write_torque(tau);
    return r.status == md::DeviceStatus::kDisconnected && torque() == 0.0;
  })) << md::to_string(r.status)
      << " torque " << torque();
  EXPECT_TRUE(r.stale);
  EXPECT_EQ(r.tau_commanded[0], 0.0);
  // Answers again: OK, and torque flows again without re-enabling.
  board.with([](haply::BoardEmulator& b) { b.set_silent(false); });
  ASSERT_TRUE(wait_until([&] {
    r = dev->read(md::monotonic_clock()->now_ns());
    dev->write_torque(tau);
    return r.status == md::DeviceStatus::kOk && torque() > 0.04;
  }));
  dev->close();
}

TEST(HaplyDriver, UnplugIsAFaultWithAClearErrorAndNoTorque) {
  PtyBoard board;
  board.with([](haply::BoardEmulator& b) { b.set_port_angles(kMidPorts); });
  auto dev = make(settings_for(board));
  dev->open();
  dev->set_enabled(true);
  fresh_reading(*dev);
  board.unplug();
  md::DeviceReading r;
  ASSERT_TRUE(wait_until([&] {
    r = dev->read(md::monotonic_clock()->now_ns());
    md::JointArray tau{};
    tau[0] = 0.05;
    dev->write_torque(tau);
    return r.status == md::DeviceStatus::kFault;
  }));
  EXPECT_EQ(r.fault, md::FaultCode::kLinkLost);
  EXPECT_FALSE(r.enabled);
  EXPECT_EQ(r.tau_commanded[0], 0.0);
  const std::string err = dev->last_error();
  EXPECT_NE(err.find(board.path()), std::string::npos) << err;
  EXPECT_NE(err.find("unplugged?"), std::string::npos) << err;
  EXPECT_FALSE(dev->clear_fault()) << "the board is still gone";
  EXPECT_EQ(dev->status(), md::DeviceStatus::kFault);
  dev->close();
}

TEST(HaplyDriver, KeepsTheSharedFaultRules) {
  PtyBoard board;
  board.with([](haply::BoardEmulator& b) { b.set_port_angles(kMidPorts); });
  auto dev = make(settings_for(board));
  dev->open();
  fresh_reading(*dev);
  md::testing::expect_shared_fault_rules(
      {*dev, [] { return md::monotonic_clock()->now_ns(); },
       [&] { return board.with([](haply::BoardEmulator& b) { return b.port_torques()[1]; }); },
       [] { std::this_thread::sleep_for(std::chrono::milliseconds(1)); }},
      0.05);
  dev->close();
}

TEST(HaplyDriver, AHandleThatLeavesTheWorkspaceFaultsUntilItIsBack) {
  PtyBoard board;
  board.with([](haply::BoardEmulator& b) { b.set_port_angles(kMidPorts); });
  auto dev = make(settings_for(board));
  dev->open();
  board.with([](haply::BoardEmulator& b) { b.set_port_angles({180.0 * kDeg, 0.0, 0, 0}); });
  ASSERT_TRUE(wait_until([&] { return dev->status() == md::DeviceStatus::kFault; }));
  EXPECT_EQ(dev->read(md::monotonic_clock()->now_ns()).fault, md::FaultCode::kWorkspace);
  EXPECT_FALSE(dev->clear_fault());
  board.with([](haply::BoardEmulator& b) { b.set_port_angles(kMidPorts); });
  // The I/O thread keeps sampling while faulted.
  ASSERT_TRUE(wait_until([&] { return dev->clear_fault(); }));
  EXPECT_EQ(dev->status(), md::DeviceStatus::kOk);
  dev->close();
}

TEST(HaplyDriver, SettingsErrorsNameTheField) {
  auto error_of = [](const std::string& yaml) {
    try {
      make(YAML::Load(yaml));
    } catch (const tsmh::config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of("{profile: haply-2diy}").find("server.yaml: device.settings.port: missing"),
            std::string::npos);
  EXPECT_NE(error_of("{port: /dev/null, board: gen9}").find("device.settings.board: 'gen9'"),
            std::string::npos);
  EXPECT_NE(error_of("{port: /dev/null, profile: falcon}").find("device.settings.profile"),
            std::string::npos);
  EXPECT_NE(error_of("{port: /dev/null, watchdog_ms: 20, wathdog_ms: 5}").find("wathdog_ms"),
            std::string::npos);
  EXPECT_NE(error_of("{port: /dev/null, mapping: {joints: [{axis: z}]}}")
                .find("device.settings.mapping.joints[0].axis: 'z' is not an axis of haply-2diy"),
            std::string::npos);
}

TEST(HaplyDriver, OpeningAMissingPortSaysWhatToCheck) {
  auto dev = make(YAML::Load("{port: /dev/ttyACM-none}"));
  try {
    dev->open();
    FAIL();
  } catch (const md::DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/ttyACM-none: cannot open"), std::string::npos)
        << e.what();
  }
}

TEST(HaplyDriver, TheBuiltInProfilesAreTheShippedFiles) {
  for (const char* name : {"haply-2diy", "haply-2diy-gen2"}) {
    const auto file = md::load_master_profile(std::string(TSMH_SOURCE_DIR) +
                                              "/master_devices/profiles/masters/" + name + ".yaml");
    const auto builtin = md::builtin_haply_profile(name);
    EXPECT_EQ(builtin.name, file.name);
    EXPECT_EQ(builtin.kinematics.pantograph.d_m, file.kinematics.pantograph.d_m);
    EXPECT_EQ(builtin.workspace_max, file.workspace_max);
    EXPECT_EQ(builtin.joint_torque_limit_nm, file.joint_torque_limit_nm);
  }
}

TEST(HaplyDriver, ListsCdcAcmPortsWithTheirUsbIds) {
  const auto root =
      std::filesystem::temp_directory_path() / ("haply-sysfs-" + std::to_string(::getpid()));
  std::filesystem::remove_all(root);
  const auto usb = root / "devices/pci0000:00/usb1/1-1";
  std::filesystem::create_directories(usb / "1-1:1.0");
  auto put = [&](const char* f, const char* v) { std::ofstream(usb / f) << v << "\n"; };
  put("idVendor", "2341");
  put("idProduct", "804d");
  put("manufacturer", "Arduino LLC");
  put("product", "Arduino Zero");
  std::filesystem::create_directories(root / "class/tty/ttyS0");
  std::filesystem::create_directories(root / "class/tty/ttyACM0");
  std::filesystem::create_directory_symlink(usb / "1-1:1.0", root / "class/tty/ttyACM0/device");
  const auto found = md::list_serial_boards(root);
  std::filesystem::remove_all(root);
  ASSERT_EQ(found.size(), 1U);
  EXPECT_EQ(found[0].driver, "haply");
  EXPECT_EQ(found[0].path, "/dev/ttyACM0");
  EXPECT_EQ(found[0].vendor_id, 0x2341);
  EXPECT_EQ(found[0].product_id, 0x804d);
  EXPECT_EQ(found[0].product, "Arduino LLC Arduino Zero");
}
