#include "crash_outputs.hpp"

#include <algorithm>
#include <array>
#include <tsmh/master_force_t.hpp>

#include "bridge/codec.hpp"
#include "bridge/lcm_url.hpp"
#include "bridge/link_auth.hpp"
#include "bridge/udpm_frame.hpp"
#include "master_devices/console_device.hpp"
#include "master_devices/haply_device.hpp"
#include "master_devices/haply_protocol.hpp"
#include "master_devices/lcm_device.hpp"
#include "master_devices/mapped_device.hpp"
#include "master_devices/protocol.hpp"
#include "realtime/clock.hpp"

namespace tsmh::haptic_server {
namespace {

int port_of(const bridge::UdpmEndpoint& e) {
  return ntohs(e.group.sin_port);
}

// The console's node when it is reached through hidraw (the `hid` driver);
// "" otherwise (libusb's "usb:..." paths, the emulator).
std::string hidraw_node(master_devices::Device& device, const std::string& driver) {
  if (driver != "hid") return {};
  const auto* console = dynamic_cast<const master_devices::ConsoleDevice*>(&device);
  if (console == nullptr) return {};
  std::string path = console->connected_path();
  return path.rfind("/dev/", 0) == 0 ? path : std::string{};
}

// The Haply board behind the `haply` driver, with or without a mapping.
master_devices::HaplyDevice* haply_board(master_devices::Device& device) {
  if (auto* haply = dynamic_cast<master_devices::HaplyDevice*>(&device)) return haply;
  if (auto* mapped = dynamic_cast<master_devices::MappedDevice*>(&device))
    return dynamic_cast<master_devices::HaplyDevice*>(&mapped->inner());
  return nullptr;
}

}  // namespace

CrashOutputs::CrashOutputs(Setup setup) : s_(std::move(setup)) {
  if (const auto e = bridge::udpm_endpoint(s_.link_url)) {
    hold_ = static_cast<int>(stop_.add_datagram(*e));
    link_port_ = port_of(*e);
    summary_ = "MASTER_COMMAND hold on " + s_.link_url;
  }
  if (s_.driver == "lcm") {
    if (const auto* lcm = dynamic_cast<const master_devices::LcmDevice*>(&s_.device)) {
      const std::string url = bridge::resolve_lcm_url(lcm->settings().url);
      if (const auto e = bridge::udpm_endpoint(url)) {
        force_ = static_cast<int>(stop_.add_datagram(*e));
        device_port_ = port_of(*e);
        force_channel_ = lcm->settings().force_channel();
        force_dof_ = static_cast<int>(lcm->settings().dof);
        summary_ +=
            std::string(summary_.empty() ? "" : ", ") + "zero " + force_channel_ + " on " + url;
      }
    }
  }
  if (s_.driver == "hid") {
    console_node_ = hidraw_node(s_.device, s_.driver);
    console_ = static_cast<int>(stop_.add_node(console_node_));
    // Enable 0, zero current: the same bytes whatever the time (the
    // firmware does not order OUTPUT reports by their sequence).
    std::array<std::uint8_t, master_devices::protocol::kOutputReportSize> report{};
    const auto n =
        master_devices::protocol::encode(master_devices::protocol::OutputReport{}, report);
    if (n.ok()) stop_.set(static_cast<std::size_t>(console_), report.data(), n.value);
    summary_ += std::string(summary_.empty() ? "" : ", ") + "zero OUTPUT report on " +
                (console_node_.empty() ? std::string("the console's hidraw node") : console_node_);
  }
  if (s_.driver == "haply") {
    if (master_devices::HaplyDevice* board = haply_board(s_.device)) {
      // The board has no watchdog: it keeps the last torque it was sent. Its
      // port is exclusive, so the handler writes the zero state command on a
      // copy of the driver's own descriptor (follow_haply()).
      haply_ = static_cast<int>(stop_.add_node());
      haply_node_ = board->settings().port;
      std::array<std::uint8_t, master_devices::haply::kMaxFrame> frame{};
      const std::size_t n = board->zero_torque_frame(frame.data());
      stop_.set(static_cast<std::size_t>(haply_), frame.data(), n);
      summary_ +=
          std::string(summary_.empty() ? "" : ", ") + "zero torque to the board on " + haply_node_;
    }
  }
  if (haply_ >= 0) follow_haply();
  find_senders();
  refresh(realtime::monotonic_now_ns());
  stop_.install();
}

void CrashOutputs::find_senders() {
  stop_.find_senders({link_port_, device_port_}, {console_node_, haply_node_});
}

void CrashOutputs::refresh(std::int64_t now_ns) {
  if (console_ >= 0) follow_console();
  if (haply_ >= 0) follow_haply();
  if (now_ns < next_refresh_ns_) return;
  next_refresh_ns_ = now_ns + kRefreshNs;
  if (hold_ >= 0) prepare_hold();
  if (force_ >= 0) prepare_force();
}

void CrashOutputs::prepare_hold() {
  bridge::MasterCommandSample last;
  const bool any = s_.link.last_command(last) != 0;
  bridge::MasterCommandSample hold;
  hold.utime = std::max(any ? last.utime : 0, realtime::monotonic_utime()) + kLeadUs;
  hold.seq = (any ? last.seq : 0) + kSeqLead;
  hold.num_joints = s_.joints;
  hold.enable = false;
  hold.clutch = false;
  // The reference where the slave is being held (the last one sent).
  if (any) hold.position_ref = last.position_ref;
  bridge::encode_sample(hold, payload_);
  const std::size_t size = payload_.size();
  const std::string& channel = s_.link.command_channel();
  if (bridge::MessageSigner* signer = s_.link.signer()) {
    payload_.resize(size + bridge::kAuthTrailerBytes);
    signer->sign(channel, payload_.data(), size, payload_.data() + size);
  }
  datagram_.resize(bridge::CrashStop::kMaxBytes);
  const std::size_t n = bridge::frame_udpm_short(channel, 0, payload_.data(), payload_.size(),
                                                 datagram_.data(), datagram_.size());
  if (n > 0) stop_.set(static_cast<std::size_t>(hold_), datagram_.data(), n);
}

void CrashOutputs::prepare_force() {
  tsmh::master_force_t m;
  // Ahead of every MASTER_FORCE the driver sent before (its utime is the
  // monotonic clock, its seq counts messages: far fewer than microseconds).
  m.utime = realtime::monotonic_utime() + kLeadUs;
  m.seq = m.utime;
  m.num_joints = force_dof_;
  m.torque.assign(static_cast<std::size_t>(force_dof_), 0.0);
  m.enable = false;
  const int size = m.getEncodedSize();
  const std::size_t trailer = s_.device_auth ? s_.device_auth->trailer_size() : 0;
  payload_.resize(static_cast<std::size_t>(size) + trailer);
  if (m.encode(payload_.data(), 0, size) != size) return;
  if (s_.device_auth)
    s_.device_auth->sign(force_channel_, payload_.data(), static_cast<std::size_t>(size),
                         payload_.data() + size);
  datagram_.resize(bridge::CrashStop::kMaxBytes);
  const std::size_t n = bridge::frame_udpm_short(
      force_channel_, 0, payload_.data(), payload_.size(), datagram_.data(), datagram_.size());
  if (n > 0) stop_.set(static_cast<std::size_t>(force_), datagram_.data(), n);
}

// The hid driver reconnects on its own after an unplug, possibly as another
// /dev/hidrawN: the handler's descriptor follows it, and hidapi's new
// descriptor joins the silenced ones.
void CrashOutputs::follow_console() {
  const std::string node = hidraw_node(s_.device, s_.driver);
  if (node.empty() || node == console_node_) return;
  if (!stop_.reopen_node(static_cast<std::size_t>(console_), node)) return;
  console_node_ = node;
  find_senders();
}

// The haply driver opens the port again after an unplug (clear_fault()),
// under another descriptor: the handler's copy follows it, and the new one
// joins the silenced ones. While the link is down the copy points at
// /dev/null. (The driver may close its descriptor just after it is read
// here; then dup3 fails and the copy stays as it was until the next look.)
void CrashOutputs::follow_haply() {
  const master_devices::HaplyDevice* board = haply_board(s_.device);
  if (board == nullptr) return;
  const int fd = board->port_descriptor();
  if (fd == haply_fd_) return;
  if (!stop_.adopt_descriptor(static_cast<std::size_t>(haply_), fd)) return;
  haply_fd_ = fd;
  find_senders();
}

}  // namespace tsmh::haptic_server
