#include "haptics/server_config.hpp"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace tsmh::haptics {
namespace {

class Reader {
 public:
  explicit Reader(std::string origin) : origin_(std::move(origin)) {}

  [[noreturn]] void fail(const std::string& field, const std::string& why) const {
    throw ConfigError(origin_ + ": " + (field.empty() ? "" : field + ": ") + why);
  }

  void only(const YAML::Node& map, const std::set<std::string>& known,
            const std::string& where) const {
    if (!map) return;
    if (!map.IsMap()) fail(where, "must be a map");
    for (const auto& kv : map) {
      const auto key = kv.first.as<std::string>();
      if (!known.count(key)) {
        std::string list;
        for (const auto& k : known)
          list += (list.empty() ? "" : ", ") + k;
        fail(where.empty() ? key : where + "." + key,
             "unknown field (expected one of: " + list + ")");
      }
    }
  }

  double number(const YAML::Node& n, const std::string& field, double fallback, double lo,
                double hi, bool lo_open = false) const {
    if (!n) return fallback;
    double v = 0.0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(field, "must be a number, got '" +
                      (n.IsScalar() ? n.Scalar() : std::string("a map or list")) + "'");
    }
    if (!std::isfinite(v) || v < lo || v > hi || (lo_open && v == lo)) {
      std::ostringstream range;
      range << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
      fail(field, "must be a finite number in " + range.str() + ", got '" + n.Scalar() + "'");
    }
    return v;
  }

  bool boolean(const YAML::Node& n, const std::string& field, bool fallback) const {
    if (!n) return fallback;
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(field, "must be true or false");
    }
  }

  std::string text(const YAML::Node& n, const std::string& field,
                   const std::string& fallback) const {
    if (!n) return fallback;
    if (!n.IsScalar()) fail(field, "must be a string");
    return n.Scalar();
  }

  double sign(const YAML::Node& n, const std::string& field) const {
    const double s = number(n, field, 1.0, -1.0, 1.0);
    if (s != 1.0 && s != -1.0) fail(field, "must be 1 or -1");
    return s;
  }

 private:
  std::string origin_;
};

// A top-level section, or an empty map when absent: const lookups in it then
// give undefined nodes (defaults apply) instead of nulls.
YAML::Node section(const YAML::Node& root, const char* key) {
  const YAML::Node n = root[key];
  if (n && !n.IsNull()) return n;
  return YAML::Node(YAML::NodeType::Map);
}

std::string resolve(const std::filesystem::path& base, const std::string& p) {
  if (p.empty() || std::filesystem::path(p).is_absolute()) return p;
  return (base / p).lexically_normal().string();
}

}  // namespace

FeedbackSource feedback_source_from_string(const std::string& s) {
  if (s == "estimated") return FeedbackSource::kEstimated;
  if (s == "naive") return FeedbackSource::kNaive;
  if (s == "none") return FeedbackSource::kNone;
  throw ConfigError("feedback: '" + s + "' is not one of estimated, naive, none");
}

ServerConfig parse_server_config(const std::string& text, const std::string& origin,
                                 const std::filesystem::path& base_dir) {
  const Reader r(origin);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    r.fail("", "not valid YAML (line " + std::to_string(e.mark.line + 1) + "): " + e.msg);
  }
  if (!root.IsMap()) r.fail("", "expected a YAML map");
  r.only(root,
         {"rate_hz", "feedback", "duration_s", "device", "lcm", "safety", "realtime", "joints",
          "evaluation"},
         "");
  ServerConfig c;
  c.source = origin;
  c.loop.rate_hz = r.number(root["rate_hz"], "rate_hz", 1000.0, 1.0, 4000.0);
  c.loop.status_every = std::max(1, static_cast<int>(std::lround(c.loop.rate_hz / 100.0)));
  try {
    c.loop.source = feedback_source_from_string(r.text(root["feedback"], "feedback", "estimated"));
  } catch (const ConfigError& e) {
    throw ConfigError(origin + ": " + e.what());
  }
  c.duration_s = r.number(root["duration_s"], "duration_s", 0.0, 0.0, 1e7);

  const YAML::Node device = section(root, "device");
  r.only(device, {"driver", "settings"}, "device");
  c.device_driver = r.text(device["driver"], "device.driver", "sim");
  c.device_settings =
      device && device["settings"] ? device["settings"] : YAML::Node(YAML::NodeType::Map);

  const YAML::Node lcm = section(root, "lcm");
  r.only(lcm, {"url", "prefix"}, "lcm");
  c.lcm_url = r.text(lcm["url"], "lcm.url", "");
  c.lcm_prefix = r.text(lcm["prefix"], "lcm.prefix", "");

  const YAML::Node safety = section(root, "safety");
  r.only(safety,
         {"stale_after_ms", "fade_ms", "recover_ms", "slave_timeout_ms", "device_stale_fault_ms"},
         "safety");
  const auto sfield = [&](const char* key, double def) {
    return r.number(safety[key], std::string("safety.") + key, def, 0.0, 1e6, true) * 1e-3;
  };
  c.loop.timing.stale_after_s = sfield("stale_after_ms", 20.0);
  c.loop.timing.fade_s = sfield("fade_ms", 50.0);
  c.loop.timing.recover_s = sfield("recover_ms", 200.0);
  c.loop.slave_timeout_s = sfield("slave_timeout_ms", 1000.0);
  c.loop.device_stale_fault_s = sfield("device_stale_fault_ms", 50.0);

  const YAML::Node rt = section(root, "realtime");
  r.only(rt, {"sched_fifo", "priority", "lock_memory", "cpu", "cpu_dma_latency"}, "realtime");
  c.realtime.sched_fifo = r.boolean(rt["sched_fifo"], "realtime.sched_fifo", true);
  c.realtime.priority = static_cast<int>(r.number(rt["priority"], "realtime.priority", 80, 1, 99));
  c.realtime.lock_memory = r.boolean(rt["lock_memory"], "realtime.lock_memory", true);
  c.realtime.cpu_dma_latency = r.boolean(rt["cpu_dma_latency"], "realtime.cpu_dma_latency", true);
  c.realtime.cpu = static_cast<int>(r.number(rt["cpu"], "realtime.cpu", -1, -1, 1023));

  const YAML::Node ev = section(root, "evaluation");
  r.only(ev, {"truth", "trace", "report", "max_trace_s"}, "evaluation");
  c.evaluation.truth = r.boolean(ev["truth"], "evaluation.truth", false);
  c.evaluation.trace = resolve(base_dir, r.text(ev["trace"], "evaluation.trace", ""));
  c.evaluation.report = resolve(base_dir, r.text(ev["report"], "evaluation.report", ""));
  c.evaluation.max_trace_s =
      r.number(ev["max_trace_s"], "evaluation.max_trace_s", 600.0, 1.0, 86400.0);

  const YAML::Node joints = root["joints"];
  if (!joints || !joints.IsSequence() || joints.size() == 0)
    r.fail("joints", "missing (a list with one entry per joint)");
  if (joints.size() > static_cast<std::size_t>(kMaxJoints))
    r.fail("joints", "at most " + std::to_string(kMaxJoints) + " joints");
  c.loop.joints = static_cast<int>(joints.size());
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const YAML::Node j = joints[i];
    const std::string w = "joints[" + std::to_string(i) + "]";
    r.only(
        j,
        {"name", "params", "radius_m", "force_scale", "force_sign", "deadband_nm", "position_scale",
         "position_sign", "slave_min_rad", "slave_max_rad", "max_torque_nm", "max_rate_nm_per_s"},
        w);
    JointConfig jc;
    jc.name = r.text(j["name"], w + ".name", "joint" + std::to_string(i + 1));
    jc.params = r.text(j["params"], w + ".params", "paper");
    if (jc.params.find('/') != std::string::npos || jc.params.ends_with(".yaml") ||
        jc.params.ends_with(".yml"))
      jc.params = resolve(base_dir, jc.params);
    jc.radius_m = r.number(j["radius_m"], w + ".radius_m", 0.01, 0.0, 1.0, true);
    c.joints.push_back(jc);
    c.loop.force[i] = {r.number(j["force_scale"], w + ".force_scale", 1.0, 0.0, 1e3),
                       r.sign(j["force_sign"], w + ".force_sign"),
                       r.number(j["deadband_nm"], w + ".deadband_nm", 0.0, 0.0, 1e3)};
    PositionMappingConfig pm;
    pm.scale = r.number(j["position_scale"], w + ".position_scale", 1.0, 0.0, 1e3, true);
    pm.sign = r.sign(j["position_sign"], w + ".position_sign");
    pm.min_ref = r.number(j["slave_min_rad"], w + ".slave_min_rad", -1e3, -1e3, 1e3);
    pm.max_ref = r.number(j["slave_max_rad"], w + ".slave_max_rad", 1e3, -1e3, 1e3);
    if (pm.min_ref >= pm.max_ref) r.fail(w + ".slave_min_rad", "must be below slave_max_rad");
    c.loop.position[i] = pm;
    if (!j["max_torque_nm"])
      r.fail(w + ".max_torque_nm", "missing: every joint needs a torque limit");
    c.loop.limits[i] = {
        r.number(j["max_torque_nm"], w + ".max_torque_nm", 0.0, 0.0, 1e3, true),
        r.number(j["max_rate_nm_per_s"], w + ".max_rate_nm_per_s", 50.0, 0.0, 1e6, true)};
  }
  return c;
}

ServerConfig load_server_config(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path.string() + ": cannot open the configuration file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_server_config(ss.str(), path.string(), path.parent_path());
}

}  // namespace tsmh::haptics
