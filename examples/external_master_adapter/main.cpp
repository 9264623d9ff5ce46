// external-master-adapter: bridges a haptic master whose vendor SDK runs
// outside haptic-server to the server's `lcm` driver.
//
//   every period:  read the device -> publish MASTER_STATE
//                  newest MASTER_FORCE -> device torque
//   watchdog:      no MASTER_FORCE for --watchdog-ms (server or network
//                  gone) or enable false -> zero torque. The server answers
//                  every MASTER_STATE, so forces stop exactly when it dies.
//
// The vendor's calls sit behind master_devices/vendor_master.hpp (--vendor
// NAME): `simulated` (the default) stands in for the SDK; novint-falcon,
// force-dimension and openhaptics are stubs that refuse to run until built
// with the vendor's SDK. The device's joint count and kinematics come from the master
// profile (--profile, master_devices/profiles/masters/); the mapping layer
// (master_devices/axis_mapping.hpp, --mapping) turns the device's own
// coordinates into the slave's joints for MASTER_STATE and the server's
// per-slave-joint MASTER_FORCE back into device joint torques through the
// Jacobian transpose, within the profile's limits. Without --profile: a
// two-joint console mapped joint to joint.
//
//   external-master-adapter [--profile FILE --mapping FILE] [--lcm-url URL]
//                           [--prefix LEFT_] [--rate-hz 1000] [--watchdog-ms 50]
//                           [--duration S] [--key FILE | --insecure]
// With the installation's link key (docs/bridge.md, "Authentication") every
// MASTER_STATE carries a MAC and only MASTER_FORCE that verifies drives the
// motors, from one server session at a time (bridge/link_session.hpp).
// Project code it uses: the bridge's link_auth.hpp and link_session.hpp,
// its node start-up and period (node_link.hpp: options, key, LCM, pacing,
// stop signals), and the message decoder every receiver of ours uses
// (lcmtypes/message_decoder.hpp).
// Server side: device: {driver: lcm, settings: {channel_prefix: LEFT_}}

#include <signal.h>
#include <yaml-cpp/yaml.h>

#include <CLI/CLI.hpp>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <tsmh/master_force_t.hpp>
#include <tsmh/master_state_t.hpp>
#include <tsmh/version.hpp>
#include <vector>

#include "bridge/link_auth.hpp"
#include "bridge/node_inbox.hpp"
#include "bridge/node_link.hpp"
#include "bridge/stop_signals.hpp"
#include "files/cli_numbers.hpp"
#include "master_devices/axis_mapping.hpp"
#include "master_devices/vendor_master.hpp"
#include "realtime/clock.hpp"

namespace {

// Without --profile: the two-joint console this adapter always modelled,
// each slave joint following the master joint of the same index.
tsmh::master_devices::MasterProfile default_profile() {
  return tsmh::master_devices::parse_master_profile(R"(
name: generic-2dof
update_rate_hz: 1000
kinematics: {type: identity, joints: 2}
axes: [joint1, joint2]
workspace: {min: -1.0, max: 1.0}
force_limit: 0.3
buttons: [dead_man]
)",
                                                    "built-in profile");
}
constexpr const char* kDefaultMapping = R"(
joints: [{axis: joint1}, {axis: joint2}]
buttons: {dead_man: dead_man}
)";

struct ForceInbox {
  ForceInbox(const tsmh::bridge::NodeLink& node, std::size_t slave_joints)
      : joints(slave_joints), link(node, static_cast<std::int32_t>(slave_joints)) {}
  std::size_t joints;  ///< the slave joints MASTER_STATE carries
  tsmh::master_devices::JointArray torque{};
  bool enable = false;
  std::int64_t received_ns = 0;
  /// Verify, session, then the project's MASTER_FORCE decoder: exactly
  /// `joints` joints and the exact size for them, checked before anything is
  /// allocated. lcm-gen's decode() alone sizes its arrays for whatever
  /// num_joints the bytes claim: a key holder's (or, without a key, anyone's)
  /// MASTER_FORCE claiming 2^28 joints made it allocate gigabytes and crash.
  tsmh::bridge::NodeInbox<tsmh::master_force_t> link;

  void on_raw(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    // Only the bound server's forces drive the motors.
    if (const auto* msg = link.receive(rbuf->data, rbuf->data_size, channel)) on_force(*msg);
  }

  // `msg` holds exactly `joints` joints (the decoder's range).
  void on_force(const tsmh::master_force_t& msg) {
    for (std::size_t j = 0; j < joints; ++j) {
      if (!std::isfinite(msg.torque[j])) return link.reject("torque is not finite");
    }
    for (std::size_t j = 0; j < joints; ++j)
      torque[j] = msg.torque[j];
    enable = msg.enable;
    received_ns = tsmh::realtime::monotonic_now_ns();
  }
};

// A crash (the core-dumping signals: SIGSEGV, SIGABRT, SIGBUS, SIGFPE, SIGILL,
// SIGTRAP, SIGSYS) must not leave the motors driven either: the handler zeroes
// the device's torque with async-signal-safe calls only, then lets the signal
// end the process as it would have (default action restored, raised again).
// A handler has no context argument: the device is reached through this one
// static pointer.
std::atomic<tsmh::master_devices::VendorMaster*> g_crash_device{nullptr};

void on_crash_signal(int sig) {
  if (tsmh::master_devices::VendorMaster* device = g_crash_device.load())
    device->zero_from_signal_handler();
  raise(sig);  // SA_RESETHAND restored the default; delivered when we return
}

void zero_torque_on_crash(tsmh::master_devices::VendorMaster& device) {
  g_crash_device.store(&device);
  struct sigaction sa {};
  sa.sa_handler = on_crash_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND;
  for (int s : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGTRAP, SIGSYS})
    sigaction(s, &sa, nullptr);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"external-master-adapter: a vendor master driver talking to haptic-server over LCM"};
  app.set_version_flag("--version", tsmh::version_line("external-master-adapter"));
  double rate_hz = 1000.0;
  double watchdog_ms = 50.0;
  double duration_s = 0.0;
  tsmh::bridge::NodeLinkOptions link;
  tsmh::bridge::add_node_link_options(
      app, link, "--prefix,--channel-prefix",
      "per-arm channel prefix, e.g. LEFT_ -> LEFT_MASTER_STATE (--channel-prefix: old name)",
      "run without a link key on a network LCM URL: anyone who reaches it can drive the "
      "master's motors (isolated networks only)");
  app.add_option("--rate-hz", rate_hz, "device read / MASTER_STATE rate")
      ->check(tsmh::files::finite_range(1.0, 20000.0, "Hz"));
  app.add_option("--watchdog-ms", watchdog_ms, "zero torque when MASTER_FORCE is older")
      ->check(CLI::PositiveNumber);
  app.add_option("--duration", duration_s, "stop after this many seconds (0: until Ctrl-C)")
      ->check(tsmh::files::finite_range(0.0, 1e7, "s"));
  std::string profile_file, mapping_file, vendor = "simulated";
  app.add_option("--vendor", vendor,
                 "the device's calls (master_devices/vendor_master.hpp): simulated (default), or "
                 "novint-falcon, force-dimension, openhaptics: stubs until built with the "
                 "vendor's SDK");
  app.add_option("--profile", profile_file,
                 "master profile: kinematics, workspace, limits, buttons "
                 "(master_devices/profiles/masters/*.yaml; default: a 2-joint console)");
  app.add_option("--mapping", mapping_file,
                 "the mapping to the slave's joints: joints: [{axis: NAME, scale: S}], "
                 "buttons: {dead_man: NAME, clutch: NAME, ...} (needed with --profile)");
  CLI11_PARSE(app, argc, argv);
  // Every signal that would end the process by default and can be caught
  // (SIGINT, SIGTERM, SIGHUP when the terminal closes, ...) stops through the
  // zero-torque path; SIGPIPE is ignored. Before LCM starts any thread.
  const sigset_t stop_signals = tsmh::bridge::block_terminating_signals();

  tsmh::master_devices::MasterProfile profile;
  tsmh::master_devices::MappingConfig mapping_cfg;
  try {
    if (profile_file.empty() != mapping_file.empty())
      throw tsmh::config::ConfigError("--profile and --mapping go together");
    profile = profile_file.empty() ? default_profile()
                                   : tsmh::master_devices::load_master_profile(profile_file);
    const YAML::Node m =
        mapping_file.empty() ? YAML::Load(kDefaultMapping) : YAML::LoadFile(mapping_file);
    mapping_cfg = tsmh::master_devices::parse_mapping(
        m, profile, mapping_file.empty() ? "built-in mapping" : mapping_file, "");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "external-master-adapter: error: %s\n", e.what());
    return 2;
  }
  tsmh::master_devices::MasterMapping mapping(profile, mapping_cfg);
  const std::size_t slave_joints = mapping.slave_joints();
  std::fprintf(stderr,
               "external-master-adapter: master %s (%zu joints, %s kinematics) -> %zu slave "
               "joints\n",
               profile.name.c_str(), profile.kinematics.joints,
               std::string(to_string(profile.kinematics.type)).c_str(), slave_joints);

  // The next server is served after this one's goodbye or its silence for
  // more than the session timeout (1 s); zero torque meanwhile.
  tsmh::bridge::NodeLink node;
  if (const int status = tsmh::bridge::start_node_link("external-master-adapter", link, node))
    return status;
  lcm::LCM& lcm = *node.lcm;
  const auto& session = node.session;
  ForceInbox inbox(node, slave_joints);
  lcm.subscribe(link.prefix + "MASTER_FORCE", &ForceInbox::on_raw, &inbox);
  const std::string state_channel = link.prefix + "MASTER_STATE";
  std::vector<std::uint8_t> bytes;

  // The hand sweeps 0.2 rad at the joints, or 40 % of the half-workspace
  // of a device that reports its handle (m).
  const double amplitude =
      profile.kinematics.type == tsmh::master_devices::KinematicsType::kIdentity &&
              !profile_file.empty()
          ? 0.4 * 0.5 * (profile.workspace_max[0] - profile.workspace_min[0])
          : 0.2;
  std::unique_ptr<tsmh::master_devices::VendorMaster> device;
  try {
    device = tsmh::master_devices::make_vendor_master(vendor, profile, rate_hz, amplitude);
    device->open();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "external-master-adapter: error: %s\n", e.what());
    return 3;
  }
  zero_torque_on_crash(*device);
  tsmh::master_state_t state;
  state.num_joints = static_cast<int>(slave_joints);
  state.q.resize(slave_joints);
  state.qd.resize(slave_joints);
  tsmh::master_devices::JointArray v_prev{};
  bool have_prev = false;
  std::int64_t seq = 0;
  std::int64_t watchdog_trips = 0;
  bool was_fresh = false;
  bool session_over = false;

  // Each period: MASTER_FORCE drained, the session ticked (a silent server
  // ends it after 1 s), then the device and MASTER_STATE.
  tsmh::bridge::NodeTicker ticker(node, rate_hz, duration_s, stop_signals);
  const double dt = static_cast<double>(ticker.period_ns()) * 1e-9;
  while (!session_over && ticker.next()) {
    const std::int64_t now = ticker.now_ns();
    const bool fresh = inbox.received_ns > 0 && now - inbox.received_ns <= watchdog_ms * 1e6;
    if (was_fresh && !fresh) {
      // Once per trip, not per period: the operator learns why the handle went limp.
      ++watchdog_trips;
      std::fprintf(stderr,
                   "external-master-adapter: no MASTER_FORCE for %.0f ms (watchdog): torque "
                   "zeroed\n",
                   static_cast<double>(now - inbox.received_ns) * 1e-6);
    }
    was_fresh = fresh;
    // Torque only from the bound server's session; another server ends it.
    const auto session_state = session ? session->state() : tsmh::bridge::SessionState::kBound;
    session_over = session_state == tsmh::bridge::SessionState::kFault;
    const bool bound = session_state == tsmh::bridge::SessionState::kBound;
    // Slave-joint torques -> the handle -> the device's joints (J^T), within
    // the profile's limits; the pose is the one of the previous update.
    device->write(fresh && inbox.enable && bound ? mapping.joint_torques(inbox.torque)
                                                 : tsmh::master_devices::JointArray{});
    tsmh::master_devices::JointArray coordinates{};
    std::uint32_t buttons = 0;
    const bool pose_ok = device->read(coordinates, buttons) && mapping.update(coordinates, buttons);

    state.utime = now / 1000;
    state.seq = seq++;
    const auto& v = mapping.slave_position();
    for (std::size_t j = 0; j < slave_joints; ++j) {
      state.q[j] = v[j];
      state.qd[j] = have_prev ? (v[j] - v_prev[j]) / dt : 0.0;
    }
    v_prev = v;
    have_prev = true;
    const auto b = mapping.buttons();
    state.buttons =
        (b.dead_man ? 1 : 0) | (b.e_stop ? 2 : 0) | (b.clutch ? 4 : 0) | (b.calibrate ? 8 : 0);
    state.status = pose_ok ? 0 : 1;  // bit 0 fault: no pose (the kinematics has no solution)
    tsmh::bridge::publish_message(node, state_channel, state, bytes);
  }
  device->write({});
  device->close();
  std::printf(
      "external-master-adapter: sent %lld MASTER_STATE, watchdog trips %lld, rejected forces "
      "%lld%s%s%s, unauthenticated forces %lld\n",
      static_cast<long long>(seq), static_cast<long long>(watchdog_trips),
      static_cast<long long>(inbox.link.rejected()),
      inbox.link.rejected() > 0 ? " (the last: " : "", inbox.link.last_rejection(),
      inbox.link.rejected() > 0 ? ")" : "", static_cast<long long>(inbox.link.unauthentic()));
  if (session_over)
    return tsmh::bridge::session_fault_exit("external-master-adapter", "server", session->fault(),
                                            "torque zero", inbox.link.other_session(), "forces");
  return 0;
}
