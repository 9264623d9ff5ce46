#include "config/field_reader.hpp"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "files/input_file.hpp"
#include "files/yaml_keys.hpp"

namespace tsmh::config {

namespace {
std::string line_of(const YAML::Node& n) {
  if (!n.IsDefined()) return "";
  const YAML::Mark m = n.Mark();
  if (m.line < 0) return "";
  return " (line " + std::to_string(m.line + 1) + ")";
}
}  // namespace

void reject_duplicate_keys(const YAML::Node& root, const std::string& source) {
  if (const auto dup = files::find_duplicate_key(root, source)) throw ConfigError(*dup);
}

YAML::Node load_yaml_file(const std::filesystem::path& path, std::string_view what) {
  std::string text;
  try {
    text = files::read_file(path, files::kMaxConfigBytes);
  } catch (const files::FileError& e) {
    throw ConfigError(std::string(what) + " " + e.what());
  }
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(path.string() + ": not valid YAML (line " + std::to_string(e.mark.line + 1) +
                      "): " + e.msg);
  }
  reject_duplicate_keys(root, path.string());
  return root;
}

void config_fail(const std::string& source, const std::string& field, std::string_view message,
                 const YAML::Node& at) {
  std::string text = source + ": ";
  if (!field.empty()) text += field + ": ";
  text += message;
  text += line_of(at);
  throw ConfigError(text);
}

FieldReader::FieldReader(const YAML::Node& map, std::string source, std::string path)
    : map_(map), source_(std::move(source)), path_(std::move(path)) {
  if (map_.IsDefined() && !map_.IsNull() && !map_.IsMap()) {
    config_fail(source_, path_.empty() ? "(root)" : path_, "must be a map of key: value", map_);
  }
}

std::string FieldReader::field(std::string_view key) const {
  return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

std::string FieldReader::element(std::string_view key, std::size_t index) const {
  return field(key) + "[" + std::to_string(index) + "]";
}

bool FieldReader::has(std::string_view key) const {
  // Look up through a const node: a non-const operator[] would add the key.
  const YAML::Node& map = map_;
  if (!map.IsMap()) return false;
  const YAML::Node n = map[std::string(key)];
  return n.IsDefined() && !n.IsNull();
}

void FieldReader::fail(std::string_view key, std::string_view message) const {
  const YAML::Node& map = map_;
  YAML::Node at = has(key) ? map[std::string(key)] : map;
  config_fail(source_, field(key), message, at);
}

YAML::Node FieldReader::value(std::string_view key, bool required) {
  known_.emplace(key);
  if (!has(key)) {
    if (required) {
      config_fail(source_, field(key), "missing (required)", map_);
    }
    return YAML::Node(YAML::NodeType::Undefined);
  }
  return map_[std::string(key)];
}

YAML::Node FieldReader::node(std::string_view key) {
  return value(key, false);
}

double FieldReader::get_double(std::string_view key) {
  const YAML::Node n = value(key, true);
  double v = 0.0;
  if (!n.IsScalar() || !YAML::convert<double>::decode(n, v)) fail(key, "must be a number");
  if (!std::isfinite(v)) fail(key, "must be finite");
  return v;
}

double FieldReader::get_double(std::string_view key, double fallback) {
  return has(key) ? get_double(key) : (known_.emplace(key), fallback);
}

long long FieldReader::get_int(std::string_view key) {
  const YAML::Node n = value(key, true);
  long long v = 0;
  if (!n.IsScalar() || !YAML::convert<long long>::decode(n, v)) fail(key, "must be an integer");
  return v;
}

long long FieldReader::get_int(std::string_view key, long long fallback) {
  return has(key) ? get_int(key) : (known_.emplace(key), fallback);
}

bool FieldReader::get_bool(std::string_view key, bool fallback) {
  if (!has(key)) {
    known_.emplace(key);
    return fallback;
  }
  const YAML::Node n = value(key, true);
  bool v = false;
  if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) fail(key, "must be true or false");
  return v;
}

std::string FieldReader::get_string(std::string_view key) {
  const YAML::Node n = value(key, true);
  if (!n.IsScalar()) fail(key, "must be a string");
  return n.Scalar();
}

std::string FieldReader::get_string(std::string_view key, std::string fallback) {
  return has(key) ? get_string(key) : (known_.emplace(key), std::move(fallback));
}

void FieldReader::reject_unknown() const {
  if (!map_.IsMap()) return;
  for (const auto& kv : map_) {
    const std::string key = kv.first.Scalar();
    if (known_.find(key) == known_.end()) {
      std::string expected;
      for (const auto& k : known_)
        expected += (expected.empty() ? "" : ", ") + k;
      config_fail(source_, field(key), "unknown key (expected one of: " + expected + ")", kv.first);
    }
  }
}

double FieldReader::get_positive(std::string_view key, double fallback) {
  const double v = get_double(key, fallback);
  if (!(v > 0.0)) fail(key, "must be > 0");
  return v;
}

double FieldReader::get_non_negative(std::string_view key, double fallback) {
  const double v = get_double(key, fallback);
  if (!(v >= 0.0)) fail(key, "must be >= 0");
  return v;
}

void FieldReader::get_joint_array(std::string_view key, realtime::JointArray& out,
                                  std::size_t dof) {
  const YAML::Node n = node(key);
  if (!n.IsDefined()) return;
  if (n.IsScalar()) {
    const double v = get_double(key);
    for (std::size_t j = 0; j < dof; ++j)
      out[j] = v;
    return;
  }
  if (!n.IsSequence() || n.size() != dof)
    fail(key, "must be a number or a list of " + std::to_string(dof) + " numbers (one per joint)");
  for (std::size_t j = 0; j < dof; ++j) {
    double v = 0.0;
    if (!n[j].IsScalar() || !YAML::convert<double>::decode(n[j], v) || !std::isfinite(v))
      config_fail(source(), element(key, j), "must be a number", n[j]);
    out[j] = v;
  }
}

}  // namespace tsmh::config
