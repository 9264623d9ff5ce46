// slave-node-skeleton: the minimal slave node of a real tendon-sheath robot
// for haptic-server (docs/real-robot.md). It is what a robot integrator
// writes; it depends on nothing of ours but the generated LCM types, their
// decoder for untrusted bytes (lcmtypes/message_decoder.hpp) and the
// bridge's message authentication (bridge/link_auth.hpp: a MAC trailer on
// every message, docs/bridge.md "Authentication") with its start-up and
// period (options, key, LCM, pacing, stop signals: bridge/node_link.hpp).
//
//   every period (1 kHz):  drain MASTER_COMMAND (newest wins)
//                          fresh and enabled -> position reference to the robot
//                          otherwise         -> hold (motors safe)
//                          read the sensors  -> publish SLAVE_STATE
//
// All robot I/O goes through RobotIo. StubRobot stands in for it so the
// skeleton runs without hardware: replace it with your driver where marked
// "REAL DRIVER". Nothing else needs to change for a two-joint arm.
//
//   slave-node-skeleton [--lcm-url URL] [--prefix ARM1_] [--rate-hz 1000]
//                       [--command-timeout-ms 100] [--duration S] [--key FILE | --insecure]

#include <signal.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <tsmh/master_command_t.hpp>
#include <tsmh/slave_state_t.hpp>
#include <tsmh/version.hpp>
#include <vector>

#include "bridge/link_auth.hpp"
#include "bridge/node_inbox.hpp"
#include "bridge/node_link.hpp"
#include "bridge/stop_signals.hpp"
#include "files/cli_numbers.hpp"
#include "realtime/clock.hpp"

namespace {

/// What the slave node needs from the robot, per joint. Units and signs are
/// the contract of SLAVE_STATE (docs/real-robot.md, docs/lcm-messages.md).
struct JointSample {
  double x_in = 0.0;   ///< motor-side input pulley angle, rad (motor encoder / gear ratio)
  double x_out = NAN;  ///< joint angle, rad; NaN when the joint has no encoder
  double T1 = 0.0;     ///< proximal tension of tendon 1, N: pulling it turns the joint +
  double T3 = 0.0;     ///< proximal tension of tendon 3, N: pulling it turns the joint -
};

class RobotIo {
 public:
  virtual ~RobotIo() = default;
  virtual int joints() const = 0;
  /// Input pulley radius R of joint j, m (tau_in = R (T1 - T3)).
  virtual double radius_m(int j) const = 0;
  /// Reads every joint's sensors now. false: a sensor fault (status bit 2).
  virtual bool read(std::vector<JointSample>& out) = 0;
  /// Position reference for joint j, rad, from the master (already scaled).
  virtual void command_position(int j, double rad) = 0;
  /// No fresh, enabled command: keep the current position, motors safe.
  virtual void hold() = 0;
};

/// REAL DRIVER: replace this class with one that talks to your motor
/// controllers and load-cell amplifiers (EtherCAT, CAN, serial ...). This
/// stand-in moves each motor towards its reference with a first-order lag
/// and makes tensions from a stiff spring, so the server sees plausible data.
class StubRobot final : public RobotIo {
 public:
  explicit StubRobot(double dt) : dt_(dt) {}
  int joints() const override { return 2; }
  double radius_m(int) const override { return 0.01; }
  bool read(std::vector<JointSample>& out) override {
    out.resize(2);
    for (int j = 0; j < 2; ++j) {
      // REAL DRIVER: motor encoder counts -> rad at the input pulley.
      x_in_[j] += (ref_[j] - x_in_[j]) * dt_ / 0.02;
      // REAL DRIVER: joint encoder (or NaN), load cells (N, tared).
      x_out_[j] += (x_in_[j] - x_out_[j]) * dt_ / 0.01;
      const double stretch = x_in_[j] - x_out_[j];
      auto& s = out[static_cast<std::size_t>(j)];
      s.x_in = x_in_[j];
      s.x_out = x_out_[j];
      s.T1 = 20.0 + 500.0 * stretch;  // 20 N pretension per tendon
      s.T3 = 20.0 - 500.0 * stretch;
    }
    return true;
  }
  void command_position(int j, double rad) override { ref_[j] = rad; }
  void hold() override {
    for (int j = 0; j < 2; ++j)
      ref_[j] = x_in_[j];
  }

 private:
  double dt_;
  double x_in_[2] = {0.0, 0.0};
  double x_out_[2] = {0.0, 0.0};
  double ref_[2] = {0.0, 0.0};
};

/// The newest MASTER_COMMAND and when it arrived (this node's clock: the
/// server's utime is on another host's clock when the nodes are apart).
struct CommandInbox {
  CommandInbox(const tsmh::bridge::NodeLink& node, int n) : link(node, n) {}
  tsmh::master_command_t newest;
  /// Verify, session, then the project's checked decoder: exactly `n` joints
  /// and the exact size for them, checked before anything is allocated
  /// (lcm-gen's decode() alone sizes its arrays for whatever num_joints the
  /// bytes claim).
  tsmh::bridge::NodeInbox<tsmh::master_command_t> link;
  std::int64_t received_ns = 0;
  std::int64_t last_seq = -1;
  void on_raw(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    // Only the bound server's commands move the robot.
    if (const auto* msg = link.receive(rbuf->data, rbuf->data_size, channel)) on_command(*msg);
  }
  // `msg` holds exactly the node's joints (the decoder's range).
  void on_command(const tsmh::master_command_t& msg) {
    // NaN/Inf, duplicate or old: never moves the robot.
    if (msg.seq <= last_seq) return link.reject("duplicate or old seq");
    for (int j = 0; j < msg.num_joints; ++j)
      if (!std::isfinite(msg.position_ref[static_cast<std::size_t>(j)]))
        return link.reject("position_ref is not finite");
    newest = msg;
    last_seq = msg.seq;
    received_ns = tsmh::realtime::monotonic_now_ns();
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "slave-node-skeleton: the minimal slave node of a real robot for haptic-server "
      "(robot I/O stubbed; docs/real-robot.md)"};
  app.set_version_flag("--version", tsmh::version_line("slave-node-skeleton"));
  double rate_hz = 1000.0;
  double command_timeout_ms = 100.0;
  double duration_s = 0.0;
  tsmh::bridge::NodeLinkOptions link;
  tsmh::bridge::add_node_link_options(
      app, link, "--prefix", "per-arm channel prefix, e.g. ARM1_ -> ARM1_SLAVE_STATE",
      "run without a link key on a network LCM URL: anyone who reaches it can move the robot "
      "(isolated networks only)");
  app.add_option("--rate-hz", rate_hz, "control and SLAVE_STATE rate")
      ->check(tsmh::files::finite_range(100.0, 4000.0, "Hz"));
  app.add_option("--command-timeout-ms", command_timeout_ms,
                 "hold when the newest MASTER_COMMAND is older")
      ->check(CLI::PositiveNumber);
  app.add_option("--duration", duration_s, "stop after this many seconds (0: until Ctrl-C)")
      ->check(tsmh::files::finite_range(0.0, 1e7, "s"));
  CLI11_PARSE(app, argc, argv);
  // Every signal that would end the process by default and can be caught
  // (SIGINT, SIGTERM, SIGHUP when the terminal closes, ...) stops through the
  // hold below; SIGPIPE is ignored. Before LCM starts any thread.
  const sigset_t stop_signals = tsmh::bridge::block_terminating_signals();

  // Only authenticated peers move the robot: MASTER_COMMAND must carry a
  // valid MAC, and SLAVE_STATE carries ours, when a link key exists.
  // A real robot serves the next server after this one's goodbye or its
  // silence for more than the session timeout (1 s), holding meanwhile.
  tsmh::bridge::NodeLink node;
  if (const int status = tsmh::bridge::start_node_link("slave-node-skeleton", link, node))
    return status;
  lcm::LCM& lcm = *node.lcm;
  const auto& session = node.session;
  // Each period: MASTER_COMMAND drained, the session ticked (a silent server
  // ends it after 1 s), then the robot and SLAVE_STATE.
  tsmh::bridge::NodeTicker ticker(node, rate_hz, duration_s, stop_signals);
  StubRobot robot(static_cast<double>(ticker.period_ns()) * 1e-9);  // REAL DRIVER: your RobotIo
  const int n = robot.joints();
  CommandInbox inbox(node, n);
  lcm.subscribe(link.prefix + "MASTER_COMMAND", &CommandInbox::on_raw, &inbox);
  const std::string state_channel = link.prefix + "SLAVE_STATE";
  std::vector<std::uint8_t> bytes;

  tsmh::slave_state_t state;
  state.num_joints = n;
  const auto un = static_cast<std::size_t>(n);
  state.x_in.resize(un);
  state.x_out.resize(un);
  state.T1.resize(un);
  state.T3.resize(un);
  state.radius_m.resize(un);
  for (int j = 0; j < n; ++j)
    state.radius_m[static_cast<std::size_t>(j)] = robot.radius_m(j);
  std::vector<JointSample> samples;

  std::int64_t seq = 0;
  std::int64_t holds = 0;
  bool was_driving = false;
  bool session_over = false;
  // After a session FAULT: hold and keep publishing (the messages say FAULT)
  // for 2 s, so that a late process of the other session stops too; then exit 4.
  std::int64_t fault_since = 0;
  while ((!session_over || tsmh::realtime::monotonic_now_ns() - fault_since < 2'000'000'000) &&
         ticker.next()) {
    const std::int64_t now = ticker.now_ns();
    const bool fresh = inbox.received_ns > 0 && now - inbox.received_ns <= command_timeout_ms * 1e6;
    // Without a bound session (between servers, or after another master
    // appeared) the robot holds, whatever the last command said.
    const auto session_state = session ? session->state() : tsmh::bridge::SessionState::kBound;
    if (!session_over && session_state == tsmh::bridge::SessionState::kFault)
      fault_since = tsmh::realtime::monotonic_now_ns();
    session_over = session_state == tsmh::bridge::SessionState::kFault;
    const bool driving =
        fresh && inbox.newest.enable && session_state == tsmh::bridge::SessionState::kBound;
    if (driving) {
      // While the operator clutches, the server freezes the reference: just follow it.
      for (int j = 0; j < n; ++j)
        robot.command_position(j, inbox.newest.position_ref[static_cast<std::size_t>(j)]);
    } else {
      if (was_driving) ++holds;
      robot.hold();
    }
    was_driving = driving;

    const bool sensors_ok = robot.read(samples);
    // utime: this node's CLOCK_MONOTONIC at the moment the sensors were read.
    state.utime = tsmh::realtime::monotonic_utime();
    state.seq = seq++;
    for (std::size_t j = 0; j < un; ++j) {
      state.x_in[j] = samples[j].x_in;
      state.x_out[j] = samples[j].x_out;
      state.T1[j] = samples[j].T1;
      state.T3[j] = samples[j].T3;
    }
    state.status = (driving ? 1 : 0) | (driving ? 0 : 2) | (sensors_ok ? 0 : 4);
    tsmh::bridge::publish_message(node, state_channel, state, bytes);
  }
  robot.hold();
  if (session && !session_over) {
    // Goodbye: the last state ends the server's session at once.
    session->close();
    state.utime = tsmh::realtime::monotonic_utime();
    state.seq = seq++;
    state.status = 2;
    tsmh::bridge::publish_message(node, state_channel, state, bytes);
  }
  std::printf(
      "slave-node-skeleton: sent %lld SLAVE_STATE, holds %lld, rejected commands %lld, "
      "unauthenticated commands %lld\n",
      static_cast<long long>(seq), static_cast<long long>(holds),
      static_cast<long long>(inbox.link.rejected()),
      static_cast<long long>(inbox.link.unauthentic()));
  if (session_over)
    return tsmh::bridge::session_fault_exit("slave-node-skeleton", "master", session->fault(),
                                            "holding", inbox.link.other_session(), "commands");
  return 0;
}
