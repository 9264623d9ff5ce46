#include "master_devices/lcm_device.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <lcm/lcm-cpp.hpp>
#include <tsmh/master_force_t.hpp>
#include <tsmh/master_state_t.hpp>
#include <vector>

#include "lcmtypes/lcm_url.hpp"
#include "lcmtypes/message_decoder.hpp"

namespace tsmh::master_devices {

LcmSettings parse_lcm_settings(config::FieldReader& r) {
  LcmSettings s;
  s.url = r.get_string("url", "");
  if (!s.url.empty()) {
    try {
      lcmtypes::parse_lcm_url(s.url);
    } catch (const lcmtypes::LcmUrlError& e) {
      r.fail("url", e.what());
    }
  }
  s.channel_prefix = r.get_string("channel_prefix", "");
  const long long dof = r.get_int("dof", 2);
  if (dof < 1 || dof > static_cast<long long>(kMaxDof))
    r.fail("dof", "must be 1 .. " + std::to_string(kMaxDof));
  s.dof = static_cast<std::size_t>(dof);
  s.nominal_rate_hz = r.get_double("nominal_rate_hz", s.nominal_rate_hz);
  if (!(s.nominal_rate_hz > 0)) r.fail("nominal_rate_hz", "must be > 0");
  s.peak_torque_nm.fill(0.3);
  r.get_joint_array("peak_torque_nm", s.peak_torque_nm, s.dof);
  s.continuous_torque_nm.fill(0.15);
  r.get_joint_array("continuous_torque_nm", s.continuous_torque_nm, s.dof);
  s.position_min_rad.fill(-1.0);
  r.get_joint_array("position_min_rad", s.position_min_rad, s.dof);
  s.position_max_rad.fill(1.0);
  r.get_joint_array("position_max_rad", s.position_max_rad, s.dof);
  s.max_stiffness_nm_per_rad.fill(0.0);
  r.get_joint_array("max_stiffness_nm_per_rad", s.max_stiffness_nm_per_rad, s.dof);
  for (std::size_t j = 0; j < s.dof; ++j) {
    if (!(s.peak_torque_nm[j] > 0)) r.fail("peak_torque_nm", "must be > 0");
    if (!(s.continuous_torque_nm[j] > 0 && s.continuous_torque_nm[j] <= s.peak_torque_nm[j])) {
      r.fail("continuous_torque_nm", "must be > 0 and <= peak_torque_nm");
    }
    if (!(s.position_min_rad[j] < s.position_max_rad[j]))
      r.fail("position_max_rad", "must be > position_min_rad");
  }
  s.stale_timeout_ms = r.get_int("stale_timeout_ms", s.stale_timeout_ms);
  if (s.stale_timeout_ms < 1) r.fail("stale_timeout_ms", "must be >= 1");
  s.command_timeout_ms = r.get_int("command_timeout_ms", s.command_timeout_ms);
  if (s.command_timeout_ms < 1) r.fail("command_timeout_ms", "must be >= 1");
  return s;
}

/// The LCM thread's side: subscription handler and reply.
struct LcmDevice::Impl {
  LcmDevice& device;
  lcm::Subscription* subscription = nullptr;
  // The project's one MASTER_STATE decoder: exactly `dof` joints and the
  // exact size for them, checked from the raw bytes before lcm-gen's decode()
  // may size anything (a body claiming 2^28 joints once made it allocate 2 GB).
  lcmtypes::MessageDecoder<tsmh::master_state_t> decoder;
  tsmh::master_force_t force;  // preallocated: its vector keeps its capacity
  std::vector<std::uint8_t> force_bytes;
  std::string auth_error;  // why the last message failed authentication
  std::uint64_t count = 0;
  std::int64_t force_seq = 0;

  explicit Impl(LcmDevice& d)
      : device(d),
        decoder({static_cast<std::int32_t>(d.settings_.dof),
                 static_cast<std::int32_t>(d.settings_.dof)}) {
    force.num_joints = static_cast<int32_t>(d.settings_.dof);
    force.torque.assign(d.settings_.dof, 0.0);
  }

  void reject(const std::string& why) {
    device.rejected_++;
    const std::string text = device.settings_.state_channel() + ": " + why;
    device.set_error(text);
    std::lock_guard lock(device.error_mutex_);
    device.last_rejection_ = text;
  }

  // Raw: authenticate before decoding (a message that fails never reaches
  // the decoder); without auth, trailing bytes (another peer's MAC) are
  // left unread as by every LCM tool; everything before them is checked.
  void on_raw(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const auto* data = static_cast<const std::uint8_t*>(rbuf->data);
    std::size_t size = rbuf->data_size;
    if (const auto& auth = device.settings_.auth) {
      using Verdict = LcmAuthResult::Verdict;
      const LcmAuthResult r = auth->verify(channel, data, size, auth_error);
      switch (r.verdict) {
        case Verdict::kUse:
          break;
        case Verdict::kHandshake:
          return answer_handshake();
        case Verdict::kRefuse:
          return reject("not authenticated: " + auth_error);
        case Verdict::kOtherSession: {
          // Another master holds the key: this session is over. Torque off
          // and a fault the loop sees (FAULT, the server ends).
          device.latch_fault(FaultCode::kOtherSession);
          return reject(auth_error);
        }
      }
      size = r.payload_size;
    }
    const auto trailing =
        device.settings_.auth ? lcmtypes::Trailing::kReject : lcmtypes::Trailing::kIgnore;
    if (const auto error = decoder.decode(data, size, trailing)) return reject(error->what.data());
    on_state(decoder.message());
  }

  // A hello of the master's session: its content is not used, but it is
  // answered (zero torque, disabled) so the adapter learns our id and binds.
  void answer_handshake() {
    force.utime = device.clock_->now_ns() / 1000;
    force.seq = force_seq++;
    force.enable = false;
    std::fill(force.torque.begin(), force.torque.end(), 0.0);
    publish_force();
  }

  void publish_force() {
    const auto& auth = device.settings_.auth;
    if (!auth) {
      device.lcm_->publish(device.settings_.force_channel(), &force);
      return;
    }
    const int size = force.getEncodedSize();
    force_bytes.resize(static_cast<std::size_t>(size) + auth->trailer_size());
    if (force.encode(force_bytes.data(), 0, size) != size) return;
    auth->sign(device.settings_.force_channel(), force_bytes.data(), static_cast<std::size_t>(size),
               force_bytes.data() + size);
    device.lcm_->publish(device.settings_.force_channel(), force_bytes.data(),
                         static_cast<unsigned>(force_bytes.size()));
  }

  // `m` holds exactly dof joints (the decoder's range).
  void on_state(const tsmh::master_state_t& m) {
    const std::int64_t now = device.clock_->now_ns();
    const std::size_t dof = device.settings_.dof;
    for (std::size_t j = 0; j < dof; ++j) {
      if (!std::isfinite(m.q[j]) || !std::isfinite(m.qd[j])) {
        reject("q[" + std::to_string(j) + "] or qd[" + std::to_string(j) + "] is not finite");
        return;
      }
    }
    if (m.buttons & ~0xF) {
      reject("buttons " + std::to_string(m.buttons) + " has undefined bits (0..3 defined)");
      return;
    }
    if ((m.status & 0x1) && device.latch_fault(FaultCode::kDeviceReported))
      device.set_error(device.settings_.state_channel() + ": the external driver reports a fault");

    // Answer with the newest torque (zero unless everything is well).
    Command cmd;
    device.command_reader_.fetch(cmd);
    const Torque torque =
        device.torque_to_send(cmd, now, device.settings_.command_timeout_ms * 1'000'000LL);
    DeviceReading r;
    r.t_ns = now;
    r.sequence = ++count;
    r.dof = static_cast<std::uint32_t>(dof);
    for (std::size_t j = 0; j < dof; ++j) {
      r.q[j] = m.q[j];
      r.qd[j] = m.qd[j];
      r.tau_commanded[j] = torque.tau[j];
      force.torque[j] = torque.tau[j];
    }
    r.buttons = Buttons{(m.buttons & 1) != 0, (m.buttons & 2) != 0, (m.buttons & 4) != 0,
                        (m.buttons & 8) != 0};
    r.enabled = torque.drive;
    r.status = DeviceStatus::kOk;
    device.readings_.store(r);

    force.utime = now / 1000;
    force.seq = force_seq++;
    force.enable = torque.drive;
    publish_force();
  }
};

LcmDevice::LcmDevice(LcmSettings settings, std::shared_ptr<const Clock> clock)
    : LcmDevice(std::move(settings), nullptr, std::move(clock)) {}

LcmDevice::LcmDevice(LcmSettings settings, std::shared_ptr<lcm::LCM> lcm,
                     std::shared_ptr<const Clock> clock)
    : DriverBase(std::move(clock)), settings_(std::move(settings)), lcm_(std::move(lcm)) {
  spec_.model = "lcm:" + settings_.state_channel();
  spec_.driver = "lcm";
  spec_.has_calibrate_button = true;  // MASTER_STATE buttons bit 3
  spec_.dof = static_cast<std::uint32_t>(settings_.dof);
  spec_.nominal_rate_hz = settings_.nominal_rate_hz;
  copy_joint_limits(settings_, spec_);
}

LcmDevice::~LcmDevice() {
  close();
}

void LcmDevice::open() {
  if (opened_) return;
  if (!lcm_) {
    // An empty URL lets LCM honour $LCM_DEFAULT_URL, as its own tools do;
    // that one is held to the same strict reading as a configured url.
    const char* env = std::getenv("LCM_DEFAULT_URL");
    if (settings_.url.empty() && env != nullptr && env[0] != '\0') {
      try {
        lcmtypes::parse_lcm_url(env);
      } catch (const lcmtypes::LcmUrlError& e) {
        throw DeviceError(std::string("lcm: $LCM_DEFAULT_URL: ") + e.what());
      }
    }
    lcm_ = std::make_shared<lcm::LCM>(settings_.url);
  }
  if (!lcm_->good()) {
    const char* env = std::getenv("LCM_DEFAULT_URL");
    const std::string url = !settings_.url.empty() ? settings_.url : (env ? env : "LCM default");
    lcm_.reset();
    throw DeviceError(
        "lcm: cannot start LCM at " + url +
        " (for udpm on a host without a multicast route: ip link set lo multicast on; "
        "ip route add 224.0.0.0/4 dev lo)");
  }
  impl_ = std::make_unique<Impl>(*this);
  impl_->subscription = lcm_->subscribe(settings_.state_channel(), &Impl::on_raw, impl_.get());
  set_enabled(false);
  stopping_ = false;
  link_up_ = true;  // no link to lose: a silent adapter reads as stale
  opened_ = true;
  thread_ = std::thread([this] {
    while (!stopping_)
      lcm_->handleTimeout(10);
  });
}

void LcmDevice::close() noexcept {
  if (!opened_.exchange(false)) return;
  stopping_ = true;
  if (thread_.joinable()) thread_.join();
  // Goodbye: a last zero force that ends the master's session at once (it
  // then waits for the next server instead of for its timeout).
  if (impl_ && settings_.auth) {
    settings_.auth->close_session();
    impl_->answer_handshake();
  }
  if (impl_ && impl_->subscription) lcm_->unsubscribe(impl_->subscription);
  impl_.reset();
}

std::string LcmDevice::last_rejection() const {
  std::lock_guard lock(error_mutex_);
  return last_rejection_;
}

void register_lcm_driver(DriverRegistry& registry, std::shared_ptr<const Clock> clock,
                         std::shared_ptr<LcmMessageAuth> auth) {
  registry.add("lcm", "external master driver over LCM (MASTER_STATE in, MASTER_FORCE out)",
               [clock, auth](const YAML::Node& settings, const DriverContext& ctx) {
                 config::FieldReader r(settings, ctx.source, ctx.path);
                 LcmSettings s = parse_lcm_settings(r);
                 r.reject_unknown();
                 s.auth = auth;
                 return std::unique_ptr<Device>(std::make_unique<LcmDevice>(std::move(s), clock));
               });
}

}  // namespace tsmh::master_devices
