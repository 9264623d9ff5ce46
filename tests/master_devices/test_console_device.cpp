// The console driver (the code behind `hid`, `usb` and `emulator`) against
// the emulated firmware: handshake, 1 kHz read/write, limits, unplug and
// replug, faults, malformed reports. Manual-paced tests tick the emulator
// one firmware period at a time on the test thread and advance a ManualClock
// (the host time the driver and the bus read) by the same period, so they
// are exact and let time pass without sleeping. Real sleeps remain only
// where a real thread must run: the driver's supervisor reconnecting, the
// emulator's real-time thread (clear_fault() and close() wait for its
// reports), real-time pacing under test.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "driver_rules.hpp"
#include "master_devices/builtin_drivers.hpp"
#include "master_devices/clock.hpp"
#include "master_devices/console_device.hpp"
#include "master_devices/emulator_bus.hpp"

namespace tsmh::master_devices {
namespace {

using namespace std::chrono_literals;

// Timeouts far above any scheduling delay, for tests that are not about
// timeouts (a loaded CI machine may preempt the test for tens of ms).
ConsoleSettings relaxed() {
  ConsoleSettings s;
  s.stale_timeout_ms = 2000;
  s.command_timeout_ms = 2000;
  s.reconnect_interval_ms = 10;
  return s;
}

struct Rig {
  // Manual pacing: simulated host time. Real-time pacing: the real clock,
  // since the emulator's thread then runs in real time.
  std::shared_ptr<ManualClock> manual;
  std::shared_ptr<const Clock> clock;
  std::shared_ptr<EmulatorBus> bus;
  std::unique_ptr<ConsoleDevice> device;

  explicit Rig(ConsoleSettings settings = relaxed(),
               DeviceProfile profile = builtin_console_profile(),
               EmulatorBus::Options options = manual_options()) {
    if (options.pacing == EmulatorBus::Pacing::kManual) {
      manual = std::make_shared<ManualClock>();
      clock = manual;
    } else {
      clock = std::make_shared<MonotonicClock>();
    }
    options.clock = clock;
    bus = std::make_shared<EmulatorBus>(std::move(options));
    device = std::make_unique<ConsoleDevice>("emulator", std::move(profile), std::move(settings),
                                             bus, clock);
  }

  ~Rig() {
    if (manual && device->status() != DeviceStatus::kClosed)
      ticking_while([&] { device->close(); });
  }

  // Runs `f`, which waits in real time for the driver's I/O context
  // (close() for its last report, clear_fault() for the firmware's answer):
  // on a manual bus that context is tick(), so a real thread ticks meanwhile.
  template <class F>
  void ticking_while(F f) {
    std::atomic<bool> done{false};
    std::thread io([&] {
      while (!done) {
        tick();
        std::this_thread::sleep_for(200us);
      }
    });
    f();
    done = true;
    io.join();
  }

  static EmulatorBus::Options manual_options() {
    EmulatorBus::Options o;
    o.pacing = EmulatorBus::Pacing::kManual;
    o.firmware = firmware_for_profile(builtin_console_profile());
    return o;
  }

  std::int64_t now() const { return clock->now_ns(); }
  // Host time passes with no report (manual pacing only).
  void wait(std::chrono::nanoseconds dt) { manual->advance(dt.count()); }
  // One firmware period: host time moves on with the device's, one report.
  void tick() {
    manual->advance(bus->period_ns());
    bus->tick();
  }

  // One loop cycle: the device produces a report (and gets our previous
  // command back), then the loop reads.
  DeviceReading cycle() {
    tick();
    return device->read(now());
  }

  double applied_torque(std::size_t j) {
    double tau = 0;
    bus->with_firmware([&](Firmware& fw) { tau = fw.applied_torque_nm(j); });
    return tau;
  }

  // Cycles until the device is OK again; bounded so a broken reconnect fails
  // instead of hanging. Real sleeps: the supervisor thread reconnects in
  // real time (its reconnect interval is a real wait).
  bool wait_ok(std::chrono::milliseconds limit = 3000ms) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < end) {
      if (cycle().status == DeviceStatus::kOk) return true;
      std::this_thread::sleep_for(1ms);
    }
    return false;
  }
};

TEST(ConsoleDevice, OpensAndProgramsTheProfileIntoTheFirmware) {
  Rig rig;
  rig.device->open();
  EXPECT_EQ(rig.device->status(), DeviceStatus::kOk);
  EXPECT_EQ(rig.device->connected_path(), "emu:0");
  rig.bus->with_firmware([](Firmware& fw) {
    EXPECT_EQ(fw.calibration().watchdog_ms, 50);
    EXPECT_EQ(fw.calibration().current_limit_ma[0], 3000);
    EXPECT_EQ(fw.calibration().current_limit_ma[1], 3000);
  });
  const DeviceReading first = rig.cycle();
  EXPECT_EQ(first.status, DeviceStatus::kOk);
  EXPECT_TRUE(first.fresh);
  EXPECT_EQ(first.sequence, 1u);
  EXPECT_FALSE(first.enabled) << "torque starts disabled";
  EXPECT_EQ(rig.device->spec().dof, 2u);
  EXPECT_EQ(rig.device->spec().driver, "emulator");
}

TEST(ConsoleDevice, ReadsAndWritesEveryCycleAtOneKilohertz) {
  Rig rig;
  rig.device->open();
  rig.device->set_enabled(true);
  std::uint64_t expected_seq = 0;
  int torque_ok = 0;
  int position_ok = 0;
  for (int k = 0; k < 1000; ++k) {
    const DeviceReading r = rig.cycle();
    ASSERT_EQ(r.status, DeviceStatus::kOk) << "cycle " << k;
    ASSERT_TRUE(r.fresh) << "cycle " << k;
    ASSERT_EQ(r.sequence, ++expected_seq);
    // The loop's command of the previous cycle is what the firmware applies now.
    const double cmd = 0.1 * std::sin(2 * 3.141592653589793 * 2.0 * k / 1000.0);
    if (k > 0) {
      const double prev = 0.1 * std::sin(2 * 3.141592653589793 * 2.0 * (k - 1) / 1000.0);
      if (std::abs(rig.applied_torque(0) - prev) < 1e-3 &&
          std::abs(rig.applied_torque(1) + prev) < 1e-3) {
        ++torque_ok;
      }
    }
    double q_true = 0;
    rig.bus->with_firmware([&](Firmware& fw) { q_true = fw.position_rad(0); });
    if (std::abs(r.q[0] - q_true) <= 1.0 / 6518.0) ++position_ok;
    rig.device->write_torque(JointArray{cmd, -cmd});
  }
  EXPECT_EQ(torque_ok, 999);
  EXPECT_EQ(position_ok, 1000);
  const ConsoleStats s = rig.device->stats();
  EXPECT_EQ(s.reports, 1000u);
  EXPECT_EQ(s.lost_reports, 0u);
  EXPECT_EQ(s.bad_reports, 0u);
  EXPECT_EQ(s.outputs_sent, 1000u);
  rig.bus->with_firmware([](Firmware& fw) {
    EXPECT_EQ(fw.stats().output_accepted, 1000u);
    EXPECT_EQ(fw.stats().output_rejected, 0u);
    EXPECT_EQ(fw.stats().watchdog_trips, 0u);
  });
}

TEST(ConsoleDevice, VelocityComesFromTheDeviceClock) {
  Rig rig;
  rig.device->open();
  rig.device->set_enabled(true);
  DeviceReading r;
  for (int k = 0; k < 200; ++k) {
    r = rig.cycle();
    rig.device->write_torque(JointArray{0.01, 0.0});
  }
  double qd_true = 0;
  rig.bus->with_firmware([&](Firmware& fw) { qd_true = fw.velocity_rad_s(0); });
  EXPECT_GT(qd_true, 0.5);
  EXPECT_NEAR(r.qd[0], qd_true, 0.05 * qd_true + 0.05);
}

TEST(ConsoleDevice, NoTorqueWhileDisabledAndTorqueClampedToPeak) {
  Rig rig;
  rig.device->open();
  for (int k = 0; k < 10; ++k) {
    rig.cycle();
    rig.device->write_torque(JointArray{0.2, 0.2});
  }
  EXPECT_EQ(rig.applied_torque(0), 0.0);
  rig.device->set_enabled(true);
  rig.device->write_torque(JointArray{5.0, -5.0});  // far above the 0.3 N m peak
  rig.cycle();
  const DeviceReading r = rig.cycle();
  EXPECT_NEAR(rig.applied_torque(0), 0.3, 1e-6);
  EXPECT_NEAR(rig.applied_torque(1), -0.3, 1e-6);
  EXPECT_NEAR(r.tau_commanded[0], 0.3, 1e-6);
  EXPECT_TRUE(r.enabled);
  rig.device->write_torque(JointArray{std::nan(""), 0.1});
  rig.cycle();
  EXPECT_EQ(rig.applied_torque(0), 0.0) << "NaN commands become zero";
}

TEST(ConsoleDevice, TorqueStopsWhenTheLoopStopsWriting) {
  ConsoleSettings s = relaxed();
  s.command_timeout_ms = 50;
  Rig rig(s);
  rig.device->open();
  rig.device->set_enabled(true);
  rig.device->write_torque(JointArray{0.1, 0.1});
  rig.cycle();
  rig.cycle();
  EXPECT_NEAR(rig.applied_torque(0), 0.1, 1e-6);
  // The loop "hangs": no write_torque() after this one, written 2 ms ago.
  rig.wait(47ms);
  rig.cycle();
  EXPECT_NEAR(rig.applied_torque(0), 0.1, 1e-6) << "a command exactly 50 ms old still drives";
  rig.cycle();
  EXPECT_EQ(rig.applied_torque(0), 0.0) << "51 ms old: past command_timeout_ms";
}

TEST(ConsoleDevice, UnplugIsDetectedWithinOneCycleWithZeroTorqueAndReplugRecovers) {
  ConsoleSettings s = relaxed();
  s.reconnect_interval_ms = 10;
  Rig rig(s);
  rig.device->open();
  rig.device->set_enabled(true);
  for (int k = 0; k < 500; ++k) {
    ASSERT_EQ(rig.cycle().status, DeviceStatus::kOk);
    rig.device->write_torque(JointArray{0.1, -0.1});
  }
  EXPECT_NE(rig.applied_torque(0), 0.0);

  rig.bus->unplug();
  const DeviceReading after = rig.cycle();  // the very next cycle
  EXPECT_EQ(after.status, DeviceStatus::kDisconnected);
  EXPECT_FALSE(after.enabled);
  EXPECT_EQ(after.tau_commanded[0], 0.0);
  EXPECT_EQ(after.tau_commanded[1], 0.0);
  EXPECT_EQ(rig.applied_torque(0), 0.0) << "the console itself drops torque on link loss";
  EXPECT_EQ(rig.applied_torque(1), 0.0);
  EXPECT_NE(rig.device->last_error().find("link lost"), std::string::npos);

  // Stays disconnected while unplugged, the loop keeps running. Real sleeps:
  // the supervisor's reconnect attempts (every 10 ms, real time) run and fail.
  for (int k = 0; k < 20; ++k) {
    EXPECT_EQ(rig.cycle().status, DeviceStatus::kDisconnected);
    rig.device->write_torque(JointArray{0.1, -0.1});
    std::this_thread::sleep_for(1ms);
  }

  rig.bus->replug();
  ASSERT_TRUE(rig.wait_ok()) << rig.device->last_error();
  EXPECT_EQ(rig.device->stats().reconnects, 1u);
  EXPECT_EQ(rig.device->stats().disconnects, 1u);
  // Back, but disabled until the host enables again.
  for (int k = 0; k < 5; ++k) {
    rig.device->write_torque(JointArray{0.1, -0.1});
    EXPECT_FALSE(rig.cycle().enabled);
  }
  EXPECT_EQ(rig.applied_torque(0), 0.0);
  rig.device->set_enabled(true);
  rig.device->write_torque(JointArray{0.1, -0.1});
  rig.cycle();
  const DeviceReading r = rig.cycle();
  EXPECT_TRUE(r.enabled);
  EXPECT_NEAR(rig.applied_torque(0), 0.1, 1e-6);
}

TEST(ConsoleDevice, OpenFailsClearlyWithoutADeviceUnlessToldToWait) {
  EmulatorBus::Options o = Rig::manual_options();
  o.start_unplugged = true;
  {
    Rig rig({}, builtin_console_profile(), o);
    try {
      rig.device->open();
      FAIL() << "open() without a device must throw";
    } catch (const DeviceError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("1209:0001"), std::string::npos) << what;
      EXPECT_NE(what.find("tsm-console-2dof"), std::string::npos) << what;
    }
  }
  ConsoleSettings s = relaxed();
  s.wait_for_device = true;
  s.reconnect_interval_ms = 10;
  Rig rig(s, builtin_console_profile(), o);
  rig.device->open();
  EXPECT_EQ(rig.cycle().status, DeviceStatus::kDisconnected);
  rig.bus->replug();
  EXPECT_TRUE(rig.wait_ok()) << rig.device->last_error();
}

TEST(ConsoleDevice, SelectsTheDeviceByPathAndSerial) {
  ConsoleSettings s = relaxed();
  s.serial = "SOMEONE-ELSE";
  Rig rig(s);
  try {
    rig.device->open();
    FAIL();
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("present: emu:0 (serial EMU-0001)"), std::string::npos)
        << e.what();
  }
  ConsoleSettings ok = relaxed();
  ok.path = "emu:0";
  ok.serial = "EMU-0001";
  Rig rig2(ok);
  EXPECT_NO_THROW(rig2.device->open());
}

TEST(ConsoleDevice, RefusesAProfileThatDoesNotMatchTheDevice) {
  DeviceProfile wrong = builtin_console_profile();
  wrong.joints[1].counts_per_rad *= 2.0;
  Rig a({}, wrong);
  try {
    a.device->open();
    FAIL();
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("joints[1].counts_per_rad"), std::string::npos)
        << e.what();
  }
  DeviceProfile greedy = builtin_console_profile();
  greedy.joints[0].current_limit_peak_a = 5.0;  // the device can do 3 A
  Rig b({}, greedy);
  try {
    b.device->open();
    FAIL();
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("joints[0].current_limit_peak_a"), std::string::npos)
        << e.what();
  }
  DeviceProfile one = builtin_console_profile();
  one.joints.pop_back();
  Rig c({}, one);
  EXPECT_THROW(c.device->open(), DeviceError);
}

TEST(ConsoleDevice, ZeroOffsetAndDirectionFromTheProfile) {
  DeviceProfile p = builtin_console_profile();
  p.joints[0].zero_offset_counts = 12345;
  p.joints[0].direction = -1;
  EmulatorBus::Options o = Rig::manual_options();
  o.firmware = firmware_for_profile(p);  // a console mounted that way
  Rig rig({}, p, o);
  rig.device->open();
  rig.bus->with_firmware([](Firmware& fw) { fw.set_position(0, -0.4); });  // mechanism frame
  // The profile's offset and direction undo the mounting: the joint angle is
  // the mechanism's, although the raw counts run the other way from 12345.
  const DeviceReading r = rig.cycle();
  EXPECT_NEAR(r.q[0], -0.4, 1e-3);
  // Positive joint torque pushes the joint positive (a negative motor current).
  rig.device->set_enabled(true);
  rig.device->write_torque(JointArray{0.1, 0.0});
  rig.cycle();
  rig.cycle();
  EXPECT_NEAR(rig.applied_torque(0), 0.1, 1e-6);
  double current = 0;
  rig.bus->with_firmware([&](Firmware& fw) { current = fw.applied_current_a(0); });
  EXPECT_NEAR(current, -1.0, 1e-6);
}

TEST(ConsoleDevice, DeviceFaultLatchesZeroTorqueAndClears) {
  Rig rig;
  rig.device->open();
  rig.device->set_enabled(true);
  for (int k = 0; k < 30; ++k) {
    rig.device->write_torque(JointArray{0.05, 0.05});
    rig.cycle();
  }
  EXPECT_NEAR(rig.applied_torque(0), 0.05, 1e-6);
  rig.bus->with_firmware(
      [](Firmware& fw) { fw.inject_fault(protocol::FirmwareFault::kOverCurrent); });
  rig.device->write_torque(JointArray{0.05, 0.05});
  rig.cycle();  // the report saying so
  EXPECT_EQ(rig.device->status(), DeviceStatus::kFault);
  const DeviceReading r = rig.device->read(rig.now());
  EXPECT_EQ(r.fault, FaultCode::kDeviceReported);
  EXPECT_EQ(r.tau_commanded[0], 0.0);
  EXPECT_NE(rig.device->last_error().find("over-current"), std::string::npos)
      << rig.device->last_error();
  EXPECT_EQ(rig.applied_torque(0), 0.0);
  bool cleared = false;
  rig.ticking_while([&] { cleared = rig.device->clear_fault(); });
  EXPECT_TRUE(cleared);
  EXPECT_EQ(rig.device->status(), DeviceStatus::kOk);
  rig.device->write_torque(JointArray{0.05, 0.05});
  const DeviceReading after = rig.cycle();
  EXPECT_EQ(after.status, DeviceStatus::kOk) << "the firmware cleared it too (else it re-latches)";
  EXPECT_FALSE(after.enabled) << "a cleared fault leaves torque disabled";
  EXPECT_EQ(rig.applied_torque(0), 0.0);
}

TEST(ConsoleDevice, WorkspaceViolationIsAFaultNamingTheJoint) {
  Rig rig;
  rig.device->open();
  rig.device->set_enabled(true);
  rig.cycle();
  rig.bus->with_firmware([](Firmware& fw) { fw.set_position(1, 1.5); });  // workspace 1.0 + 0.2
  const DeviceReading r = rig.cycle();
  EXPECT_EQ(r.status, DeviceStatus::kFault);
  EXPECT_EQ(r.fault, FaultCode::kWorkspace);
  EXPECT_EQ(rig.device->last_error().rfind("emulator emu:0: joint 1 at 1.4", 0), 0u)
      << rig.device->last_error();
  rig.device->write_torque(JointArray{0.1, 0.1});
  rig.cycle();
  EXPECT_EQ(rig.applied_torque(1), 0.0);
}

TEST(ConsoleDevice, MalformedReportsAreDroppedAndTooManyFault) {
  ConsoleSettings s = relaxed();
  s.max_bad_reports = 5;
  Rig rig(s);
  rig.device->open();
  rig.cycle();
  rig.bus->corrupt_next_input_reports(3);
  for (int k = 0; k < 3; ++k)
    EXPECT_FALSE(rig.cycle().fresh) << "a corrupt report is no reading";
  DeviceReading r = rig.cycle();
  EXPECT_TRUE(r.fresh);
  EXPECT_EQ(r.status, DeviceStatus::kOk) << "a few bad reports are survivable";
  EXPECT_EQ(rig.device->stats().bad_reports, 3u);
  EXPECT_NE(rig.device->last_error().find("bad CRC"), std::string::npos)
      << rig.device->last_error();
  rig.bus->corrupt_next_input_reports(5);
  for (int k = 0; k < 5; ++k)
    r = rig.cycle();
  EXPECT_EQ(r.status, DeviceStatus::kFault);
  EXPECT_EQ(r.fault, FaultCode::kBadReports);
}

TEST(ConsoleDevice, HostRaisedFaultZeroesTorque) {
  Rig rig;
  rig.device->open();
  rig.device->set_enabled(true);
  rig.device->write_torque(JointArray{0.1, 0.1});
  rig.cycle();
  rig.device->raise_fault(FaultCode::kHostRequested);
  rig.cycle();
  const DeviceReading r = rig.cycle();
  EXPECT_EQ(r.status, DeviceStatus::kFault);
  EXPECT_EQ(rig.applied_torque(0), 0.0);
  EXPECT_EQ(rig.device->last_error(), "fault raised by the host");
}

TEST(ConsoleDevice, StaleReadingsReadAsDisconnected) {
  ConsoleSettings s = relaxed();
  s.stale_timeout_ms = 50;
  Rig rig(s);
  rig.device->open();
  EXPECT_EQ(rig.cycle().status, DeviceStatus::kOk);
  rig.wait(50ms);  // the device goes silent (no tick)
  EXPECT_EQ(rig.device->read(rig.now()).status, DeviceStatus::kOk) << "50 ms is within the bound";
  rig.wait(1ms);
  EXPECT_EQ(rig.device->read(rig.now()).status, DeviceStatus::kDisconnected);
}

TEST(ConsoleDevice, CloseSendsZeroAndDisable) {
  Rig rig;
  rig.device->open();
  rig.device->set_enabled(true);
  for (int k = 0; k < 20; ++k) {
    rig.device->write_torque(JointArray{0.1, 0.1});
    rig.cycle();
  }
  EXPECT_NEAR(rig.applied_torque(0), 0.1, 1e-6);
  rig.ticking_while([&] { rig.device->close(); });
  EXPECT_EQ(rig.device->status(), DeviceStatus::kClosed);
  bool enabled = true;
  std::uint64_t watchdog_trips = 1;
  rig.bus->with_firmware([&](Firmware& fw) {
    enabled = fw.torque_enabled();
    watchdog_trips = fw.stats().watchdog_trips;
  });
  EXPECT_FALSE(enabled);
  EXPECT_EQ(rig.applied_torque(0), 0.0);
  EXPECT_EQ(watchdog_trips, 0u) << "disabled by close()'s last report, not by the watchdog";
}

TEST(ConsoleDevice, RealTimeEmulatorStreamsToAOneKilohertzLoop) {
  EmulatorBus::Options o = Rig::manual_options();
  o.pacing = EmulatorBus::Pacing::kRealTime;  // real-time pacing is what is under test
  Rig rig({}, builtin_console_profile(), o);
  rig.device->open();
  rig.device->set_enabled(true);
  std::uint64_t fresh = 0;
  std::uint64_t last_seq = 0;
  bool monotonic = true;
  std::int64_t next = realtime::monotonic_now_ns();
  for (int k = 0; k < 300; ++k) {
    next += 1'000'000;
    realtime::sleep_until_ns(next);
    const DeviceReading r = rig.device->read(rig.now());
    fresh += r.fresh ? 1 : 0;
    monotonic = monotonic && r.sequence >= last_seq;
    last_seq = r.sequence;
    rig.device->write_torque(JointArray{0.05, -0.05});
  }
  EXPECT_TRUE(monotonic);
  EXPECT_GT(fresh, 0u);
  EXPECT_GT(rig.device->stats().outputs_sent, 0u);
  EXPECT_EQ(rig.device->stats().bad_reports, 0u);
  EXPECT_NEAR(rig.applied_torque(0), 0.05, 1e-6);
}

// ---- freshness: silence and late reports (docs/usb-stack-tests.md findings) ----

// The driver's own freshness settings (a bound of 2 device periods), the
// other timeouts relaxed.
ConsoleSettings fresh_by_periods() {
  ConsoleSettings s = relaxed();
  s.stale_timeout_ms = 0;
  s.stale_periods = 2.0;
  return s;
}

// A console that announces 20 Hz: a freshness bound of 2 periods, 100 ms.
struct SlowRig : Rig {
  SlowRig() : Rig(fresh_by_periods(), builtin_console_profile(), slow_options()) {}
  static EmulatorBus::Options slow_options() {
    EmulatorBus::Options o = manual_options();
    o.firmware.info.nominal_rate_hz = 20;
    return o;
  }
  static constexpr std::int64_t kBoundNs = 100'000'000;
  // A cycle with the handle held at its centre: 50 ms of torque per tick
  // would otherwise drive it into its end stops (a workspace fault).
  DeviceReading cycle() {
    bus->with_firmware([](Firmware& fw) {
      fw.set_position(0, 0.0);
      fw.set_position(1, 0.0);
    });
    return Rig::cycle();
  }
  void tick() {
    hold();
    Rig::tick();
  }
  // One report the device had already sent (queued by the host meanwhile):
  // the device's clock moves on, the host's does not.
  DeviceReading drain() {
    hold();
    bus->tick();
    return device->read(now());
  }
  void hold() {
    bus->with_firmware([](Firmware& fw) {
      fw.set_position(0, 0.0);
      fw.set_position(1, 0.0);
    });
  }
};

TEST(ConsoleDevice, FreshnessBoundIsAFewDevicePeriodsUnlessGivenInMilliseconds) {
  Rig a(fresh_by_periods());
  EXPECT_EQ(a.device->freshness_bound_ns(), 2'000'000);  // 2 periods at the profile's 1 kHz
  a.device->open();
  EXPECT_EQ(a.device->freshness_bound_ns(), 2'000'000);  // DEVICE_INFO: 1000 Hz

  EmulatorBus::Options slow = Rig::manual_options();
  slow.firmware.info.nominal_rate_hz = 250;  // the device announces 250 Hz
  ConsoleSettings s = fresh_by_periods();
  s.stale_periods = 1.5;
  Rig b(s, builtin_console_profile(), slow);
  b.device->open();
  EXPECT_EQ(b.device->freshness_bound_ns(), 6'000'000) << "1.5 periods of the device's own rate";
  EXPECT_EQ(b.device->spec().nominal_rate_hz, 250.0);

  ConsoleSettings ms = relaxed();
  ms.stale_timeout_ms = 7;
  Rig c(ms);
  c.device->open();
  EXPECT_EQ(c.device->freshness_bound_ns(), 7'000'000);
}

TEST(ConsoleDevice, SilenceIsNotOkOnceTheBoundPassesAndOkAgainWithTheNextReport) {
  SlowRig rig;
  rig.device->open();
  ASSERT_EQ(rig.device->freshness_bound_ns(), SlowRig::kBoundNs);
  rig.device->set_enabled(true);
  DeviceReading r;
  for (int k = 0; k < 50; ++k) {
    r = rig.cycle();
    rig.device->write_torque(JointArray{0.1, -0.1});
  }
  ASSERT_EQ(r.status, DeviceStatus::kOk);
  ASSERT_TRUE(r.enabled);
  // The device goes silent (no tick). The loop passes its own clock: the
  // verdict depends only on the newest sample's age, so it is exact here.
  const std::int64_t t = r.t_ns;
  DeviceReading inside = rig.device->read(t + SlowRig::kBoundNs - 1000);
  EXPECT_EQ(inside.status, DeviceStatus::kOk);
  EXPECT_FALSE(inside.stale);
  DeviceReading past = rig.device->read(t + SlowRig::kBoundNs + 1000);
  EXPECT_EQ(past.status, DeviceStatus::kDisconnected) << "one cycle after the bound at most";
  EXPECT_TRUE(past.stale);
  EXPECT_FALSE(past.enabled);
  EXPECT_EQ(past.tau_commanded[0], 0.0);
  EXPECT_EQ(past.tau_commanded[1], 0.0);
  EXPECT_EQ(rig.device->status(), DeviceStatus::kOk) << "the link itself is up: nothing latched";

  // Reports resume: OK at once, torque still enabled (no reconnect happened).
  r = rig.cycle();
  EXPECT_EQ(r.status, DeviceStatus::kOk);
  EXPECT_FALSE(r.stale);
  EXPECT_TRUE(r.enabled);
  rig.device->write_torque(JointArray{0.1, -0.1});
  rig.cycle();
  EXPECT_NEAR(rig.applied_torque(0), 0.1, 1e-6);
  EXPECT_EQ(rig.device->stats().disconnects, 0u);
  EXPECT_EQ(rig.device->stats().reconnects, 0u);
  EXPECT_EQ(rig.device->stats().late_reports, 0u);
}

TEST(ConsoleDevice, AReportReadLateIsStaleAndCarriesNoTorque) {
  SlowRig rig;
  rig.device->open();
  rig.device->set_enabled(true);
  for (int k = 0; k < 50; ++k) {
    rig.cycle();
    rig.device->write_torque(JointArray{0.1, -0.1});
  }
  EXPECT_NEAR(rig.applied_torque(0), 0.1, 1e-6);
  // The host is starved for 250 ms while the device takes one sample (50 ms
  // of its clock): the report is read 200 ms after the device's clock says
  // it was taken (what the QEMU guest showed with reports queued before an
  // unplug, at this device's slower pace).
  rig.wait(200ms);
  rig.tick();  // 50 ms more
  const std::int64_t now = rig.now();
  const DeviceReading late = rig.device->read(now);
  EXPECT_TRUE(late.fresh);
  EXPECT_EQ(late.status, DeviceStatus::kDisconnected);
  EXPECT_TRUE(late.stale);
  EXPECT_GT(now - late.t_ns, 190'000'000) << "dated on the device clock, not on arrival";
  EXPECT_EQ(late.tau_commanded[0], 0.0);
  EXPECT_EQ(rig.applied_torque(0), 0.0) << "its answer carried no torque";
  EXPECT_EQ(rig.device->stats().late_reports, 1u);

  // The host reads the reports the device sent meanwhile: the device clock
  // catches up with the host's, the reports are on time again, OK with
  // torque, without re-enabling.
  bool back = false;
  for (int k = 0; k < 4 && !back; ++k) {
    rig.device->write_torque(JointArray{0.1, -0.1});
    const DeviceReading r = rig.drain();
    back = r.status == DeviceStatus::kOk && r.enabled;
  }
  EXPECT_TRUE(back) << "within the 4 reports of the starved 200 ms";
  rig.device->write_torque(JointArray{0.1, -0.1});
  rig.cycle();
  EXPECT_NEAR(rig.applied_torque(0), 0.1, 1e-6);
  EXPECT_EQ(rig.device->stats().disconnects, 0u);
}

TEST(ConsoleDevice, UnplugIsNotOkFromTheBoundEvenBeforeTheLinkLossPathFires) {
  SlowRig rig;
  rig.device->open();
  rig.device->set_enabled(true);
  DeviceReading r;
  for (int k = 0; k < 20; ++k) {
    r = rig.cycle();
    rig.device->write_torque(JointArray{0.1, -0.1});
  }
  rig.bus->unplug();  // the transport notices only on its next tick (like a slow kernel)
  const DeviceReading before_link = rig.device->read(r.t_ns + SlowRig::kBoundNs + 1000);
  EXPECT_EQ(before_link.status, DeviceStatus::kDisconnected);
  EXPECT_TRUE(before_link.stale);
  EXPECT_FALSE(before_link.enabled);
  EXPECT_EQ(rig.device->stats().disconnects, 0u);
  rig.tick();  // the link-loss path
  const DeviceReading after_link = rig.device->read(rig.now());
  EXPECT_EQ(after_link.status, DeviceStatus::kDisconnected);
  EXPECT_FALSE(after_link.stale) << "a lost link, not a silence";
  EXPECT_EQ(rig.device->stats().disconnects, 1u);
}

TEST(ConsoleDevice, FreshnessSettingsAreValidated) {
  const auto error_of = [](const char* yaml) {
    YAML::Node node = YAML::Load(yaml);
    config::FieldReader r(node, "server.yaml", "device.settings");
    try {
      parse_console_settings(r);
    } catch (const config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of("stale_periods: 0.5").find("device.settings.stale_periods: must be >= 1"),
            std::string::npos);
  EXPECT_NE(error_of("stale_periods: 3\nstale_timeout_ms: 5")
                .find("device.settings.stale_periods: give stale_timeout_ms or stale_periods"),
            std::string::npos);
  EXPECT_NE(error_of("clock_tolerance_ppm: -1").find("device.settings.clock_tolerance_ppm"),
            std::string::npos);
  EXPECT_EQ(error_of("stale_periods: 3\nclock_tolerance_ppm: 1000"), "");
}

TEST(ConsoleDevice, KeepsTheSharedFaultRules) {
  EmulatorBus::Options o = Rig::manual_options();
  o.pacing = EmulatorBus::Pacing::kRealTime;  // clear_fault() waits for the firmware's reports
  Rig rig(relaxed(), builtin_console_profile(), o);
  rig.device->open();
  testing::DriverProbe probe{*rig.device, [&] { return rig.now(); },
                             [&] { return rig.applied_torque(0); },
                             [] { std::this_thread::sleep_for(1ms); }};
  ASSERT_TRUE(testing::within_steps(
      probe, [&] { return rig.device->read(rig.now()).status == DeviceStatus::kOk; }));
  testing::expect_shared_fault_rules(probe, 0.05);
  rig.device->close();
}

}  // namespace
}  // namespace tsmh::master_devices
