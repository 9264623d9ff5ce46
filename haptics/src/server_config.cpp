#include "haptics/server_config.hpp"

#include <sched.h>

#include <cmath>
#include <set>
#include <sstream>

#include "files/input_file.hpp"
#include "realtime/joint_names.hpp"

namespace tsmh::haptics {
namespace {

using config::FieldReader;

/// A number within [lo, hi] ((lo, hi] when lo_open), the fallback when absent.
double in_range(FieldReader& r, const char* key, double fallback, double lo, double hi,
                bool lo_open = false) {
  const double v = r.get_double(key, fallback);
  if (v < lo || v > hi || (lo_open && v == lo)) {
    std::ostringstream range;
    range << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
    r.fail(key, "must be within " + range.str());
  }
  return v;
}

double unit_sign(FieldReader& r, const char* key) {
  const double s = r.get_double(key, 1.0);
  if (s != 1.0 && s != -1.0) r.fail(key, "must be 1 or -1");
  return s;
}

std::string cpu_list(const cpu_set_t& set) {
  std::string out;
  for (int i = 0; i < CPU_SETSIZE; ++i) {
    if (!CPU_ISSET(i, &set)) continue;
    if (!out.empty()) out += ',';
    out += std::to_string(i);
  }
  return out;
}

std::string resolve(const std::filesystem::path& base, const std::string& p) {
  if (p.empty() || std::filesystem::path(p).is_absolute()) return p;
  return (base / p).lexically_normal().string();
}

// safety.oscillation; every field optional.
OscillationConfig parse_oscillation(FieldReader& o, double rate_hz) {
  OscillationConfig c;
  c.enabled = o.get_bool("enabled", c.enabled);
  c.band_low_hz = in_range(o, "band_low_hz", c.band_low_hz, 0.0, 1e3, true);
  c.band_high_hz = in_range(o, "band_high_hz", c.band_high_hz, 0.0, 0.45 * rate_hz, true);
  if (c.band_high_hz <= c.band_low_hz) o.fail("band_high_hz", "must be above band_low_hz");
  c.threshold_nm = in_range(o, "threshold_nm", c.threshold_nm, 0.0, 1e3, true);
  c.min_crossings = static_cast<int>(in_range(o, "min_crossings", c.min_crossings, 1, 1000));
  c.window_s = in_range(o, "window_ms", c.window_s * 1e3, 0.0, 1e4, true) * 1e-3;
  c.fade_s = in_range(o, "fade_ms", c.fade_s * 1e3, 0.0, 1e4, true) * 1e-3;
  c.hold_s = in_range(o, "hold_ms", c.hold_s * 1e3, 0.0, 6e4) * 1e-3;
  c.recover_s = in_range(o, "recover_ms", c.recover_s * 1e3, 0.0, 6e4, true) * 1e-3;
  o.reject_unknown();
  return c;
}

// passivity; off unless enabled.
PassivityConfig parse_passivity(FieldReader& p) {
  PassivityConfig c;
  c.enabled = p.get_bool("enabled", c.enabled);
  c.max_damping_nms_per_rad =
      in_range(p, "max_damping_nms_per_rad", c.max_damping_nms_per_rad, 0.0, 100.0, true);
  c.max_brake_nm = in_range(p, "max_brake_nm", c.max_brake_nm, 0.0, 1000.0);
  p.reject_unknown();
  return c;
}

}  // namespace

FeedbackSource feedback_source_from_string(const std::string& s) {
  if (s == "estimated") return FeedbackSource::kEstimated;
  if (s == "naive") return FeedbackSource::kNaive;
  if (s == "none") return FeedbackSource::kNone;
  throw ConfigError("feedback: '" + s + "' is not one of estimated, naive, none");
}

namespace {

void parse_safety(FieldReader& safety, const std::string& origin, LoopConfig& loop) {
  const auto ms = [&](const char* key, double def) {
    return in_range(safety, key, def, 0.0, 1e6, true) * 1e-3;
  };
  loop.timing.stale_after_s = ms("stale_after_ms", 20.0);
  loop.timing.fade_s = ms("fade_ms", 50.0);
  loop.timing.recover_s = ms("recover_ms", 200.0);
  loop.slave_timeout_s = ms("slave_timeout_ms", 1000.0);
  loop.device_stale_fault_s = ms("device_stale_fault_ms", 50.0);
  loop.estimate_fault_s = ms("estimate_fault_ms", 500.0);
  FieldReader oscillation(safety.node("oscillation"), origin, "safety.oscillation");
  loop.oscillation = parse_oscillation(oscillation, loop.rate_hz);
  safety.reject_unknown();
}

void parse_slave_limits(FieldReader& slave, bridge::SlaveStateLimits& sl) {
  sl.max_x_in_rate_rad_s = in_range(slave, "max_motor_speed_rad_s", sl.max_x_in_rate_rad_s, 0, 1e6);
  sl.max_x_out_rate_rad_s =
      in_range(slave, "max_joint_speed_rad_s", sl.max_x_out_rate_rad_s, 0, 1e6);
  sl.max_tension_rate_n_per_s =
      in_range(slave, "max_tension_rate_n_per_s", sl.max_tension_rate_n_per_s, 0, 1e9);
  sl.step_slack_s = in_range(slave, "step_slack_ms", sl.step_slack_s * 1e3, 0, 1e4) * 1e-3;
  slave.reject_unknown();
}

void parse_realtime(FieldReader& rt, RealtimeConfig& c) {
  c.sched_fifo = rt.get_bool("sched_fifo", true);
  c.priority = static_cast<int>(in_range(rt, "priority", 80, 1, 99));
  c.lock_memory = rt.get_bool("lock_memory", true);
  c.cpu_dma_latency = rt.get_bool("cpu_dma_latency", true);
  c.cpu = static_cast<int>(in_range(rt, "cpu", -1, -1, 1023));
  if (c.cpu >= 0) {
    // Pinning to a CPU this process may not use fails at start-up at best;
    // refuse it here, with the CPUs there are.
    cpu_set_t allowed;
    CPU_ZERO(&allowed);
    if (sched_getaffinity(0, sizeof allowed, &allowed) == 0 && !CPU_ISSET(c.cpu, &allowed))
      rt.fail("cpu", "CPU " + std::to_string(c.cpu) + " is not available (" +
                         std::to_string(CPU_COUNT(&allowed)) + " CPUs: " + cpu_list(allowed) +
                         "); use one of them or -1 for no pinning");
  }
  rt.reject_unknown();
}

// Drift alarm and one-button recalibration (recalibration.hpp).
void parse_calibration(FieldReader& drift, FieldReader& recal, LoopConfig& loop) {
  auto& d = loop.drift;
  d.enabled = drift.get_bool("enabled", d.enabled);
  d.threshold = in_range(drift, "threshold", d.threshold, 0.0, 10.0, true);
  d.hold_s = in_range(drift, "hold_s", d.hold_s, 0.0, 600.0);
  d.time_constant_s = in_range(drift, "time_constant_s", d.time_constant_s, 0.0, 600.0, true);
  drift.reject_unknown();
  auto& rc = loop.recalibration;
  rc.collect_s = in_range(recal, "collect_s", rc.collect_s, 0.5, 60.0);
  rc.min_span_rad = in_range(recal, "min_span_rad", rc.min_span_rad, 0.0, 10.0);
  rc.min_improvement = in_range(recal, "min_improvement", rc.min_improvement, 0.0, 0.99);
  rc.ramp_per_s = in_range(recal, "ramp_per_s", rc.ramp_per_s, 0.0, 100.0, true);
  const std::string scale = recal.get_string("scale", "levels");
  if (scale == "levels")
    rc.scale = RecalibrationScale::kLevels;
  else if (scale == "output")
    rc.scale = RecalibrationScale::kOutput;
  else
    recal.fail("scale", "must be levels or output, got '" + scale + "'");
  rc.per_direction = recal.get_bool("per_direction", rc.per_direction);
  // Two slave samples per loop tick at most, for the whole collection.
  rc.capacity = static_cast<std::size_t>(rc.collect_s * 2.0 * LoopConfig::kMaxRateHz) + 100;
  recal.reject_unknown();
}

void parse_evaluation(FieldReader& ev, const std::filesystem::path& base_dir, EvaluationConfig& c) {
  c.truth = ev.get_bool("truth", false);
  c.trace = resolve(base_dir, ev.get_string("trace", ""));
  c.report = resolve(base_dir, ev.get_string("report", ""));
  c.max_trace_s = in_range(ev, "max_trace_s", 600.0, 1.0, 86400.0);
  ev.reject_unknown();
}

// One entry of `joints:`: the estimator's settings, the force and position
// mapping and the safety limits of joint i.
void parse_joint(FieldReader& j, std::size_t i, const std::filesystem::path& base_dir,
                 ServerConfig& c) {
  JointConfig jc;
  jc.name = j.get_string("name", realtime::joint_name(i));
  jc.params = j.get_string("params", "paper");
  if (jc.params.find('/') != std::string::npos || jc.params.ends_with(".yaml") ||
      jc.params.ends_with(".yml"))
    jc.params = resolve(base_dir, jc.params);
  jc.radius_m = in_range(j, "radius_m", 0.01, 0.0, 1.0, true);
  auto& est = jc.estimator;
  for (const auto& s : estimator::numeric_settings()) {
    const double v = j.get_double(s.key, est.*s.field);
    const std::string problem = s.problem(v);
    if (!problem.empty()) j.fail(s.key, problem);
    est.*s.field = v;
  }
  const auto start = estimator::start_state_from_name(j.get_string("start_state", "free_tip"));
  if (!start) j.fail("start_state", "must be " + std::string(estimator::kStartStateNames));
  est.start_state = *start;
  c.joints.push_back(jc);
  c.loop.force[i] = {in_range(j, "force_scale", 1.0, 0.0, 1e3), unit_sign(j, "force_sign"),
                     in_range(j, "deadband_nm", 0.0, 0.0, 1e3)};
  PositionMappingConfig pm;
  pm.scale = in_range(j, "position_scale", 1.0, 0.0, 1e3, true);
  pm.sign = unit_sign(j, "position_sign");
  pm.min_ref = in_range(j, "slave_min_rad", -1e3, -1e3, 1e3);
  pm.max_ref = in_range(j, "slave_max_rad", 1e3, -1e3, 1e3);
  if (pm.min_ref >= pm.max_ref) j.fail("slave_min_rad", "must be below slave_max_rad");
  c.loop.position[i] = pm;
  if (!j.has("max_torque_nm")) j.fail("max_torque_nm", "missing: every joint needs a torque limit");
  c.loop.limits[i] = {in_range(j, "max_torque_nm", 0.0, 0.0, 1e3, true),
                      in_range(j, "max_rate_nm_per_s", 50.0, 0.0, 1e6, true)};
  j.reject_unknown();
}

}  // namespace

ServerConfig parse_server_config(const std::string& text, const std::string& origin,
                                 const std::filesystem::path& base_dir) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(origin + ": not valid YAML (line " + std::to_string(e.mark.line + 1) +
                      "): " + e.msg);
  }
  if (!root.IsMap()) throw ConfigError(origin + ": expected a YAML map");
  config::reject_duplicate_keys(root, origin);
  FieldReader r(root, origin, "");
  ServerConfig c;
  c.source = origin;
  c.loop.set_rate(in_range(r, "rate_hz", 1000.0, LoopConfig::kMinRateHz, LoopConfig::kMaxRateHz));
  const std::string feedback = r.get_string("feedback", "estimated");
  if (feedback != "estimated" && feedback != "naive" && feedback != "none")
    r.fail("feedback", "'" + feedback + "' is not one of estimated, naive, none");
  c.loop.source = feedback_source_from_string(feedback);
  c.duration_s = in_range(r, "duration_s", 0.0, 0.0, 1e7);

  // No silent default: a configuration without a device section would run
  // the simulated console, which in an operating room means the surgeon's
  // console is silently ignored. Reported after the joints, whose errors come
  // first.
  const bool has_device = r.has("device");
  FieldReader device(r.node("device"), origin, "device");
  if (has_device && !device.has("driver"))
    device.fail("driver",
                "missing: name the master driver (hid, usb, lcm, emulator, or sim for a "
                "simulated console)");
  c.device_driver = device.get_string("driver", "sim");
  const YAML::Node settings = device.node("settings");
  c.device_settings = settings.IsDefined() ? settings : YAML::Node(YAML::NodeType::Map);
  device.reject_unknown();

  FieldReader lcm(r.node("lcm"), origin, "lcm");
  c.lcm_url = lcm.get_string("url", "");
  c.lcm_prefix = lcm.get_string("prefix", "");
  lcm.reject_unknown();

  FieldReader safety(r.node("safety"), origin, "safety");
  parse_safety(safety, origin, c.loop);
  FieldReader passivity(r.node("passivity"), origin, "passivity");
  c.loop.passivity = parse_passivity(passivity);
  FieldReader slave(r.node("slave_state"), origin, "slave_state");
  parse_slave_limits(slave, c.slave_limits);
  FieldReader rt(r.node("realtime"), origin, "realtime");
  parse_realtime(rt, c.realtime);
  FieldReader drift(r.node("drift"), origin, "drift");
  FieldReader recal(r.node("recalibration"), origin, "recalibration");
  parse_calibration(drift, recal, c.loop);
  FieldReader ev(r.node("evaluation"), origin, "evaluation");
  parse_evaluation(ev, base_dir, c.evaluation);

  const YAML::Node joints = r.node("joints");
  if (!joints.IsSequence() || joints.size() == 0)
    r.fail("joints", "missing (a list with one entry per joint)");
  if (joints.size() > kMaxJoints)
    r.fail("joints", "at most " + std::to_string(kMaxJoints) + " joints");
  c.loop.joints = static_cast<int>(joints.size());
  for (std::size_t i = 0; i < joints.size(); ++i) {
    FieldReader j(joints[i], origin, "joints[" + std::to_string(i) + "]");
    parse_joint(j, i, base_dir, c);
  }
  if (!has_device)
    r.fail("device",
           "missing: name the master device (device: {driver: hid|usb|lcm|emulator|sim, "
           "settings: ...}); there is no default, so a configuration can never run a "
           "simulated console by accident");
  r.reject_unknown();
  return c;
}

void check_against_device(const ServerConfig& c, const master_devices::DeviceSpec& spec) {
  if (c.loop.joints > static_cast<int>(spec.dof))
    throw ConfigError(c.source + ": joints: " + std::to_string(c.loop.joints) +
                      " joints configured but the device (" + c.device_driver + ", " + spec.model +
                      ") has " + std::to_string(spec.dof) +
                      "; a joint without a master axis would render into nothing");
}

ServerConfig load_server_config(const std::filesystem::path& path) {
  // Bounded and never blocking (a FIFO or /dev/zero is refused at once).
  std::string text;
  try {
    text = files::read_file(path, files::kMaxConfigBytes);
  } catch (const files::FileError& e) {
    throw ConfigError(std::string("configuration ") + e.what());
  }
  return parse_server_config(text, path.string(), path.parent_path());
}

}  // namespace tsmh::haptics
