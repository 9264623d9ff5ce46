#include "free_motion_options.hpp"

namespace tsmh::tsm_cli {

void add_free_motion_options(CLI::App& cmd, FreeMotionCliOptions& o) {
  cmd.add_flag("--free-motion", o.enabled,
               "DATA was recorded in free motion (no tau_out needed): the distal torque is the "
               "joint's inertia/damping torque from x_out, else zero; data showing contact is "
               "refused");
  cmd.add_option("--joint-inertia", o.joint_inertia,
                 "With --free-motion and x_out: joint-side inertia J, kg m^2 (default: none)")
      ->check(CLI::NonNegativeNumber);
  cmd.add_option("--joint-damping", o.joint_damping,
                 "With --free-motion and x_out: joint-side viscous damping b, N m s/rad "
                 "(default: none)")
      ->check(CLI::NonNegativeNumber);
}

LoadedFitData load_fit_recording(const Context& ctx, const std::string& data,
                                 std::optional<double> radius, const FreeMotionCliOptions& o) {
  LoadedFitData out;
  if (!o.enabled) {
    if (o.joint_inertia || o.joint_damping)
      throw CLI::ValidationError("--joint-inertia/--joint-damping",
                                 "only apply with --free-motion");
    out.recording =
        ctx.sources.load(data, radius, {.tau_in = true, .tau_out = true, .radius = true});
    return out;
  }
  const auto rec = ctx.sources.load(data, radius, {.tau_in = true, .radius = true});
  estimator::FreeMotionConfig cfg;
  cfg.joint_inertia = o.joint_inertia;
  cfg.joint_damping = o.joint_damping;
  out.free_motion = estimator::free_motion_recording(rec, cfg);
  out.recording = out.free_motion->recording;
  out.notes = out.free_motion->notes;
  return out;
}

nlohmann::json free_motion_json(const estimator::FreeMotionData& f) {
  const auto& c = f.contact;
  return {{"distal_torque", f.distal_source},
          {"distal_rms_nm", f.distal_rms_nm},
          {"notes", f.notes},
          {"contact_check",
           {{"band_half_width_nm", c.band_half_width_nm},
            {"midline_shift_nm", c.midline_shift_nm},
            {"longest_excess_s", c.longest_excess_s},
            {"peak_excess_nm", c.peak_excess_nm},
            {"bins", c.bins_used}}}};
}

}  // namespace tsmh::tsm_cli
