#pragma once
// Reading a YAML configuration map field by field, so that every error names
// the file and the field at fault, e.g.
//   "profile.yaml: joints[1].counts_per_rad: must be > 0 (line 14)".
// Unknown keys are errors too: a misspelt limit must not silently fall back
// to its default. One reader for every configuration of the project:
// haptic-server's own file (haptics), driver settings and device profiles
// (master_devices), tsm-devices (docs/architecture.md "Defined once").

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>

#include "realtime/joints.hpp"

namespace tsmh::config {

/// Bad configuration. The message names source and field.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class FieldReader {
 public:
  /// `source` names the file (or "server config"); `path` is where `map` sits
  /// in it ("" at the root, "joints[1]", "device.settings"). A null node is
  /// an empty map; any other non-map is an error.
  FieldReader(const YAML::Node& map, std::string source, std::string path);

  bool has(std::string_view key) const;
  /// The raw node (marks the key as known). Undefined node when absent.
  YAML::Node node(std::string_view key);

  double get_double(std::string_view key);
  double get_double(std::string_view key, double fallback);
  long long get_int(std::string_view key);
  long long get_int(std::string_view key, long long fallback);
  bool get_bool(std::string_view key, bool fallback);
  std::string get_string(std::string_view key);
  std::string get_string(std::string_view key, std::string fallback);
  /// A number > 0 (>= 0): the fallback when absent, an error naming the field otherwise.
  double get_positive(std::string_view key, double fallback);
  double get_non_negative(std::string_view key, double fallback);
  /// One value per joint: a number (every joint) or a list of `dof` numbers.
  /// Leaves `out` unchanged when absent.
  void get_joint_array(std::string_view key, realtime::JointArray& out, std::size_t dof);

  /// "path.key" (or "key" at the root), for messages.
  std::string field(std::string_view key) const;
  /// "path[index]" for a list element below this map.
  std::string element(std::string_view key, std::size_t index) const;
  const std::string& source() const { return source_; }

  /// Throws ConfigError "source: path.key: message (line N)".
  [[noreturn]] void fail(std::string_view key, std::string_view message) const;
  /// Throws when the map holds a key nobody asked for.
  void reject_unknown() const;

 private:
  YAML::Node value(std::string_view key, bool required);

  YAML::Node map_;
  std::string source_;
  std::string path_;
  std::set<std::string, std::less<>> known_;
};

/// Throws ConfigError "source: path.key: duplicate key (line N; first at line
/// M)" for the first map anywhere under `root` that holds a key twice.
/// yaml-cpp keeps both entries and lookups return the first, so without this
/// `max_torque_nm: 0.3` followed by `max_torque_nm: 50` would pass silently.
/// The check itself is files::find_duplicate_key, shared by every YAML reader.
void reject_duplicate_keys(const YAML::Node& root, const std::string& source);

/// A YAML file read within files::kMaxConfigBytes, refusing anything but a
/// regular file (a FIFO, /dev/zero) without blocking, parsed, and checked
/// for duplicate keys. `what` names the file's role in errors ("profile",
/// "settings"). Throws ConfigError.
YAML::Node load_yaml_file(const std::filesystem::path& path, std::string_view what);

/// "source: field: message (line N)" for a node outside any FieldReader.
[[noreturn]] void config_fail(const std::string& source, const std::string& field,
                              std::string_view message, const YAML::Node& at = YAML::Node());

}  // namespace tsmh::config
