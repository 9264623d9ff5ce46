#pragma once
// A compilable skeleton of a master device driver, the starting point of
// docs/adding-a-driver.md. ctest builds it and runs it
// (tests/master_devices/test_skeleton_driver.cpp). Copy it, rename
// `skeleton`, and work through the numbered steps.
//
// Shape: the vendor's calls run on the driver's own I/O thread; the 1 kHz
// loop only touches two LatestValue cells (readings in, commands out), so
// nothing in read()/write_torque() blocks, allocates or locks. DriverBase
// (driver_base.hpp) holds those cells and what every driver shares: the
// latched fault, the enable request, status(), last_error(), write_torque(),
// and the torque limits (torque_to_send).

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "config/field_reader.hpp"
#include "master_devices/clock.hpp"
#include "master_devices/driver_base.hpp"
#include "master_devices/registry.hpp"
#include "realtime/joint_names.hpp"
#include "realtime/latest_value.hpp"
#include "realtime/pacing.hpp"

namespace tsmh::master_devices::skeleton {

// STEP 1. Settings, with defaults, parsed by config::FieldReader so that every error
// names the file and the field (parse_settings below).
struct Settings {
  int dof = 2;
  double peak_torque_nm = 0.2;
  double rate_hz = 1000.0;
  double stale_timeout_ms = 50.0;    ///< no new sample this long: DISCONNECTED
  double command_timeout_ms = 20.0;  ///< no write_torque() this long: zero torque
};

inline Settings parse_settings(config::FieldReader& r) {
  Settings s;
  s.dof = static_cast<int>(r.get_int("dof", 2));
  if (s.dof < 1 || s.dof > static_cast<int>(kMaxDof))
    r.fail("dof", "must be 1.." + std::to_string(kMaxDof));
  s.peak_torque_nm = r.get_positive("peak_torque_nm", s.peak_torque_nm);
  s.rate_hz = r.get_positive("rate_hz", s.rate_hz);
  s.stale_timeout_ms = r.get_positive("stale_timeout_ms", s.stale_timeout_ms);
  s.command_timeout_ms = r.get_positive("command_timeout_ms", s.command_timeout_ms);
  r.reject_unknown();
  return s;
}

// STEP 2. The vendor's calls. This stand-in is a handle that sways slowly and
// records the last torque it was given; replace its bodies with the SDK's.
// It is shared with tests, which unplug it and look at the torque it got.
class VendorLink {
 public:
  virtual ~VendorLink() = default;
  /// One sample: joint angles (rad, already zeroed and signed) and buttons.
  /// False: the device is gone (unplugged, SDK error).
  virtual bool read_sample(JointArray& q, Buttons& buttons) {
    if (!plugged.load()) return false;
    const double t = static_cast<double>(++samples_) * 1e-3;
    for (std::size_t j = 0; j < kMaxDof; ++j)
      q[j] = 0.1 * std::sin(t + static_cast<double>(j));
    buttons.dead_man = true;
    return true;
  }
  /// Joint torques, N m; only ever called with limited values.
  virtual void write_torques(const JointArray& tau) {
    for (std::size_t j = 0; j < kMaxDof; ++j)
      last_torque[j].store(tau[j]);
  }
  std::atomic<bool> plugged{true};
  std::array<std::atomic<double>, kMaxDof> last_torque{};

 private:
  long samples_ = 0;
};

class SkeletonDevice final : public DriverBase {
 public:
  SkeletonDevice(Settings s, std::shared_ptr<VendorLink> link,
                 std::shared_ptr<const Clock> clock = monotonic_clock())
      : DriverBase(std::move(clock)), s_(s), link_(std::move(link)) {
    // STEP 3. The spec: everything the server's limits and scaling read.
    spec_.model = "skeleton";
    spec_.driver = "skeleton";
    spec_.dof = static_cast<std::uint32_t>(s_.dof);
    spec_.nominal_rate_hz = s_.rate_hz;
    for (std::size_t j = 0; j < spec_.dof; ++j) {
      spec_.joint_names[j] = realtime::joint_name(j);  // joint1, joint2, ...
      spec_.peak_torque_nm[j] = s_.peak_torque_nm;
      spec_.max_continuous_torque_nm[j] = s_.peak_torque_nm;
      spec_.position_min_rad[j] = -1.0;
      spec_.position_max_rad[j] = 1.0;
    }
  }
  ~SkeletonDevice() override { close(); }

  // STEP 4. open(): connect (throw DeviceError naming the cause), then start
  // the I/O thread. Torque starts disabled.
  void open() override {
    if (running_.load()) return;
    if (!link_->plugged.load())
      throw DeviceError("skeleton: no device found (plugged in? permissions?)");
    unlatch_fault();  // also disables
    link_up_.store(true);
    opened_.store(true);
    running_.store(true);
    io_ = std::thread([this] { io_loop(); });
  }

  void close() noexcept override {
    if (!running_.exchange(false)) return;
    io_.join();
    link_->write_torques({});  // zero torque on the way out
    opened_.store(false);
  }

  // STEP 5. Faults latch (DriverBase::latch_fault, raise_fault) until
  // clear_fault(), which fails while the cause persists.
  bool clear_fault() override {
    if (fault() == FaultCode::kNone) return true;
    if (!link_->plugged.load()) return false;
    unlatch_fault();  // back disabled
    return true;
  }

  // STEP 6. read() is DriverBase's: the newest reading from the cell with the
  // shared rules (stale -> DISCONNECTED, not OK -> disabled with nothing
  // commanded). The driver says only how old a reading may be.
  std::int64_t freshness_bound_ns() const noexcept override {
    return static_cast<std::int64_t>(s_.stale_timeout_ms * 1e6);
  }

  // STEP 7. write_torque() is DriverBase's: it stamps the command with the
  // clock. The I/O thread limits it with torque_to_send() (NaN -> 0, clamp to
  // spec().peak_torque_nm, zero unless OK, enabled and on time).

 private:
  // STEP 8. The I/O thread: paced on absolute deadlines, it reads the vendor,
  // publishes the reading, and sends the newest command, or zero when the
  // command is older than command_timeout_ms (the loop died) or the device
  // is not OK.
  void io_loop() {
    realtime::LatestValueReader<Command> commands(commands_);
    const auto period_ns = static_cast<std::int64_t>(1e9 / s_.rate_hz);
    realtime::Pacer pace(period_ns, realtime::monotonic_now_ns() + period_ns);
    DeviceReading s;
    s.dof = spec_.dof;
    s.enabled = true;  // the host's request decides (apply_reading_rules)
    s.status = DeviceStatus::kOk;
    JointArray q_prev{};
    while (running_.load()) {
      pace.wait_through_signals();
      pace.advance(realtime::monotonic_now_ns());
      JointArray q{};
      Buttons b;
      const bool ok = link_->read_sample(q, b);
      const std::int64_t now = clock_->now_ns();
      if (ok) {
        const double dt = 1.0 / s_.rate_hz;
        for (std::size_t j = 0; j < kMaxDof; ++j)
          s.qd[j] = s.sequence ? (q[j] - q_prev[j]) / dt : 0.0;
        q_prev = q;
        s.q = q;
        s.buttons = b;
        s.t_ns = now;
        ++s.sequence;
      } else if (link_up_.load()) {
        set_enabled(false);  // a device that comes back comes back disabled
        set_error("skeleton: device unplugged");
      }
      link_up_.store(ok);  // down: status() is DISCONNECTED
      Command c;
      commands.fetch(c);
      const Torque torque =
          torque_to_send(c, now, static_cast<std::int64_t>(s_.command_timeout_ms * 1e6));
      s.tau_commanded = torque.tau;
      readings_.store(s);
      if (ok) link_->write_torques(torque.tau);
    }
  }

  Settings s_;
  std::shared_ptr<VendorLink> link_;
  std::atomic<bool> running_{false};
  std::thread io_;
};

// STEP 9. Register it by name where the registry is built (haptic-server's
// make_registry(), tsm-devices): device: {driver: skeleton, settings: {...}}.
inline void register_skeleton_driver(DriverRegistry& registry, std::shared_ptr<VendorLink> link,
                                     std::shared_ptr<const Clock> clock = monotonic_clock()) {
  registry.add("skeleton", "skeleton driver (docs/adding-a-driver.md)",
               [link, clock](const YAML::Node& settings, const DriverContext& ctx) {
                 config::FieldReader r(settings, ctx.source, ctx.path);
                 return std::unique_ptr<Device>(
                     std::make_unique<SkeletonDevice>(parse_settings(r), link, clock));
               });
}

}  // namespace tsmh::master_devices::skeleton
