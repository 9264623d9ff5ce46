#include "lcm_log_source.hpp"

#include <charconv>
#include <cstdlib>
#include <iostream>

#include "bridge/link_security.hpp"
#include "bridge/log_reader.hpp"
#include "estimator/table.hpp"
#include "realtime/joint_names.hpp"
#include "realtime/joints.hpp"

namespace tsmh::tsm_cli {

estimator::Recording recording_from_lcm_log(const std::filesystem::path& path,
                                            const LcmLogSelection& sel,
                                            std::optional<double> radius_override,
                                            const estimator::RecordingRequirements& need,
                                            std::string* summary) {
  bridge::JointSeries js;
  std::optional<bridge::LinkKey> key;
  try {
    if (!sel.skip_mac) {
      const auto file = bridge::find_key_file(sel.key_file, std::getenv(bridge::kLinkKeyEnv),
                                              std::getenv("XDG_CONFIG_HOME"), std::getenv("HOME"));
      if (file) key.emplace(bridge::LinkKey::load(*file));
    }
  } catch (const bridge::LinkKeyError& e) {
    throw estimator::DataError(path.string(), 0, "", e.what());
  }
  try {
    js = bridge::read_joint_series(path, sel.joint, sel.prefix,
                                   {.accept_damage = sel.accept_truncated,
                                    .verify_key = key ? &*key : nullptr,
                                    .skip_mac = sel.skip_mac});
  } catch (const bridge::LogError& e) {
    throw estimator::DataError(e.file(), 0, "", e.detail());
  }
  if (summary != nullptr) {
    *summary = std::to_string(js.state_messages) + " SLAVE_STATE and " +
               std::to_string(js.truth_messages) +
               " SLAVE_TRUTH messages; left out: " + std::to_string(js.skipped_invalid) +
               " invalid, " + std::to_string(js.skipped_not_increasing) +
               " with time not increasing, " + std::to_string(js.rows_without_truth) +
               " without matching SLAVE_TRUTH" +
               (js.x_out.empty() ? "; no x_out (NaN in the log)" : "") +
               (sel.skip_mac ? "; MACs not checked (--skip-mac)"
                : js.no_macs ? "; no MACs in the log (read unverified)"
                : key        ? "; MACs verified, left out " + std::to_string(js.skipped_no_mac) +
                            " without and " + std::to_string(js.skipped_bad_mac) + " with a bad MAC"
                      : "");
  }
  if (js.no_macs)
    std::cerr << "tsm: warning: " << path.string()
              << ": no event carries a MAC (recorded before authentication, or from senders "
                 "without the link key): read unverified\n";
  // Accepted damage is never silent, whether or not a summary was asked for.
  if (js.damage.any())
    std::cerr << "tsm: warning: " << path.string() << ": " << js.damage.describe() << "; using the "
              << js.state_messages << " intact SLAVE_STATE events\n";
  // Through the CSV contract's own checks (time strictly increasing,
  // requirements, tau_in from T1 and T3), so a log and a CSV behave the same.
  estimator::Table table;
  table.source = path.string();
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, js.radius_m);
  table.meta["radius_m"] = std::string(buf, res.ptr);
  table.set("t", std::move(js.t));
  table.set("x_in", std::move(js.x_in));
  if (!js.tau_out.empty()) table.set("tau_out", std::move(js.tau_out));
  if (!js.x_out.empty()) table.set("x_out", std::move(js.x_out));
  table.set("T1", std::move(js.T1));
  table.set("T3", std::move(js.T3));
  return estimator::recording_from_table(table, radius_override, need);
}

DataSource lcm_log_source(const LcmLogSelection& sel) {
  DataSource s;
  s.name = "lcm-log";
  s.accepts = [](const std::filesystem::path& p) { return bridge::is_lcm_log(p); };
  s.load = [&sel](const std::filesystem::path& p, std::optional<double> radius,
                  const estimator::RecordingRequirements& need) {
    return recording_from_lcm_log(p, sel, radius, need);
  };
  return s;
}

void add_lcm_log_options(CLI::App& cmd, LcmLogSelection& sel) {
  cmd.add_option("--joint", sel.joint,
                 "LCM log DATA: the joint to read: joint1 (default), joint2, ... (or its 0-based "
                 "index)")
      ->transform(CLI::Validator(
          [](std::string& value) -> std::string {
            const auto j = realtime::joint_from_text(value, realtime::kMaxJoints);
            if (!j) return "no joint '" + value + "' (joint1, joint2, ...)";
            value = std::to_string(*j);
            return "";
          },
          "JOINT"));
  cmd.add_option("--prefix", sel.prefix,
                 "LCM log DATA: channel prefix of the arm, e.g. ARM1_ (default none)");
  cmd.add_flag("--accept-truncated", sel.accept_truncated,
               "LCM log DATA: use the intact events of a log that is cut off or has corrupt "
               "regions (and say how many were lost) instead of refusing it");
  cmd.add_option("--key", sel.key_file,
                 "LCM log DATA: link key to verify the events' MACs with (default: $TSMH_LINK_KEY, "
                 "~/.config/tsmh/link.key, /etc/tsmh/link.key; events that do not verify are left "
                 "out)");
  cmd.add_flag("--skip-mac", sel.skip_mac,
               "LCM log DATA: use the events without checking their MACs (a log from another "
               "installation, or recorded from unauthenticated senders)");
}

}  // namespace tsmh::tsm_cli
