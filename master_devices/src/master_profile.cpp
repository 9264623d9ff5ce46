#include "master_devices/master_profile.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <sstream>

namespace tsmh::master_devices {

int MasterProfile::axis_index(std::string_view n) const {
  for (std::size_t k = 0; k < task_axes(); ++k)
    if (axis_names[k] == n) return static_cast<int>(k);
  return -1;
}

int MasterProfile::button_bit(std::string_view n) const {
  for (std::size_t b = 0; b < buttons; ++b)
    if (button_names[b] == n) return static_cast<int>(b);
  return -1;
}

namespace {

void read_names(config::FieldReader& r, std::string_view key, std::size_t count, std::size_t max,
                std::string* out, std::size_t* got) {
  const YAML::Node n = r.node(key);
  if (!n.IsDefined()) {
    if (count > 0) r.fail(key, "missing: a list of " + std::to_string(count) + " names");
    return;
  }
  if (!n.IsSequence()) r.fail(key, "must be a list of names");
  if (count > 0 && n.size() != count)
    r.fail(key, "must name " + std::to_string(count) + " axes, has " + std::to_string(n.size()));
  if (n.size() > max) r.fail(key, "at most " + std::to_string(max) + " entries");
  for (std::size_t i = 0; i < n.size(); ++i) {
    if (!n[i].IsScalar() || n[i].Scalar().empty()) r.fail(key, "entries must be non-empty names");
    for (std::size_t k = 0; k < i; ++k)
      if (out[k] == n[i].Scalar()) r.fail(key, "'" + n[i].Scalar() + "' named twice");
    out[i] = n[i].Scalar();
  }
  if (got) *got = n.size();
}

void positive_array(config::FieldReader& r, std::string_view key, JointArray& out, std::size_t n) {
  if (!r.has(key)) r.fail(key, "missing: one limit per axis (or one for all)");
  r.get_joint_array(key, out, n);
  for (std::size_t i = 0; i < n; ++i)
    if (!(out[i] > 0.0) || !std::isfinite(out[i])) r.fail(key, "every entry must be a number > 0");
}

}  // namespace

MasterProfile parse_master_profile(const std::string& yaml_text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw config::ConfigError(origin + ": not valid YAML: " + e.what());
  }
  config::reject_duplicate_keys(root, origin);
  config::FieldReader r(root, origin, "");
  MasterProfile p;
  p.name = r.get_string("name");
  p.description = r.get_string("description", "");
  p.update_rate_hz = r.get_positive("update_rate_hz", 0.0);
  if (!(p.update_rate_hz > 0.0)) r.fail("update_rate_hz", "missing: the device's update rate");

  config::FieldReader k(r.node("kinematics"), origin, "kinematics");
  const std::string type = k.get_string("type");
  const long long joints = k.get_int("joints");
  if (joints < 1 || joints > static_cast<long long>(kMaxDof))
    k.fail("joints", "must be 1.." + std::to_string(kMaxDof));
  p.kinematics.joints = static_cast<std::size_t>(joints);
  if (type == "identity") {
    p.kinematics.type = KinematicsType::kIdentity;
  } else if (type == "pantograph") {
    p.kinematics.type = KinematicsType::kPantograph;
    if (joints != 2) k.fail("joints", "a pantograph has 2 joints");
    p.kinematics.pantograph = {k.get_positive("l_m", 0.0), k.get_positive("L_m", 0.0),
                               k.get_non_negative("d_m", 0.0)};
    if (!(p.kinematics.pantograph.l_m > 0.0)) k.fail("l_m", "missing: proximal link length, m");
    if (!(p.kinematics.pantograph.L_m > 0.0)) k.fail("L_m", "missing: distal link length, m");
  } else {
    k.fail("type", "'" + type + "' is not a known kinematics (expected identity or pantograph)");
  }
  k.reject_unknown();

  const std::size_t n = p.task_axes();
  read_names(r, "axes", n, kMaxDof, p.axis_names.data(), nullptr);
  config::FieldReader w(r.node("workspace"), origin, "workspace");
  if (!w.has("min") || !w.has("max")) w.fail("min", "missing: workspace.min and workspace.max");
  w.get_joint_array("min", p.workspace_min, n);
  w.get_joint_array("max", p.workspace_max, n);
  for (std::size_t i = 0; i < n; ++i)
    if (!(p.workspace_min[i] < p.workspace_max[i]))
      w.fail("max", "every entry must be above workspace.min's");
  w.reject_unknown();
  positive_array(r, "force_limit", p.force_limit, n);
  if (p.kinematics.type == KinematicsType::kIdentity) {
    p.joint_torque_limit_nm = p.force_limit;
  } else {
    positive_array(r, "joint_torque_limit_nm", p.joint_torque_limit_nm, p.kinematics.joints);
  }
  read_names(r, "buttons", 0, p.button_names.size(), p.button_names.data(), &p.buttons);
  r.reject_unknown();
  return p;
}

MasterProfile load_master_profile(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw config::ConfigError(path.string() + ": cannot read the master profile");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_master_profile(ss.str(), path.string());
}

}  // namespace tsmh::master_devices
