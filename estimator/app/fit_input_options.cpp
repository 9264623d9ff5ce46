#include "fit_input_options.hpp"

namespace tsmh::tsm_cli {

void add_recording_options(CLI::App& cmd, FitInputCliOptions& o) {
  cmd.add_option("data", o.data, "Recorded data: CSV (t, x_in, tau_in, tau_out) or LCM log")
      ->required();
  cmd.add_option("--radius", o.radius,
                 "Pulley radius in m (default: the file's '# radius_m:' comment)")
      ->check(CLI::PositiveNumber);
}

void add_fit_input_options(CLI::App& cmd, FitInputCliOptions& o, Context& ctx) {
  cmd.add_option("--seed", o.seed, "Seed of the optimiser's random streams (default 1)");
  cmd.add_option("--threads", o.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(0, 64));
  cmd.add_option("--derivatives", o.derivatives,
                 "Velocity/acceleration: auto (the file's xd_in/xdd_in, else offline), offline "
                 "(zero-phase smoother of x_in), deployed (the online differentiator)")
      ->check(CLI::IsMember({"auto", "offline", "deployed"}));
  add_free_motion_options(cmd, o.free_motion);
  add_master_scale_options(cmd, o.master);
  add_lcm_log_options(cmd, ctx.lcm_log);
}

}  // namespace tsmh::tsm_cli
