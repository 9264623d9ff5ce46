// tsm convert LOG.lcmlog --output OUT.csv [--joint J] [--prefix P]
// An LCM log of SLAVE_STATE (and SLAVE_TRUTH, for tau_out) to the CSV data
// contract (docs/data-formats.md), with the '# radius_m:' comment.

#include <iostream>
#include <memory>

#include "commands.hpp"
#include "lcm_log_source.hpp"
#include "output_checks.hpp"

namespace tsmh::tsm_cli {
namespace {

struct ConvertOptions {
  std::string log;
  std::string output;
  LcmLogSelection sel;
};

void run_convert(const ConvertOptions& o) {
  check_outputs({{"--output", o.output, OutputKind::kFile}},
                {{"the log", o.log}, key_input(o.sel)});
  std::string summary;
  const auto rec = recording_from_lcm_log(o.log, o.sel, std::nullopt, {}, &summary);
  estimator::write_recording_csv(rec, o.output);
  std::cerr << "tsm convert: " << rec.size() << " rows of joint " << o.sel.joint << " ("
            << (rec.has_tau_out() ? "with" : "without") << " tau_out) -> " << o.output << "; "
            << summary << "\n";
}

}  // namespace

void add_convert_command(CLI::App& app, Context& /*ctx*/) {
  auto opts = std::make_shared<ConvertOptions>();
  auto* cmd = app.add_subcommand(
      "convert", "Turn an LCM log of SLAVE_STATE (+ SLAVE_TRUTH) into the CSV data contract");
  cmd->add_option("log", opts->log, "LCM log file (lcm-logger)")->required();
  cmd->add_option("--output", opts->output, "Output CSV")->required();
  add_lcm_log_options(*cmd, opts->sel);
  cmd->callback([opts] { run_convert(*opts); });
}

}  // namespace tsmh::tsm_cli
