#pragma once
// Duplicate keys in YAML: yaml-cpp keeps both entries of `theta: 15.5` and
// `theta: 99` in one map and lookups return the first, so a corrected value
// further down a file was silently ignored. Every YAML the project reads
// (server configuration, device settings and profiles, friction-model
// params, tsm-devices settings) goes through this one check.

#include <yaml-cpp/yaml.h>

#include <optional>
#include <string>

namespace tsmh::files {

/// "SOURCE: path.key: duplicate key (line N; first at line M)" for the first
/// map anywhere under `root` that holds a key twice; nullopt when none does.
/// Callers throw it as their own error type.
std::optional<std::string> find_duplicate_key(const YAML::Node& root, const std::string& source);

}  // namespace tsmh::files
