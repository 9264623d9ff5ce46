#include "estimator/free_motion.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

#include "estimator/offline_derivatives.hpp"

namespace tsmh::estimator {
namespace {

std::string num(double v, int digits = 3) {
  std::ostringstream s;
  s.precision(digits);
  s << v;
  return s.str();
}

// J xdd + b xd of the joint from the smoothed joint encoder.
std::vector<double> inertia_damping_torque(const Recording& rec, double inertia, double damping) {
  Recording joint;
  joint.source = rec.source;
  joint.radius_m = rec.radius_m;
  joint.t = rec.t;
  joint.x_in = rec.x_out;
  OfflineDerivativeConfig cfg;
  cfg.quantum = 2.0 * std::numbers::pi / 65536.0;  // joint encoders are usually finer
  const auto m = offline_motion(joint, cfg);
  std::vector<double> tau(m.size());
  for (std::size_t i = 0; i < m.size(); ++i)
    tau[i] = inertia * m[i].xdd + damping * m[i].xd;
  return tau;
}

void check_parameter(const Recording& rec, const std::optional<double>& v, const char* name) {
  if (v && (!std::isfinite(*v) || *v < 0.0))
    throw DataError(rec.source, 0, "",
                    std::string(name) + " must be a finite number >= 0, got " + num(*v));
}

}  // namespace

FreeMotionData free_motion_recording(const Recording& rec, const FreeMotionConfig& config) {
  check_requirements(rec, {.tau_in = true, .radius = true});
  check_parameter(rec, config.joint_inertia, "--joint-inertia");
  check_parameter(rec, config.joint_damping, "--joint-damping");
  for (std::size_t i = 0; i < rec.size(); ++i) {
    if (!std::isfinite(rec.tau_in[i]) || !std::isfinite(rec.x_in[i]))
      throw DataError(rec.source, 0, std::isfinite(rec.x_in[i]) ? "tau_in" : "x_in",
                      "sample " + std::to_string(i + 1) + " (t = " + num(rec.t[i], 6) +
                          " s) is not a finite number");
  }

  FreeMotionData out;
  out.recording = rec;
  if (rec.has_tau_out()) out.notes.push_back("--free-motion: the file's tau_out column is ignored");

  // A joint encoder that reads NaN throughout is absent (virtual-slave
  // --no-joint-encoder); one with some NaNs is a broken recording.
  std::size_t finite_out = 0;
  for (double v : rec.x_out)
    finite_out += std::isfinite(v) ? 1 : 0;
  if (finite_out != 0 && finite_out != rec.x_out.size()) {
    for (std::size_t i = 0; i < rec.x_out.size(); ++i)
      if (!std::isfinite(rec.x_out[i]))
        throw DataError(rec.source, 0, "x_out",
                        "sample " + std::to_string(i + 1) + " (t = " + num(rec.t[i], 6) +
                            " s) is not a finite number (the joint encoder must read throughout, "
                            "or the column be absent)");
  }
  const bool have_encoder = finite_out != 0 && finite_out == rec.x_out.size();
  const bool have_dynamics = config.joint_inertia || config.joint_damping;
  if (have_encoder && have_dynamics) {
    out.recording.tau_out = inertia_damping_torque(rec, config.joint_inertia.value_or(0.0),
                                                   config.joint_damping.value_or(0.0));
    out.distal_source = "inertia_damping";
    out.notes.push_back("--free-motion: distal torque = J xdd_out + b xd_out from x_out (J = " +
                        num(config.joint_inertia.value_or(0.0)) +
                        " kg m^2, b = " + num(config.joint_damping.value_or(0.0)) + " N m s/rad)");
  } else {
    out.recording.tau_out.assign(rec.size(), 0.0);
    out.distal_source = "zero";
    out.notes.push_back(
        have_encoder
            ? "--free-motion: distal torque taken as zero (x_out is there but no "
              "--joint-inertia/--joint-damping were given)"
            : "--free-motion: distal torque taken as zero (no joint encoder: x_out is absent)");
  }
  double ss = 0.0;
  for (double v : out.recording.tau_out)
    ss += v * v;
  out.distal_rms_nm = rec.size() ? std::sqrt(ss / static_cast<double>(rec.size())) : 0.0;

  const auto motion = offline_motion(rec);
  std::vector<double> x(motion.size()), xd(motion.size());
  for (std::size_t i = 0; i < motion.size(); ++i)
    x[i] = motion[i].x, xd[i] = motion[i].xd;
  out.contact = check_contact(rec.t, x, xd, rec.tau_in, config.contact);
  if (out.contact.bins_used < 2)
    throw DataError(rec.source, 0, "x_in",
                    "--free-motion: too little sliding to tell free motion from contact (needs "
                    "strokes of more than " +
                        num(kContactSettleRad) +
                        " rad each way past every reversal, in both directions over the same "
                        "angles)");
  std::string why;
  if (shows_contact(out.contact, config.contact, &why))
    throw DataError(rec.source, 0, "tau_in",
                    "--free-motion: the data shows contact: " + why +
                        ". Record free motion with the instrument clear of tissue, or fit with a "
                        "measured tau_out");
  return out;
}

}  // namespace tsmh::estimator
