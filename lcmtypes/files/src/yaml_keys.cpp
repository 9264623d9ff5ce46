#include "files/yaml_keys.hpp"

#include <utility>
#include <vector>

namespace tsmh::files {
namespace {

std::optional<std::string> below(const YAML::Node& n, const std::string& source,
                                 const std::string& path) {
  if (n.IsSequence()) {
    for (std::size_t i = 0; i < n.size(); ++i) {
      if (auto found = below(n[i], source, path + "[" + std::to_string(i) + "]")) return found;
    }
    return std::nullopt;
  }
  if (!n.IsMap()) return std::nullopt;
  std::vector<std::pair<std::string, YAML::Mark>> seen;
  for (const auto& kv : n) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : std::string("(complex key)");
    const std::string field = path.empty() ? key : path + "." + key;
    for (const auto& [k, mark] : seen) {
      if (k != key) continue;
      return source + ": " + field + ": duplicate key (line " +
             std::to_string(kv.first.Mark().line + 1) + "; first at line " +
             std::to_string(mark.line + 1) + ")";
    }
    seen.emplace_back(key, kv.first.Mark());
    if (auto found = below(kv.second, source, field)) return found;
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> find_duplicate_key(const YAML::Node& root, const std::string& source) {
  return below(root, source, "");
}

}  // namespace tsmh::files
