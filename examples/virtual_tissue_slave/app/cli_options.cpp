#include "cli_options.hpp"

#include <bridge/node_link.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>

#include "files/cli_numbers.hpp"
#include "realtime/joint_names.hpp"
#include "virtual_tissue_slave/effects.hpp"

namespace tsmh::virtual_tissue_slave::app {

namespace {

// --joint: a joint's name (joint1, joint2) or its 0-based index, as an index.
CLI::Validator joint_option(std::size_t count) {
  return CLI::Validator(
      [count](std::string& value) -> std::string {
        const auto j = realtime::joint_from_text(value, count);
        if (!j) return "no joint '" + value + "' (joint1..joint" + std::to_string(count) + ")";
        value = std::to_string(*j);
        return "";
      },
      "joint1..joint" + std::to_string(count));
}

// --wrap / --pretension: "V1[,V2]" sets `field` of the joint's sheath 01 (and
// 02); one value sets sheath 01 alone. Empty: the preset's values stay.
void set_sheaths(JointParams& joint, const std::string& text, const char* option, const char* must,
                 double TendonParams::*field) {
  if (text.empty()) return;
  const auto [v1, v2] = parse_pair(text, option);
  if (v1 < 0 || (!std::isnan(v2) && v2 < 0))
    throw std::invalid_argument(std::string(option) + ": " + must);
  joint.tendon1.*field = v1;
  if (!std::isnan(v2)) joint.tendon2.*field = v2;
}

}  // namespace

void add_options(CLI::App& app, CliOptions& o) {
  app.add_flag("--offline", o.offline,
               "run faster than real time on --scenario and write --output (no LCM)");
  app.add_option("--duration", o.duration_s,
                 "seconds to run (offline: default per scenario; real time: 0 = until SIGINT)")
      ->check(files::finite_range(0.0, 1e7, "s"));
  app.add_option("--scenario", o.scenario,
                 "offline scenario: sine, multisine, palpate, chirp, excite, identify");
  app.add_option("--output", o.output,
                 "offline: CSV file to write (data contract: docs/data-formats.md)");
  app.add_option("--joint", o.joint,
                 "joint written to --output, and whose sheaths --wrap/--pretension/--reroute-wrap "
                 "set: joint1 (the gripper, default) or joint2 (the 0-based index 0 or 1 is "
                 "accepted too)")
      ->transform(joint_option(2));
  app.add_flag(
      "--exact-derivatives", o.exact_derivatives,
      "offline: add xd_in, xdd_in columns (the simulator's true motor velocity, acceleration)");
  app.add_flag("--truth-columns", o.truth_columns,
               "offline: add evaluation columns (reference, x_out_true, T2, T4, friction_true, "
               "contact_force, indentation)");
  app.add_option("--seed", o.seed, "seed of the sensor noise");
  app.add_flag("--print-tissue", o.print_tissue,
               "print the tissue and its true stiffness values as JSON and exit");
  app.add_flag("--list-scenarios", o.list_scenarios, "list the offline scenarios and exit");

  app.add_option("--tissue", o.tissue,
                 "tissue at the tool for both joints: none, soft, hard, nodule "
                 "(default: the scenario's offline, nodule in real time)");
  app.add_option("--contact", o.contact, "contact law: kelvin-voigt or hunt-crossley");
  app.add_option("--surface", o.surface_rad, "joint angle where the tool meets the tissue, rad");
  app.add_option("--wrap", o.wrap, "total wrap of sheath 01[,02] of --joint, rad");
  app.add_option("--pretension", o.pretension, "pretension of tendon 1[,2] of --joint, N");
  app.add_option("--mu", o.mu, "tendon-sheath friction coefficient, all tendons");
  app.add_option(
      "--effect", o.effects,
      "hidden effect NAME=VALUE, repeatable: viscous=C (N per rad/s of extra sheath "
      "drag), capstan=0 (friction independent of load), position=G (wrap x (1 + G x_in))");
  app.add_option("--reroute-at", o.reroute_at_s, "time at which the sheaths are re-routed, s");
  app.add_option("--reroute-wrap", o.reroute_wrap,
                 "new wrap of sheath 01[,02] of --joint at --reroute-at, rad (one value: every "
                 "sheath bends by the same factor)");

  app.add_option("--load-cell-noise", o.load_cell_noise_n,
                 "load cell noise, standard deviation, N");
  app.add_option("--motor-encoder-counts", o.motor_encoder_counts,
                 "motor encoder counts per revolution (default 40960; 0 = ideal)");
  app.add_flag("--no-joint-encoder", o.no_joint_encoder,
               "no joint encoder: x_out reads NaN, compensation is feedforward only");
  app.add_flag("--no-compensation", o.no_compensation,
               "slave controller without the backlash compensation (PD only)");

  bridge::add_node_link_options(app, o.link, "--prefix", "channel prefix, e.g. ARM1_",
                                "run without a link key on a network LCM URL: anyone who "
                                "reaches it can move the slave (isolated networks only)");
  app.add_option("--command-timeout", o.command_timeout_s,
                 "hold position when no MASTER_COMMAND arrived for this long, s")
      ->check(CLI::PositiveNumber);
  app.add_option("--rt-priority", o.rt_priority,
                 "SCHED_FIFO priority of the 1 kHz loop (0: normal scheduling)")
      ->check(CLI::Range(0, 99));
  app.add_option("--cpu", o.cpu, "pin the 1 kHz loop thread to this CPU (-1: no pinning)")
      ->check(CLI::Range(-1, 1023));
}

Setup make_setup(const CliOptions& o, const Scenario* scenario) {
  Setup s;
  s.params = paper_slave();
  s.joint_index = o.joint;
  JointParams& jp = s.params.joints[static_cast<std::size_t>(s.joint_index)];

  set_sheaths(jp, o.wrap, "--wrap", "wraps must be >= 0 rad", &TendonParams::wrap_rad);
  set_sheaths(jp, o.pretension, "--pretension", "tensions must be >= 0 N",
              &TendonParams::pretension_n);
  if (o.mu) {
    if (!(std::isfinite(*o.mu) && *o.mu >= 0)) throw std::invalid_argument("--mu must be >= 0");
    for (auto& j : s.params.joints)
      j.tendon1.mu = j.tendon2.mu = *o.mu;
  }
  if (o.load_cell_noise_n) {
    if (!(std::isfinite(*o.load_cell_noise_n) && *o.load_cell_noise_n >= 0))
      throw std::invalid_argument("--load-cell-noise must be >= 0 N");
    s.params.sensors.load_cell_noise_n = *o.load_cell_noise_n;
  }
  if (o.motor_encoder_counts) {
    if (*o.motor_encoder_counts < 0)
      throw std::invalid_argument("--motor-encoder-counts must be >= 0");
    s.params.sensors.motor_encoder_quantum_rad =
        *o.motor_encoder_counts == 0 ? 0.0 : 2.0 * std::numbers::pi / *o.motor_encoder_counts;
  }
  s.params.sensors.joint_encoder = !o.no_joint_encoder;
  for (auto& c : s.params.controllers)
    c.compensation = !o.no_compensation;

  const ContactLaw law = parse_contact_law(o.contact);
  const std::string preset =
      !o.tissue.empty() ? o.tissue : (scenario ? scenario->tissue : "nodule");
  s.tissue = tissue_preset(preset, law);
  s.tissue.surface_rad = o.surface_rad ? *o.surface_rad : (scenario ? scenario->surface_rad : 0.2);
  validate(s.tissue);
  for (auto& j : s.params.joints)
    j.tissue = s.tissue;

  s.effects = parse_effects(o.effects);
  if (o.reroute_at_s || !o.reroute_wrap.empty()) {
    if (!o.reroute_at_s || o.reroute_wrap.empty())
      throw std::invalid_argument("--reroute-at and --reroute-wrap go together");
    const auto [w1, w2] = parse_pair(o.reroute_wrap, "--reroute-wrap");
    s.reroute.at_s = *o.reroute_at_s;
    s.reroute.sheath1_wrap_rad = w1;
    s.reroute.sheath2_wrap_rad = w2;
    validate(s.reroute);
  }
  validate(s.params);
  return s;
}

std::string tissue_json(const TissueParams& t) {
  const TissueTruth truth = tissue_truth(t);
  nlohmann::json j;
  j["preset"] = t.name;
  j["present"] = t.present;
  j["contact_law"] = std::string(contact_law_name(t.law));
  j["surface_rad"] = t.surface_rad;
  j["lever_m"] = t.lever_m;
  j["outer_stiffness"] = {{"n_per_m", truth.outer_n_per_m}, {"nm_per_rad", truth.outer_nm_per_rad}};
  if (truth.inclusion_depth_m > 0) {
    j["inclusion"] = {{"depth_m", truth.inclusion_depth_m},
                      {"depth_rad", truth.inclusion_depth_rad},
                      {"n_per_m", truth.inclusion_n_per_m},
                      {"nm_per_rad", truth.inclusion_nm_per_rad}};
  } else {
    j["inclusion"] = nullptr;
  }
  j["damping"] = t.damping;
  j["exponent"] = t.law == ContactLaw::kHuntCrossley ? t.exponent : 1.0;
  return j.dump(2);
}

}  // namespace tsmh::virtual_tissue_slave::app
