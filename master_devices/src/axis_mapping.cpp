#include "master_devices/axis_mapping.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>

namespace tsmh::master_devices {

namespace {

std::string known_list(const std::string* names, std::size_t n) {
  std::string s;
  for (std::size_t i = 0; i < n; ++i)
    s += (i ? ", " : "") + names[i];
  return s.empty() ? "none" : s;
}

// Scales v[0..n) down uniformly until |v[i]| <= limit[i] for every i.
void limit_uniformly(JointArray& v, const JointArray& limit, std::size_t n) {
  double k = 1.0;
  for (std::size_t i = 0; i < n; ++i)
    if (std::abs(v[i]) > limit[i]) k = std::min(k, limit[i] / std::abs(v[i]));
  for (std::size_t i = 0; i < n; ++i)
    v[i] *= k;
}

}  // namespace

MappingConfig parse_mapping(const YAML::Node& node, const MasterProfile& profile,
                            const std::string& origin, const std::string& path) {
  config::FieldReader r(node, origin, path);
  MappingConfig c;
  const YAML::Node joints = r.node("joints");
  if (!joints.IsDefined() || !joints.IsSequence() || joints.size() == 0 || joints.size() > kMaxDof)
    r.fail("joints", "missing: a list of 1.." + std::to_string(kMaxDof) +
                         " slave joints, each {axis: NAME, scale: S}");
  c.slave_joints = joints.size();
  for (std::size_t i = 0; i < joints.size(); ++i) {
    config::FieldReader j(joints[i], origin, r.element("joints", i));
    const std::string axis = j.get_string("axis");
    c.axes[i].master_axis = profile.axis_index(axis);
    if (c.axes[i].master_axis < 0)
      j.fail("axis", "'" + axis + "' is not an axis of " + profile.name + " (its axes: " +
                         known_list(profile.axis_names.data(), profile.task_axes()) + ")");
    c.axes[i].scale = j.get_double("scale", 1.0);
    if (c.axes[i].scale == 0.0) j.fail("scale", "must not be 0");
    c.axes[i].offset = j.get_double("offset", 0.0);
    j.reject_unknown();
  }
  config::FieldReader b(r.node("buttons"), origin, r.field("buttons"));
  auto role = [&](std::string_view key, int& bit) {
    if (!b.has(key)) return;
    const std::string name = b.get_string(key);
    bit = profile.button_bit(name);
    if (bit < 0)
      b.fail(key, "'" + name + "' is not a button of " + profile.name + " (its buttons: " +
                      known_list(profile.button_names.data(), profile.buttons) + ")");
  };
  if (b.has("dead_man") && b.get_string("dead_man") == "held") {
    c.buttons.dead_man_held = true;
  } else {
    role("dead_man", c.buttons.dead_man);
  }
  role("e_stop", c.buttons.e_stop);
  role("clutch", c.buttons.clutch);
  role("calibrate", c.buttons.calibrate);
  b.reject_unknown();
  r.reject_unknown();
  return c;
}

MasterMapping::MasterMapping(const MasterProfile& profile, const MappingConfig& config)
    : profile_(profile), config_(config) {
  for (std::size_t i = 0; i < config_.slave_joints; ++i) {
    const auto k = static_cast<std::size_t>(config_.axes[i].master_axis);
    const double centre = 0.5 * (profile_.workspace_min[k] + profile_.workspace_max[k]);
    offset_[i] = config_.axes[i].offset - config_.axes[i].scale * centre;
    v_[i] = config_.axes[i].offset;
  }
}

bool MasterMapping::update(const JointArray& q, std::uint32_t raw) {
  auto pressed = [raw](int bit) { return bit >= 0 && ((raw >> bit) & 1U) != 0; };
  const ButtonRoles& roles = config_.buttons;
  buttons_.dead_man = roles.dead_man_held || pressed(roles.dead_man);
  buttons_.e_stop = pressed(roles.e_stop);
  buttons_.clutch = pressed(roles.clutch);
  buttons_.calibrate = pressed(roles.calibrate);

  JointArray x;
  Jacobian J;
  valid_ = forward_kinematics(profile_.kinematics, q, x, J);
  if (!valid_) return false;  // hold v and the last handle position
  for (std::size_t k = 0; k < profile_.task_axes(); ++k)
    x[k] = std::clamp(x[k], profile_.workspace_min[k], profile_.workspace_max[k]);
  x_ = x;
  J_ = J;
  for (std::size_t i = 0; i < config_.slave_joints; ++i) {
    const auto k = static_cast<std::size_t>(config_.axes[i].master_axis);
    const double v = config_.axes[i].scale * x_[k] + offset_[i];
    if (buttons_.clutch) continue;  // the slave holds while the handle re-indexes
    // Leaving the clutch: re-index so the slave continues from where it held.
    if (clutched_) offset_[i] += v_[i] - v;
    v_[i] = config_.axes[i].scale * x_[k] + offset_[i];
  }
  clutched_ = buttons_.clutch;
  return true;
}

JointArray MasterMapping::handle_force(const JointArray& tau) const {
  JointArray f{};
  if (!valid_) return f;
  for (std::size_t i = 0; i < config_.slave_joints; ++i) {
    if (!std::isfinite(tau[i])) return JointArray{};
    f[static_cast<std::size_t>(config_.axes[i].master_axis)] += config_.axes[i].scale * tau[i];
  }
  limit_uniformly(f, profile_.force_limit, profile_.task_axes());
  return f;
}

JointArray MasterMapping::joint_torques(const JointArray& tau_slave) const {
  const JointArray f = handle_force(tau_slave);
  JointArray tau{};
  const std::size_t n = profile_.kinematics.joints;
  for (std::size_t j = 0; j < n; ++j)
    for (std::size_t k = 0; k < profile_.task_axes(); ++k)
      tau[j] += J_[k][j] * f[k];
  limit_uniformly(tau, profile_.joint_torque_limit_nm, n);
  return tau;
}

}  // namespace tsmh::master_devices
