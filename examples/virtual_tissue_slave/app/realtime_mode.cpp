#include "realtime_mode.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <atomic>
#include <bridge/link_session.hpp>
#include <bridge/node_link.hpp>
#include <bridge/receiver.hpp>
#include <bridge/sender.hpp>
#include <bridge/stop_signals.hpp>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <memory>
#include <realtime/clock.hpp>
#include <realtime/histogram.hpp>
#include <realtime/pacing.hpp>
#include <thread>

#include "virtual_tissue_slave/command_gate.hpp"
#include "virtual_tissue_slave/offline.hpp"

namespace tsmh::virtual_tissue_slave::app {
namespace {

// SIGINT/SIGTERM are blocked in every thread of the process and taken by a
// watcher thread with sigwait(): no handler, no global flag; the loop reads
// an atomic it owns.
class StopOnSignal {
 public:
  StopOnSignal() {
    set_ = bridge::block_terminating_signals();  // before any other thread exists
    watcher_ = std::thread([this] {
      int sig = 0;
      sigwait(&set_, &sig);
      stop_.store(true, std::memory_order_relaxed);
    });
  }
  ~StopOnSignal() {
    if (!stop_.load(std::memory_order_relaxed)) pthread_kill(watcher_.native_handle(), SIGTERM);
    watcher_.join();
  }
  StopOnSignal(const StopOnSignal&) = delete;
  StopOnSignal& operator=(const StopOnSignal&) = delete;
  bool requested() const noexcept { return stop_.load(std::memory_order_relaxed); }

 private:
  sigset_t set_{};
  std::atomic<bool> stop_{false};
  std::thread watcher_;
};

void try_realtime_priority(int priority) {
  if (priority <= 0) return;
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
    std::fprintf(stderr, "virtual-slave: note: mlockall failed (%s); continuing\n",
                 std::strerror(errno));
  sched_param sp{};
  sp.sched_priority = priority;
  if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0)
    std::fprintf(stderr,
                 "virtual-slave: note: SCHED_FIFO %d refused (%s); running with normal "
                 "scheduling\n",
                 priority, std::strerror(errno));
}

void fill_state(bridge::SlaveStateSample& out, const SlaveSample& s, const SlaveParams& p,
                std::int32_t status) {
  out.num_joints = kJoints;
  out.status = status;
  for (std::size_t j = 0; j < kJoints; ++j) {
    out.x_in[j] = s.measured[j].x_in;
    out.x_out[j] = s.measured[j].x_out;
    out.T1[j] = s.measured[j].T1;
    out.T3[j] = s.measured[j].T3;
    out.radius_m[j] = p.joints[j].radius_m;
  }
}

void fill_truth(bridge::SlaveTruthSample& out, const SlaveSample& s) {
  out.num_joints = kJoints;
  for (std::size_t j = 0; j < kJoints; ++j) {
    const JointTruth& t = s.truth[j];
    out.tau_out[j] = t.tau_out;
    out.friction[j] = t.friction;
    out.tau_in[j] = t.tau_in;
    out.x_out[j] = t.x_out;
    out.contact_force[j] = t.contact.force_n;
    out.indentation[j] = t.contact.indentation_m;
  }
}

// Only the loop thread: the bridge threads, started before, stay free to run
// elsewhere.
void pin_to_cpu(int cpu) {
  if (cpu < 0) return;
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  const int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
  if (rc != 0)
    std::fprintf(stderr, "virtual-slave: note: cannot pin to CPU %d (%s); not pinned\n", cpu,
                 std::strerror(rc));
}

// The newest MASTER_COMMAND into the gate's view. Version 0: none yet, or
// (practically never) the read gave up against the receive thread: keep the
// previous view, only its age grows. `bound`: the master session is bound
// (always true without a key); otherwise hold, whatever the last command said.
void take_command(bridge::Inbox<bridge::MasterCommandSample>& commands,
                  bridge::MasterCommandSample& cmd, CommandView& view, std::int64_t now_ns,
                  bool bound) {
  const std::uint64_t version = commands.latest(cmd);
  if (version != 0) {
    view.version = version;
    view.enable = cmd.enable && bound;
    view.clutch = cmd.clutch;
    for (std::size_t j = 0; j < kJoints; ++j)
      view.position_ref[j] = cmd.position_ref[j];
  }
  if (!bound) view.enable = false;
  if (view.version != 0) view.age_s = static_cast<double>(now_ns - cmd.receive_ns) * 1e-9;
}

// Says what the master session does, from its own thread (the loop never
// prints): bound to a master, a master's goodbye or silence (holding,
// waiting for the next), the end in FAULT.
class SessionLog {
 public:
  explicit SessionLog(const bridge::LinkSession* session) : session_(session) {
    if (session_ != nullptr) thread_ = std::thread([this] { run(); });
  }
  ~SessionLog() {
    stop_.store(true, std::memory_order_relaxed);
    if (thread_.joinable()) thread_.join();
  }
  SessionLog(const SessionLog&) = delete;
  SessionLog& operator=(const SessionLog&) = delete;

 private:
  void run() {
    std::uint64_t binds = 0;
    auto state = bridge::SessionState::kOpen;
    while (!stop_.load(std::memory_order_relaxed)) {
      report(binds, state);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    report(binds, state);
  }
  // Polled: a master may bind and leave between two looks (its goodbye
  // 10 ms after binding), so the counts decide, not the states alone.
  void report(std::uint64_t& binds, bridge::SessionState& state) const {
    using bridge::SessionState;
    const auto now = session_->state();
    const std::uint64_t b = session_->binds();
    if (state == SessionState::kBound &&
        (now == SessionState::kOpen || (b != binds && now == SessionState::kBound)))
      std::fprintf(stderr,
                   "virtual-slave: session: the master ended its session (goodbye, or silent "
                   "for more than 1 s): holding, waiting for the next master\n");
    if (b != binds) {
      const std::uint64_t brief = b - binds - (now == SessionState::kBound ? 1 : 0);
      if (brief > 0)
        std::fprintf(stderr,
                     "virtual-slave: session: %llu master session(s) began and ended within "
                     "20 ms\n",
                     static_cast<unsigned long long>(brief));
      if (now == SessionState::kBound)
        std::fprintf(stderr, "virtual-slave: session: following master %016llx\n",
                     static_cast<unsigned long long>(session_->peer()));
    }
    if (now != state && now == bridge::SessionState::kFault)
      bridge::print_session_fault("virtual-slave", "master", session_->fault(),
                                  ": holding, exiting in 2 s");
    binds = b;
    state = now;
  }

  const bridge::LinkSession* session_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

struct LoopTiming {
  realtime::LogHistogram lateness, compute;
  std::int64_t overruns = 0;
};

void print_summary(std::int64_t ticks, const LoopTiming& timing,
                   const bridge::OutboxStats& published,
                   const bridge::Inbox<bridge::MasterCommandSample>& commands) {
  const realtime::HistogramSummary l = timing.lateness.summary();
  const realtime::HistogramSummary c = timing.compute.summary();
  std::fprintf(stderr,
               "virtual-slave: %lld ticks, %lld overruns; lateness p50 %.0f us, p99 %.0f us, max "
               "%.0f us; tick compute p99 %.0f us; SLAVE_STATE published %llu, dropped %llu; "
               "MASTER_COMMAND accepted %llu, rejected %llu\n",
               static_cast<long long>(ticks), static_cast<long long>(timing.overruns), l.p50_us,
               l.p99_us, l.max_us, c.p99_us, static_cast<unsigned long long>(published.published),
               static_cast<unsigned long long>(published.dropped_full),
               static_cast<unsigned long long>(commands.stats().accepted),
               static_cast<unsigned long long>(commands.stats().rejected()));
  // A rejected command is never silent: say which and why (the last one).
  if (const auto r = commands.last_rejection())
    std::fprintf(stderr, "virtual-slave: last rejected MASTER_COMMAND: %s\n",
                 bridge::describe(*r, commands.channel()).c_str());
}

}  // namespace

int run_realtime_mode(const CliOptions& o) {
  const StopOnSignal stop;
  const Setup setup = make_setup(o, nullptr);
  CommandGateParams gate_params;
  gate_params.timeout_s = o.command_timeout_s;

  // Only authenticated peers move the slave (docs/bridge.md, "Authentication"):
  // the same options, key search and refusals as every standalone node.
  bridge::BridgeConfig config;
  if (const int status = bridge::resolve_node_link("virtual-slave", o.link, config)) return status;
  bridge::Receiver rx(config);
  bridge::Sender tx(config);
  // One master at a time (docs/bridge.md, "Sessions"): the slave binds to the
  // server that answers its SLAVE_STATE; after that server's goodbye or its
  // silence for longer than the session timeout it holds and serves the
  // next; any other keyed master meanwhile ends the session: hold, exit 4.
  std::unique_ptr<bridge::LinkSession> session;
  if (tx.signer() != nullptr)
    session =
        std::make_unique<bridge::LinkSession>(*tx.signer(), bridge::SessionOptions{.rearm = true});
  bridge::InboxOptions<bridge::MasterCommandSample> inbox_options;
  inbox_options.expected_joints = kJoints;
  inbox_options.session = session.get();
  auto& commands = rx.subscribe<bridge::MasterCommandSample>(inbox_options);
  // The truth goes out before the state of the same tick (the sender drains
  // its outboxes in creation order, LCM delivers one socket in order): a
  // consumer that sees SLAVE_STATE seq N then already holds SLAVE_TRUTH N.
  // The other order lost the match whenever the server's tick fell between
  // the two arrivals, for most ticks at some phases on a loaded host.
  auto& truth_box = tx.outbox<bridge::SlaveTruthSample>();
  auto& state_box = tx.outbox<bridge::SlaveStateSample>();

  VirtualSlave slave(setup.params, o.seed);
  for (int j = 0; j < kJoints; ++j)
    slave.joint(j).set_effects(setup.effects);
  const std::array<double, kJoints> home{0.0, 0.0};
  slave.settle(home, 0.5);
  CommandGate gate(gate_params, home);

  try_realtime_priority(o.rt_priority);
  rx.start();
  tx.start();
  const SessionLog session_log(session.get());
  std::fprintf(stderr,
               "virtual-slave: 1 kHz on %s, channels %sMASTER_COMMAND -> %sSLAVE_STATE, "
               "%sSLAVE_TRUTH; %s\n",
               config.url.c_str(), config.prefix.c_str(), config.prefix.c_str(),
               config.prefix.c_str(), tissue_description(setup.tissue).c_str());
  pin_to_cpu(o.cpu);

  // Everything the loop touches exists before it starts: no allocation,
  // locks, blocking I/O or printing inside.
  const std::int64_t period_ns =
      static_cast<std::int64_t>(setup.params.control_period_s * 1e9 + 0.5);
  const double dt = setup.params.control_period_s;
  const std::int64_t end_ticks =
      o.duration_s > 0 ? static_cast<std::int64_t>(o.duration_s / dt + 0.5) : -1;
  LoopTiming timing;
  bridge::MasterCommandSample cmd;
  bridge::SlaveStateSample state;
  bridge::SlaveTruthSample truth;
  CommandView view;
  std::int64_t seq = 0;
  const Reroute& rr = setup.reroute;
  bool rerouted = std::isnan(rr.at_s);

  // The project's pacing loop: absolute deadlines, re-based after an
  // overrun rather than bursting to catch up (realtime/pacing.hpp).
  realtime::Pacer pace(period_ns, realtime::monotonic_now_ns() + period_ns);
  bool session_over = false;
  // After a session FAULT the slave holds and keeps publishing (its messages
  // say FAULT) for this many ticks before it exits, so that a late process
  // of the other session learns it too and stops.
  constexpr std::int64_t kFaultLingerTicks = 2000;
  std::int64_t fault_ticks = 0;
  while (!stop.requested() && (end_ticks < 0 || seq < end_ticks)) {
    if (!pace.wait()) continue;  // a signal: check the stop request
    const std::int64_t woke = realtime::monotonic_now_ns();
    timing.lateness.record(woke - pace.due_ns());
    const bridge::SessionState session_state =
        session ? session->state() : bridge::SessionState::kBound;
    // Ends after this tick: the state it publishes already says holding.
    session_over = session_state == bridge::SessionState::kFault;
    take_command(commands, cmd, view, woke, session_state == bridge::SessionState::kBound);
    const auto& refs = gate.update(view, dt);
    if (!rerouted && slave.time() >= rr.at_s) {
      apply_reroute(slave, setup.params, rr, setup.joint_index);
      rerouted = true;
    }
    const SlaveSample& s = slave.tick(refs);

    // The sample was measured at the deadline of this tick.
    state.utime = pace.deadline_ns() / 1000;
    state.seq = seq;
    fill_state(state, s, setup.params, gate.status());
    truth.utime = state.utime;
    truth.seq = seq;
    fill_truth(truth, s);
    truth_box.publish(truth);
    state_box.publish(state);
    ++seq;
    const std::int64_t done = realtime::monotonic_now_ns();
    timing.compute.record(done - woke);
    timing.overruns += pace.advance(done);
    if (session_over && ++fault_ticks >= kFaultLingerTicks) break;
  }

  // A clean stop says goodbye: the server's session ends at once (it then
  // faults on a missing slave as before, but no next slave is mistaken for
  // a second one while this one is still "alive").
  if (session && !session_over) {
    session->close();
    state.utime = realtime::monotonic_now_ns() / 1000;
    state.seq = seq;
    state_box.publish(state);
  }
  rx.stop();
  tx.stop();
  print_summary(seq, timing, state_box.stats(), commands);
  if (session_over) {
    std::fprintf(stderr,
                 "virtual-slave: exit 4: the master session ended in FAULT (another keyed "
                 "master on the link); the joints were held\n");
    return 4;
  }
  return 0;
}

}  // namespace tsmh::virtual_tissue_slave::app
