// bench_teleop_delay: the benchmark scenario of delayed
// teleoperation, in simulated time and in one process, so it is
// deterministic and independent of this machine's load:
//
//   simulated operator (sim device, light grip) -> HapticLoop -> forward
//   DelayLine -> CommandGate + VirtualSlave (nodule tissue) -> backward
//   DelayLine -> HapticLoop ...
//
// The operator presses into the hard nodule and holds for 5 s. For each
// round-trip delay (0, 10, 50, 100 ms by default; jitter 20 % of each
// one-way delay, 1 % loss each way) the run is repeated with the passivity
// controller off and on. Printed per run: peak-to-peak rendered torque over
// the hold after 1 s of settling (and as a share of the hold torque),
// overshoot, stiffness felt on the nodule, the observer's energy and the
// controller's dissipation, and whether the oscillation detector would have
// tripped (it is off in the loop here, so that the raw behaviour is
// measured; a separate detector watches the rendered torque). Also the
// loop's compute time per tick (p50/p99) with the controller off and on.
//
//   bench_teleop_delay [--rtt-ms 0,10,50,100] [--jitter 0.2] [--loss 0.01]
//                      [--seed N] [--output DIR] [--params FILE]
// --output writes DIR/delay-<rtt>-<off|on>.csv (t, q, torque, W_M) and
// DIR/delay-table.md for scripts/bench-delay's plot.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "delay_relay/link_impairment.hpp"
#include "estimator/model_io.hpp"
#include "haptics/evaluation.hpp"
#include "haptics/haptic_loop.hpp"
#include "master_devices/sim_device.hpp"
#include "realtime/quantile.hpp"
#include "virtual_tissue_slave/command_gate.hpp"
#include "virtual_tissue_slave/slave.hpp"
#include "virtual_tissue_slave/tissue.hpp"

namespace {

using namespace tsmh;
namespace vs = tsmh::virtual_tissue_slave;
constexpr std::int64_t kMs = 1'000'000;

struct StatePair {
  bridge::SlaveStateSample state;
  bridge::SlaveTruthSample truth;
};

/// The network and the slave node in one: the loop's SlaveLink on one side,
/// the virtual slave behind two DelayLines on the other.
class DelayedSlave final : public haptics::SlaveLink {
 public:
  DelayedSlave(const delay_relay::ImpairmentParams& fwd, const delay_relay::ImpairmentParams& back,
               std::uint64_t seed, const vs::TissueParams& tissue)
      : to_slave_(fwd, seed * 2 + 1),
        to_master_(back, seed * 2 + 2),
        slave_(vs::paper_slave(), seed),
        gate_({}, {0.0, 0.0}) {
    for (int j = 0; j < vs::kJoints; ++j)
      slave_.joint(j).set_tissue(tissue);
    slave_.settle({0.0, 0.0}, 0.5);
  }

  /// The slave node's tick at now_ns, then what the network delivers by then.
  void step(std::int64_t now_ns) {
    bridge::MasterCommandSample cmd;
    while (to_slave_.pop_due(now_ns, cmd)) {
      view_.version++;
      view_.enable = cmd.enable;
      view_.clutch = cmd.clutch;
      for (std::size_t j = 0; j < vs::kJoints; ++j)
        view_.position_ref[j] = cmd.position_ref[j];
      cmd_receive_ns_ = now_ns;
    }
    if (view_.version != 0) view_.age_s = static_cast<double>(now_ns - cmd_receive_ns_) * 1e-9;
    const auto& refs = gate_.update(view_, 0.001);
    const vs::SlaveSample& s = slave_.tick(refs);
    StatePair p;
    p.state.utime = now_ns / 1000;
    p.state.seq = seq_;
    p.state.num_joints = vs::kJoints;
    p.state.status = gate_.status();
    p.truth.utime = p.state.utime;
    p.truth.seq = seq_++;
    p.truth.num_joints = vs::kJoints;
    for (std::size_t j = 0; j < vs::kJoints; ++j) {
      p.state.x_in[j] = s.measured[j].x_in;
      p.state.x_out[j] = s.measured[j].x_out;
      p.state.T1[j] = s.measured[j].T1;
      p.state.T3[j] = s.measured[j].T3;
      p.state.radius_m[j] = slave_.params().joints[j].radius_m;
      p.truth.tau_out[j] = s.truth[j].tau_out;
      p.truth.x_out[j] = s.truth[j].x_out;
      p.truth.indentation[j] = s.truth[j].contact.indentation_m;
      p.truth.contact_force[j] = s.truth[j].contact.force_n;
    }
    to_master_.push(now_ns, p);
    StatePair in;
    while (to_master_.pop_due(now_ns, in)) {
      latest_ = in;
      latest_.state.receive_ns = now_ns;
      ++version_;
    }
    now_ns_ = now_ns;
  }

  std::uint64_t latest_state(bridge::SlaveStateSample& out) noexcept override {
    if (version_ == 0) return 0;
    out = latest_.state;
    return version_;
  }
  std::uint64_t latest_truth(bridge::SlaveTruthSample& out) noexcept override {
    if (version_ == 0) return 0;
    out = latest_.truth;
    return version_;
  }
  void publish_command(const bridge::MasterCommandSample& cmd) noexcept override {
    to_slave_.push(now_ns_, cmd);  // the bench allocates; the loop never waits for it
  }
  void publish_status(const bridge::HapticStatusSample&) noexcept override {}
  haptics::SlaveLinkStats stats() const noexcept override { return {}; }
  const bridge::SlaveTruthSample& truth() const { return latest_.truth; }

 private:
  delay_relay::DelayLine<bridge::MasterCommandSample> to_slave_;
  delay_relay::DelayLine<StatePair> to_master_;
  vs::VirtualSlave slave_;
  vs::CommandGate gate_;
  vs::CommandView view_;
  std::int64_t cmd_receive_ns_ = 0;
  std::int64_t seq_ = 0;
  std::int64_t now_ns_ = 0;
  StatePair latest_{};
  std::uint64_t version_ = 0;
};

struct Options {
  std::vector<double> rtt_ms{0, 10, 50, 100};
  double jitter = 0.2;  // of each one-way delay
  double loss = 0.01;
  std::uint64_t seed = 21;
  std::string output;
  std::string params = "paper";
  double hand_stiffness =
      3.0;                    // the sim operator's defaults (master_devices/simulated_operator.hpp)
  double hand_damping = 0.2;  // N m s/rad
  double depth_rad = 0.5;     // the operator's intention: 0.15 rad into the nodule
  double max_damping = 1.0;   // passivity.max_damping_nms_per_rad
};

// The scenario's times (s).
constexpr double kStart = 0.5, kPress = 1.0, kHold = 5.0, kRelease = 0.8, kEnd = 0.5;
constexpr double kHoldFrom = kStart + kPress, kHoldTo = kHoldFrom + kHold;
constexpr double kSettle = 1.0;  // oscillation is judged from kHoldFrom + kSettle

struct Result {
  double rtt_ms = 0;
  bool pc = false;
  double hold_nm = 0, p2p_nm = 0, osc_p2p_nm = 0, amplitude_pct = 0, overshoot_pct = 0;
  double stiffness = 0;
  double energy_min = 0, energy_end = 0, dissipated = 0;
  std::uint64_t detector_trips = 0;
  std::vector<double> compute_ns;
};

/// Joint 0's rows, as the loop traces them.
class Rows final : public haptics::TraceSink {
 public:
  void append(const haptics::TraceRow& row) noexcept override {
    t.push_back(row.t);
    q.push_back(row.joints[0].master_q);
    tau.push_back(row.joints[0].torque_cmd);
    indentation.push_back(row.joints[0].indentation);
    for (std::size_t j = 0; j < 2; ++j)
      last[j] = row.joints[j].torque_cmd;
  }
  int joints() const noexcept override { return 2; }
  std::vector<double> t, q, tau, indentation;
  haptics::JointArray last{};  ///< torque rendered at the last tick, per joint
};

using realtime::quantile;

Result run(const Options& o, double rtt_ms, bool pc) {
  master_devices::SimSettings sim;
  sim.simulated_time = true;
  sim.dof = 2;
  master_devices::PalpateScenario sc;
  sc.soft_presses = 0;
  sc.hard_presses = 1;
  sc.hard_depth_rad = o.depth_rad;
  sc.start_s = kStart;
  sc.press_s = kPress;
  sc.hold_s = kHold;
  sc.release_s = kRelease;
  sc.rest_s = 0.0;
  sc.end_s = kEnd;
  sc.other_amplitude_rad = 0.0;
  sim.scenario = sc;
  sim.hand.stiffness_nm_per_rad = o.hand_stiffness;
  sim.hand.damping_nms_per_rad = o.hand_damping;
  master_devices::SimDevice device(sim);
  device.open();

  haptics::LoopConfig cfg;
  cfg.joints = 2;
  for (std::size_t j = 0; j < 2; ++j) {
    // The rendered torque opposes the press (the sim hand is pushed back):
    // the force mapping renders the tissue's reaction.
    cfg.force[j] = {1.0, 1.0, 0.0};
    cfg.position[j] = {};
    cfg.limits[j] = {0.3, 30.0};
  }
  cfg.oscillation.enabled = false;  // measured raw; a separate detector watches
  cfg.passivity.enabled = pc;
  cfg.passivity.max_damping_nms_per_rad = o.max_damping;
  std::vector<std::unique_ptr<estimator::DistalTorqueEstimator>> est;
  for (int j = 0; j < 2; ++j)
    est.push_back(
        std::make_unique<estimator::DistalTorqueEstimator>(estimator::load_model(o.params), 0.01));

  const double one_way = rtt_ms * 0.5e-3;
  const delay_relay::ImpairmentParams link{one_way, o.jitter * one_way, o.loss};
  vs::TissueParams tissue = vs::tissue_preset("nodule");
  tissue.surface_rad = 0.2;
  DelayedSlave slave(link, link, o.seed, tissue);
  Rows rows;
  haptics::HapticLoop loop(cfg, device, slave, std::move(est), &rows);
  haptics::OscillationDetector watch(2, {}, 1000.0);

  Result r;
  r.rtt_ms = rtt_ms;
  r.pc = pc;
  std::vector<double> energy;
  const double total = kStart + kPress + kHold + kRelease + kEnd;
  std::int64_t now = 1'000 * kMs;
  const int ticks = static_cast<int>(total * 1000);
  r.compute_ns.reserve(static_cast<std::size_t>(ticks));
  for (int i = 0; i < ticks; ++i, now += kMs) {
    slave.step(now);
    const auto t0 = std::chrono::steady_clock::now();
    loop.tick(now);
    const auto t1 = std::chrono::steady_clock::now();
    r.compute_ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count());
    watch.update(rows.last, 1e-3);
    energy.push_back(loop.passivity(0).observed_energy());
  }
  r.energy_min = *std::min_element(energy.begin(), energy.end());
  r.energy_end = energy.back();
  r.dissipated = loop.passivity(0).dissipated();
  r.detector_trips = watch.trips();

  // Hold torque and its oscillation after settling; overshoot over press and
  // hold; stiffness felt: slope of -torque against the master angle while
  // loading on the nodule (indentation past the inclusion, torque rising).
  const double boundary_m = vs::tissue_truth(tissue).inclusion_depth_m;
  double lo = 1e9, hi = -1e9, sum = 0, peak = 0;
  std::size_t n = 0;
  std::vector<double> kq, ktau;
  for (std::size_t i = 0; i < rows.t.size(); ++i) {
    const double t = rows.t[i], tau = rows.tau[i];
    if (t >= kHoldFrom + kSettle && t < kHoldTo) {
      lo = std::min(lo, tau);
      hi = std::max(hi, tau);
      sum += tau;
      ++n;
    }
    if (t >= kStart && t < kHoldTo) peak = std::max(peak, std::fabs(tau));
    if (t >= kStart && t < kHoldFrom && rows.indentation[i] > boundary_m) {
      kq.push_back(rows.q[i]);
      ktau.push_back(-tau);  // pushes back: negative torque, positive slope
    }
  }
  r.hold_nm = n ? std::fabs(sum / static_cast<double>(n)) : 0.0;
  r.p2p_nm = n ? hi - lo : 0.0;
  // Oscillation: the torque less its centred 0.5 s moving average, so that
  // the slow drift of a hold (the hand settling, the slave's integrator)
  // does not count; a 2 Hz or faster ring passes almost whole.
  {
    constexpr std::size_t kHalf = 250;
    double olo = 1e9, ohi = -1e9;
    for (std::size_t i = kHalf; i + kHalf < rows.t.size(); ++i) {
      // The whole averaging window inside the hold (never the release ramp).
      if (rows.t[i] < kHoldFrom + kSettle || rows.t[i] + 0.25 >= kHoldTo) continue;
      double mean = 0;
      for (std::size_t k = i - kHalf; k <= i + kHalf; ++k)
        mean += rows.tau[k];
      mean /= static_cast<double>(2 * kHalf + 1);
      olo = std::min(olo, rows.tau[i] - mean);
      ohi = std::max(ohi, rows.tau[i] - mean);
    }
    r.osc_p2p_nm = ohi > olo ? ohi - olo : 0.0;
  }
  r.amplitude_pct = r.hold_nm > 0 ? 100.0 * 0.5 * r.osc_p2p_nm / r.hold_nm : 0.0;
  r.overshoot_pct = r.hold_nm > 0 ? 100.0 * (peak - r.hold_nm) / r.hold_nm : 0.0;
  r.stiffness = kq.size() > 20 ? haptics::slope(kq, ktau) : std::nan("");

  if (!o.output.empty()) {
    std::ostringstream name;
    name << o.output << "/delay-" << static_cast<int>(rtt_ms) << "-" << (pc ? "on" : "off")
         << ".csv";
    std::ofstream f(name.str());
    f << "t,q,torque,energy\n";
    for (std::size_t i = 0; i < rows.t.size(); ++i)
      f << rows.t[i] << ',' << rows.q[i] << ',' << rows.tau[i] << ',' << energy[i] << '\n';
  }
  return r;
}

std::vector<double> parse_list(const std::string& s) {
  std::vector<double> v;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    v.push_back(std::stod(item));
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + ": needs a value");
      return argv[++i];
    };
    try {
      if (a == "--rtt-ms")
        o.rtt_ms = parse_list(next());
      else if (a == "--jitter")
        o.jitter = std::stod(next());
      else if (a == "--loss")
        o.loss = std::stod(next());
      else if (a == "--seed")
        o.seed = std::stoull(next());
      else if (a == "--output")
        o.output = next();
      else if (a == "--params")
        o.params = next();
      else if (a == "--hand-stiffness")
        o.hand_stiffness = std::stod(next());
      else if (a == "--hand-damping")
        o.hand_damping = std::stod(next());
      else if (a == "--depth")
        o.depth_rad = std::stod(next());
      else if (a == "--max-damping")
        o.max_damping = std::stod(next());
      else if (a == "--help" || a == "-h") {
        std::printf(
            "bench_teleop_delay [--rtt-ms 0,10,50,100] [--jitter 0.2] [--loss 0.01] [--seed N]\n"
            "                   [--output DIR] [--params FILE|paper] [--hand-stiffness 3.0]\n"
            "                   [--hand-damping 0.2] [--depth 0.5] [--max-damping 1.0]\n");
        return 0;
      } else {
        throw std::invalid_argument("unknown argument '" + a + "' (try --help)");
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_teleop_delay: %s\n", e.what());
      return 2;
    }
  }
  if (!o.output.empty()) std::filesystem::create_directories(o.output);

  std::ostringstream table;
  table << "| RTT ms | passivity | hold N m | p2p after 1 s N m | oscillation p2p N m | "
           "oscillation amplitude % of hold | "
           "overshoot % | stiffness felt N m/rad | W_M min J | W_M end J | dissipated J | "
           "detector trips |\n"
           "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  std::vector<double> compute_off, compute_on;
  char line[512];
  for (const double rtt : o.rtt_ms) {
    for (const bool pc : {false, true}) {
      const Result r = run(o, rtt, pc);
      (pc ? compute_on : compute_off)
          .insert((pc ? compute_on : compute_off).end(), r.compute_ns.begin(), r.compute_ns.end());
      std::snprintf(
          line, sizeof line,
          "| %.0f | %s | %.3f | %.4f | %.4f | %.1f | %.1f | %.3f | %.4f | %.4f | %.4f | %llu |\n",
          rtt, pc ? "on" : "off", r.hold_nm, r.p2p_nm, r.osc_p2p_nm, r.amplitude_pct,
          r.overshoot_pct, r.stiffness, r.energy_min, r.energy_end, r.dissipated,
          static_cast<unsigned long long>(r.detector_trips));
      table << line;
    }
  }
  std::snprintf(line, sizeof line,
                "\nloop compute per tick (simulated time, this process; %zu ticks each): "
                "passivity off p50 %.2f us p99 %.2f us; on p50 %.2f us p99 %.2f us\n",
                compute_off.size(), quantile(compute_off, 0.5) * 1e-3,
                quantile(compute_off, 0.99) * 1e-3, quantile(compute_on, 0.5) * 1e-3,
                quantile(compute_on, 0.99) * 1e-3);
  table << line;
  std::snprintf(
      line, sizeof line,
      "scenario: press into the nodule (intention %.2f rad), hold %.0f s; hand %.2f N m/rad, "
      "%.3f N m s/rad; jitter %.0f %% of each one-way delay, loss %.1f %% each way; seed %llu\n",
      o.depth_rad, kHold, o.hand_stiffness, o.hand_damping, o.jitter * 100, o.loss * 100,
      static_cast<unsigned long long>(o.seed));
  table << line;
  std::fputs(table.str().c_str(), stdout);
  if (!o.output.empty()) std::ofstream(o.output + "/delay-table.md") << table.str();
  return 0;
}
