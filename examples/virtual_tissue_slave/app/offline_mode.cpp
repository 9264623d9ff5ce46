#include "offline_mode.hpp"

#include <cstdio>
#include <cstdlib>
#include <estimator/recording.hpp>
#include <estimator/table.hpp>
#include <filesystem>
#include <stdexcept>

#include "bridge/link_security.hpp"
#include "files/distinct_outputs.hpp"

namespace tsmh::virtual_tissue_slave::app {
namespace {

// Before the simulation, not after it: the output's folder exists, and the
// output is not the link key (files/distinct_outputs.hpp).
void check_output(const CliOptions& o) {
  const std::filesystem::path out(o.output);
  const std::filesystem::path folder = out.parent_path().empty() ? "." : out.parent_path();
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec))
    throw std::invalid_argument("--output " + o.output + ": the folder '" + folder.string() +
                                "' does not exist (outputs are written into existing folders)");
  if (std::filesystem::is_directory(out, ec))
    throw std::invalid_argument("--output " + o.output + ": is a folder; name a file to write");
  std::vector<files::NamedInput> inputs;
  try {
    if (const auto key =
            bridge::find_key_file(o.link.security.key_file, std::getenv(bridge::kLinkKeyEnv),
                                  std::getenv("XDG_CONFIG_HOME"), std::getenv("HOME")))
      inputs.push_back({"the link key", *key});
  } catch (const std::exception&) {
    // No key to protect.
  }
  try {
    files::check_distinct_outputs(inputs, {{"--output", o.output}});
  } catch (const files::FileError& e) {
    throw std::invalid_argument(e.what());
  }
}

}  // namespace

int run_offline_mode(const CliOptions& o) {
  if (o.output.empty()) throw std::invalid_argument("--offline needs --output DATA.csv");
  check_output(o);
  const Scenario scenario = make_scenario(o.scenario);
  const Setup setup = make_setup(o, &scenario);

  OfflineOptions run;
  run.scenario = scenario;
  run.scenario.surface_rad = setup.tissue.surface_rad;  // palpation follows the surface
  run.duration_s = o.duration_s > 0 ? o.duration_s : scenario.default_duration_s;
  run.tissue = setup.tissue;
  run.effects = setup.effects;
  run.reroute = setup.reroute;
  run.joint = setup.joint_index;
  run.seed = o.seed;

  const auto j = static_cast<std::size_t>(setup.joint_index);
  const double radius = setup.params.joints[j].radius_m;
  estimator::Recording rec;
  rec.source = "virtual-slave --offline --scenario " + scenario.name;
  rec.radius_m = radius;
  std::vector<double> reference, x_out_true, t2, t4, friction_true, contact_force, indentation;
  const auto n = static_cast<std::size_t>(run.duration_s / setup.params.control_period_s) + 1;
  for (auto* v : {&rec.t, &rec.x_in, &rec.tau_in, &rec.tau_out, &rec.x_out, &rec.T1, &rec.T3})
    v->reserve(n);

  const OfflineStats stats = run_offline(setup.params, run, [&](const SlaveSample& s) {
    const Measurement& m = s.measured[j];
    const JointTruth& tr = s.truth[j];
    rec.t.push_back(s.t);
    rec.x_in.push_back(m.x_in);
    rec.tau_in.push_back(radius * (m.T1 - m.T3));
    rec.tau_out.push_back(tr.tau_out);
    if (setup.params.sensors.joint_encoder) rec.x_out.push_back(m.x_out);
    rec.T1.push_back(m.T1);
    rec.T3.push_back(m.T3);
    if (o.exact_derivatives) {
      rec.xd_in.push_back(tr.xd_in);
      rec.xdd_in.push_back(tr.xdd_in);
    }
    if (o.truth_columns) {
      reference.push_back(s.reference[j]);
      x_out_true.push_back(tr.x_out);
      t2.push_back(tr.T2);
      t4.push_back(tr.T4);
      friction_true.push_back(tr.friction);
      contact_force.push_back(tr.contact.force_n);
      indentation.push_back(tr.contact.indentation_m);
    }
  });

  if (o.truth_columns) {
    estimator::Table table = estimator::recording_to_table(rec);
    table.set("reference", std::move(reference));
    table.set("x_out_true", std::move(x_out_true));
    table.set("T2", std::move(t2));
    table.set("T4", std::move(t4));
    table.set("friction_true", std::move(friction_true));
    table.set("contact_force", std::move(contact_force));
    table.set("indentation", std::move(indentation));
    estimator::write_csv_table(table, o.output);
  } else {
    estimator::write_recording_csv(rec, o.output);
  }
  std::fprintf(stderr,
               "virtual-slave: %s, joint index %d, %.1f s simulated in %.2f s (%.0fx real time), "
               "%ld samples -> %s\n",
               scenario.name.c_str(), o.joint, stats.simulated_s, stats.wall_s,
               stats.realtime_factor(), stats.samples, o.output.c_str());
  if (stats.fallback_solves > 0)
    std::fprintf(stderr, "virtual-slave: note: %ld tendon solves used the slow fallback\n",
                 stats.fallback_solves);
  return 0;
}

}  // namespace tsmh::virtual_tissue_slave::app
