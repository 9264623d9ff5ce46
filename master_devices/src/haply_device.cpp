#include "master_devices/haply_device.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>

#include "haply_profiles.hpp"
#include "master_devices/mapped_device.hpp"
#include "realtime/pacing.hpp"

namespace tsmh::master_devices {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

std::int64_t ms_to_ns(double ms) {
  return static_cast<std::int64_t>(ms * 1e6);
}

void sleep_ns(std::int64_t ns) {
  std::this_thread::sleep_for(std::chrono::nanoseconds(ns));
}

/// The board a profile's geometry belongs to.
std::string default_board(const std::string& profile_name) {
  if (profile_name == "haply-2diy") return "gen3";
  if (profile_name == "haply-2diy-gen2") return "gen2";
  return "";
}

/// The first line of a small sysfs attribute ("" when absent).
std::string read_attribute(const std::filesystem::path& p) {
  std::FILE* f = std::fopen(p.c_str(), "r");
  if (f == nullptr) return "";
  char line[256] = {};
  const bool ok = std::fgets(line, sizeof line, f) != nullptr;
  std::fclose(f);
  std::string v = ok ? line : "";
  while (!v.empty() && (v.back() == '\n' || v.back() == ' '))
    v.pop_back();
  return v;
}

}  // namespace

std::string_view builtin_haply_profile_text(std::string_view name) {
  if (name == "haply-2diy") return generated::kHaply2diyYaml;
  if (name == "haply-2diy-gen2") return generated::kHaply2diyGen2Yaml;
  return {};
}

MasterProfile builtin_haply_profile(std::string_view name) {
  const std::string_view text = builtin_haply_profile_text(name);
  if (text.empty())
    throw config::ConfigError("'" + std::string(name) +
                              "' is not a built-in Haply profile (haply-2diy, haply-2diy-gen2)");
  return parse_master_profile(std::string(text), std::string(name) + ".yaml (built in)");
}

HaplySettings parse_haply_settings(config::FieldReader& r, const DriverContext& ctx) {
  HaplySettings s;
  s.port = r.get_string("port", "");
  if (s.port.empty())
    r.fail("port", "missing: the board's serial port, e.g. /dev/ttyACM0 (`tsm-devices list`)");
  const std::string profile = r.get_string("profile", "haply-2diy");
  if (!builtin_haply_profile_text(profile).empty()) {
    s.profile = builtin_haply_profile(profile);
  } else if (profile.size() > 5 && profile.substr(profile.size() - 5) == ".yaml") {
    const std::filesystem::path p = ctx.base_dir / profile;
    if (!std::filesystem::is_regular_file(p)) r.fail("profile", "no such file: " + p.string());
    s.profile = load_master_profile(p);
  } else {
    r.fail("profile", "'" + profile +
                          "' is neither a built-in profile (haply-2diy, haply-2diy-gen2) nor a "
                          "FILE.yaml");
  }
  if (s.profile.kinematics.joints != 2)
    r.fail("profile", s.profile.name + " has " + std::to_string(s.profile.kinematics.joints) +
                          " joints; the 2DIY's board drives 2");
  std::string board = r.get_string("board", default_board(s.profile.name));
  if (board.empty())
    r.fail("board",
           "missing: which board (" + haply::board_preset_names() + ") drives " + s.profile.name);
  try {
    s.board = haply::board_preset(board);
  } catch (const std::invalid_argument& e) {
    r.fail("board", e.what());
  }
  const long long id = r.get_int("device_id", s.board.device_id);
  if (id < 1 || id > 255) r.fail("device_id", "must be 1..255");
  s.board.device_id = static_cast<std::uint8_t>(id);
  s.rate_hz = r.get_positive("rate_hz", s.profile.update_rate_hz);
  if (s.rate_hz > 4000.0) r.fail("rate_hz", "must be <= 4000 (one request and reply per period)");
  s.watchdog_ms = r.get_positive("watchdog_ms", s.watchdog_ms);
  s.command_timeout_ms = r.get_positive("command_timeout_ms", s.command_timeout_ms);
  s.open_timeout_ms = r.get_positive("open_timeout_ms", s.open_timeout_ms);
  s.max_bad_replies = static_cast<int>(r.get_int("max_bad_replies", s.max_bad_replies));
  if (s.max_bad_replies < 1) r.fail("max_bad_replies", "must be >= 1");
  s.workspace_margin_m = r.get_positive("workspace_margin_m", s.workspace_margin_m);
  return s;
}

HaplyDevice::HaplyDevice(HaplySettings s, std::shared_ptr<const Clock> clock)
    : DriverBase(std::move(clock)), s_(std::move(s)) {
  if (const std::string e = haply::validate(s_.board); !e.empty())
    throw DeviceError("haply: board wiring: " + e);
  spec_.model = s_.profile.name;
  spec_.driver = "haply";
  spec_.dof = 2;
  spec_.nominal_rate_hz = s_.rate_hz;
  for (std::size_t j = 0; j < 2; ++j) {
    spec_.joint_names[j] = "motor" + std::to_string(j + 1);
    spec_.peak_torque_nm[j] = s_.profile.joint_torque_limit_nm[j];
    spec_.max_continuous_torque_nm[j] = s_.profile.joint_torque_limit_nm[j];
    spec_.encoder_resolution_rad[j] = 2.0 * std::numbers::pi / s_.board.wiring[j].counts_per_rev;
    // Motor angles in hAPI's convention: from -180 to 360 degrees covers
    // every preset's rest pose and range.
    spec_.position_min_rad[j] = -std::numbers::pi;
    spec_.position_max_rad[j] = 2.0 * std::numbers::pi;
  }
}

HaplyDevice::~HaplyDevice() {
  close();
}

void HaplyDevice::handshake(SerialPort& port) {
  const std::string who = "haply (" + s_.port + "): ";
  const auto reset = haply::encode_reset();
  const auto setup = haply::encode_setup(s_.board);
  std::uint8_t request[haply::kMaxFrame];
  const std::size_t request_len = haply::encode_state(s_.board, JointArray{}, request);
  const std::size_t want = haply::reply_size(s_.board);
  const std::int64_t start = clock_->now_ns();
  const std::int64_t deadline = start + ms_to_ns(s_.open_timeout_ms);
  std::string seen = "no reply";
  // A board may still be booting when the port opens: repeat reset + setup
  // every 250 ms, with state requests in between, until one is answered.
  std::int64_t next_setup = start;
  while (clock_->now_ns() < deadline) {
    if (clock_->now_ns() >= next_setup) {
      if (port.write_all(reset.data(), reset.size(), 50) != SerialPort::Io::kOk ||
          port.write_all(setup.data(), setup.size(), 50) != SerialPort::Io::kOk)
        throw DeviceError(who + "cannot write the setup: " + std::strerror(port.error()));
      next_setup += 250'000'000;
    }
    port.discard_input();
    if (port.write_all(request, request_len, 50) == SerialPort::Io::kGone)
      throw DeviceError(who + "the port went away during the handshake");
    std::uint8_t reply[haply::kMaxFrame];
    std::size_t have = 0;
    const std::int64_t wait_until = clock_->now_ns() + 50'000'000;
    while (have < want && clock_->now_ns() < wait_until) {
      std::size_t got = 0;
      const auto io = port.read_some(reply + have, sizeof reply - have, got, 10);
      if (io == SerialPort::Io::kGone)
        throw DeviceError(who + "the port went away during the handshake");
      have += got;
    }
    if (have == 0) continue;
    JointArray deg{};
    const auto err = haply::decode_reply(s_.board, reply, have, deg);
    if (err != haply::ReplyError::kNone) {
      seen = std::to_string(have) + " bytes (" + std::string(haply::to_string(err)) + ")";
      continue;
    }
    JointArray q{};
    for (std::size_t j = 0; j < 2; ++j)
      q[j] = deg[j] * kDegToRad;
    if (const std::string e = check_workspace(q); !e.empty())
      throw DeviceError(who + e +
                        ": wrong `board` or `profile` for this device, or the handle was not at "
                        "rest when the board was set up (its encoders count from there: hold it "
                        "at rest, unplug and replug, start again)");
    const std::int64_t now = clock_->now_ns();
    sample_ = DeviceReading{};
    sample_.t_ns = now;
    sample_.sequence = 1;
    sample_.dof = 2;
    sample_.q = q;
    sample_.enabled = true;  // the host's request decides (apply_reading_rules)
    sample_.status = DeviceStatus::kOk;
    readings_.store(sample_);
    last_reply_ns_ = now;
    bad_replies_ = 0;
    return;
  }
  throw DeviceError(who + "the board did not answer within " +
                    std::to_string(static_cast<int>(s_.open_timeout_ms)) + " ms (" + seen +
                    "): is it a Haply board running Haply's firmware, on this port?");
}

std::string HaplyDevice::check_workspace(const JointArray& q) const {
  JointArray x{};
  Jacobian J{};
  char msg[256];
  if (!forward_kinematics(s_.profile.kinematics, q, x, J)) {
    std::snprintf(msg, sizeof msg, "motor angles %.1f and %.1f deg have no handle position in %s",
                  q[0] / kDegToRad, q[1] / kDegToRad, s_.profile.name.c_str());
    return msg;
  }
  const MasterProfile& p = s_.profile;
  const double m = s_.workspace_margin_m;
  for (std::size_t k = 0; k < 2; ++k) {
    if (x[k] < p.workspace_min[k] - m || x[k] > p.workspace_max[k] + m) {
      std::snprintf(msg, sizeof msg,
                    "motor angles %.1f and %.1f deg put the handle at (%.3f, %.3f) m, more than "
                    "%.3f m outside %s's workspace",
                    q[0] / kDegToRad, q[1] / kDegToRad, x[0], x[1], m, p.name.c_str());
      return msg;
    }
  }
  return "";
}

void HaplyDevice::open() {
  if (running_.load()) return;
  try {
    port_ = SerialPort(s_.port);
  } catch (const std::runtime_error& e) {
    throw DeviceError(std::string("haply: ") + e.what());
  }
  handshake(port_);
  unlatch_fault();
  port_fd_.store(port_.fd());
  link_up_.store(true);
  opened_.store(true);
  set_error("");
  running_.store(true);
  io_ = std::thread([this] { io_loop(); });
}

std::size_t HaplyDevice::zero_torque_frame(std::uint8_t* out) const noexcept {
  return haply::encode_state(s_.board, JointArray{}, out);
}

void HaplyDevice::close() noexcept {
  if (running_.exchange(false)) io_.join();
  port_fd_.store(-1);
  if (port_.is_open()) {
    // Zero torque before letting go: the board keeps the last torque it got.
    std::uint8_t frame[haply::kMaxFrame];
    const std::size_t n = haply::encode_state(s_.board, JointArray{}, frame);
    for (int attempt = 0; attempt < 3; ++attempt) {
      port_.discard_input();
      if (port_.write_all(frame, n, 20) != SerialPort::Io::kOk) break;
      std::uint8_t reply[haply::kMaxFrame];
      std::size_t have = 0, got = 0;
      while (have < haply::reply_size(s_.board) &&
             port_.read_some(reply + have, sizeof reply - have, got, 20) == SerialPort::Io::kOk)
        have += got;
      if (have == haply::reply_size(s_.board)) break;  // the board took it
    }
    port_.close();
  }
  link_up_.store(false);
  opened_.store(false);
}

bool HaplyDevice::clear_fault() {
  if (fault() == FaultCode::kNone) return true;
  if (!link_up_.load()) {
    // The I/O thread left the port alone when the link went down: reopen it here.
    try {
      SerialPort port(s_.port);
      handshake(port);
      port_ = std::move(port);
      port_fd_.store(port_.fd());
    } catch (const std::exception& e) {
      set_error(std::string(e.what()) + " (still faulted: the board was unplugged)");
      return false;
    }
    link_up_.store(true);
  } else if (fault() == FaultCode::kWorkspace) {
    DeviceReading now;
    realtime::LatestValueReader<DeviceReading> reader(readings_);
    reader.fetch(now);
    if (const std::string e = check_workspace(now.q); !e.empty()) {
      set_error("haply (" + s_.port + "): still faulted: " + e);
      return false;
    }
  }
  bad_replies_ = 0;
  unlatch_fault();
  set_error("");
  return true;
}

std::int64_t HaplyDevice::freshness_bound_ns() const noexcept {
  return ms_to_ns(s_.watchdog_ms);
}

void HaplyDevice::link_lost(const std::string& why) {
  port_fd_.store(-1);
  port_.close();
  link_up_.store(false);
  latch_fault(FaultCode::kLinkLost);
  set_error("haply (" + s_.port + "): " + why +
            ": unplugged? Torque is zero on this side; replug the board and clear the fault "
            "(the handshake runs again)");
}

bool HaplyDevice::exchange(realtime::LatestValueReader<Command>& commands) {
  Command c;
  commands.fetch(c);
  const std::int64_t sent = clock_->now_ns();
  const bool silent = sent - last_reply_ns_ > ms_to_ns(s_.watchdog_ms);
  const Torque torque = torque_to_send(c, sent, ms_to_ns(s_.command_timeout_ms), !silent);
  std::uint8_t frame[haply::kMaxFrame];
  const std::size_t n = haply::encode_state(s_.board, torque.tau, frame);
  // A reply that came after its request timed out would be taken for the
  // next one's: requests and replies have no sequence number.
  port_.discard_input();
  auto io = port_.write_all(frame, n, 10);
  if (io == SerialPort::Io::kGone || io == SerialPort::Io::kError) {
    link_lost(std::string("write: ") + std::strerror(port_.error()));
    return false;
  }
  const std::size_t want = haply::reply_size(s_.board);
  std::uint8_t reply[haply::kMaxFrame];
  std::size_t have = 0;
  // Wait for the reply up to the watchdog time, in slices short enough that
  // close() never waits long for this thread.
  const std::int64_t give_up = sent + ms_to_ns(s_.watchdog_ms);
  while (have < want && running_.load()) {
    const std::int64_t left = give_up - clock_->now_ns();
    if (left <= 0) break;
    std::size_t got = 0;
    io = port_.read_some(reply + have, sizeof reply - have, got,
                         static_cast<int>(std::clamp<std::int64_t>(left / 1'000'000 + 1, 1, 5)));
    if (io == SerialPort::Io::kGone || io == SerialPort::Io::kError) {
      link_lost(std::string("read: ") + std::strerror(port_.error()));
      return false;
    }
    have += got;
  }
  if (have < want)
    return true;  // silent: the next request carries zero torque once past the watchdog
  JointArray deg{};
  if (haply::decode_reply(s_.board, reply, have, deg) != haply::ReplyError::kNone) {
    if (++bad_replies_ >= s_.max_bad_replies && latch_fault(FaultCode::kBadReports)) {
      set_error("haply (" + s_.port + "): " + std::to_string(bad_replies_) +
                " malformed replies in a row");
    }
    return true;
  }
  bad_replies_ = 0;
  const std::int64_t arrived = clock_->now_ns();
  // The board samples its encoders between our request and its reply.
  const std::int64_t t = sent + (arrived - sent) / 2;
  const double dt = static_cast<double>(t - sample_.t_ns) * 1e-9;
  // Finite difference, low-passed at 150 Hz: encoder steps of 0.07-0.03 deg
  // at 1 kHz would otherwise read as +-1.3 rad/s of noise.
  const double alpha = dt > 0.0 ? dt / (dt + 1.0 / (2.0 * std::numbers::pi * 150.0)) : 0.0;
  for (std::size_t j = 0; j < 2; ++j) {
    const double q = deg[j] * kDegToRad;
    if (dt > 0.0) sample_.qd[j] += alpha * ((q - sample_.q[j]) / dt - sample_.qd[j]);
    sample_.q[j] = q;
  }
  sample_.t_ns = t;
  ++sample_.sequence;
  sample_.tau_commanded = torque.tau;
  readings_.store(sample_);
  last_reply_ns_ = arrived;
  if (fault() == FaultCode::kNone) {
    if (const std::string e = check_workspace(sample_.q); !e.empty()) {
      if (latch_fault(FaultCode::kWorkspace))
        set_error("haply (" + s_.port + "): " + e + " (encoders slipped, or a wrong board preset)");
    }
  }
  return true;
}

void HaplyDevice::io_loop() {
  realtime::LatestValueReader<Command> commands(commands_);
  const auto period_ns = static_cast<std::int64_t>(1e9 / s_.rate_hz);
  realtime::Pacer pace(period_ns, realtime::monotonic_now_ns());
  while (running_.load()) {
    if (!link_up_.load()) {
      sleep_ns(5'000'000);  // faulted until clear_fault() reopens the port
      pace = realtime::Pacer(period_ns, realtime::monotonic_now_ns());
      continue;
    }
    exchange(commands);
    // Pacing in real time (absolute deadlines); a late round trip skips the
    // missed deadlines rather than bunching requests to catch up.
    pace.advance(realtime::monotonic_now_ns());
    pace.wait_through_signals();
  }
}

std::vector<ConnectedDevice> list_serial_boards(const std::filesystem::path& sysfs_root) {
  std::vector<ConnectedDevice> out;
  std::error_code ec;
  const std::filesystem::path tty = sysfs_root / "class" / "tty";
  for (const auto& entry : std::filesystem::directory_iterator(tty, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("ttyACM", 0) != 0) continue;
    ConnectedDevice d;
    d.driver = "haply";
    d.path = "/dev/" + name;
    d.profile = "haply-2diy if it is a Haply board";
    // device -> the USB interface; its parent holds the USB device's IDs.
    const auto usb = std::filesystem::canonical(entry.path() / "device", ec).parent_path();
    if (!ec) {
      auto field = [&](const char* f) { return read_attribute(usb / f); };
      d.vendor_id =
          static_cast<std::uint16_t>(std::strtoul(field("idVendor").c_str(), nullptr, 16));
      d.product_id =
          static_cast<std::uint16_t>(std::strtoul(field("idProduct").c_str(), nullptr, 16));
      d.serial = field("serial");
      const std::string maker = field("manufacturer"), product = field("product");
      d.product = maker.empty() ? product : maker + " " + product;
    }
    out.push_back(std::move(d));
  }
  std::sort(out.begin(), out.end(),
            [](const ConnectedDevice& a, const ConnectedDevice& b) { return a.path < b.path; });
  return out;
}

void register_haply_driver(DriverRegistry& registry, std::shared_ptr<const Clock> clock) {
  registry.add(
      "haply", "Haply 2DIY pantograph board over USB serial (not yet verified on hardware)",
      [clock](const YAML::Node& settings, const DriverContext& ctx) {
        config::FieldReader r(settings, ctx.source, ctx.path);
        HaplySettings s = parse_haply_settings(r, ctx);
        const YAML::Node mapping = r.node("mapping");
        r.reject_unknown();
        MasterProfile profile = s.profile;
        auto device = std::make_unique<HaplyDevice>(std::move(s), clock);
        if (!mapping.IsDefined() || mapping.IsNull())
          return std::unique_ptr<Device>(std::move(device));
        MappingConfig m = parse_mapping(mapping, profile, ctx.source, r.field("mapping"));
        return std::unique_ptr<Device>(
            std::make_unique<MappedDevice>(std::move(device), std::move(profile), m));
      },
      [] { return list_serial_boards(); });
}

}  // namespace tsmh::master_devices
