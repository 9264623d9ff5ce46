#include "estimator/model_io.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>

#include "estimator/atomic_file.hpp"
#include "estimator/baselines.hpp"
#include "files/input_file.hpp"
#include "files/yaml_keys.hpp"

namespace tsmh::estimator {
namespace {

[[noreturn]] void fail(const std::string& origin, const std::string& field,
                       const std::string& why) {
  throw ParamsError(origin + ": " + (field.empty() ? "" : field + ": ") + why);
}

double number(const YAML::Node& node, const std::string& origin, const std::string& field) {
  if (!node || !node.IsScalar()) fail(origin, field, "must be a number");
  double v = 0.0;
  try {
    v = node.as<double>();
  } catch (const YAML::Exception&) {
    fail(origin, field, "must be a number, got '" + node.Scalar() + "'");
  }
  if (!std::isfinite(v)) fail(origin, field, "must be finite, got '" + node.Scalar() + "'");
  return v;
}

void reject_unknown_keys(const YAML::Node& map, const std::set<std::string>& known,
                         const std::string& origin, const std::string& where) {
  for (const auto& kv : map) {
    const auto key = kv.first.as<std::string>();
    if (!known.count(key)) {
      std::string list;
      for (const auto& k : known)
        list += (list.empty() ? "" : ", ") + k;
      fail(origin, where.empty() ? key : where + "." + key,
           "unknown field (expected one of: " + list + ")");
    }
  }
}

// A list of `count` numbers, named per basis function in errors.
void read_weights(const YAML::Node& node, const DistributedSlipSpec& s, const std::string& origin,
                  const std::string& field, std::array<double, kMaxSlipBasis>& out) {
  const std::string where = "distributed_slip." + field;
  if (!node.IsSequence() || node.size() != s.basis_count())
    fail(origin, where,
         "must be a list of " + std::to_string(s.basis_count()) + " numbers (one per element, " +
             "then coulomb_positive, coulomb_negative, stribeck, viscous" +
             (s.distal_elements > 0 ? ", then one per distal element)" : ")"));
  for (std::size_t k = 0; k < s.basis_count(); ++k) {
    const std::size_t i = s.basis_index(k);
    out[i] = number(node[k], origin, where + "." + slip_basis_name(i));
  }
}

DistributedSlipSpec parse_slip(const YAML::Node& node, const std::string& origin) {
  if (!node.IsMap()) fail(origin, "distributed_slip", "must be a map");
  reject_unknown_keys(
      node,
      {"elements", "width_min", "width_max", "smoothing", "stribeck_speed", "weights",
       "tension_ref", "tension_weights", "load_weights", "drive_weights", "tendon_widths",
       "coulomb_play", "distal_elements", "distal_position", "distal_position2"},
      origin, "distributed_slip");
  DistributedSlipSpec s;
  s.enabled = true;
  const double elements = number(node["elements"], origin, "distributed_slip.elements");
  if (elements != std::round(elements) || elements < 1.0 ||
      elements > static_cast<double>(kMaxSlipElements))
    fail(origin, "distributed_slip.elements",
         "must be an integer 1 .. " + std::to_string(kMaxSlipElements));
  s.elements = static_cast<int>(elements);
  s.width_min = number(node["width_min"], origin, "distributed_slip.width_min");
  s.width_max = number(node["width_max"], origin, "distributed_slip.width_max");
  s.smoothing = number(node["smoothing"], origin, "distributed_slip.smoothing");
  s.stribeck_speed = number(node["stribeck_speed"], origin, "distributed_slip.stribeck_speed");
  if (node["tendon_widths"]) {
    const YAML::Node& tw = node["tendon_widths"];
    if (!tw.IsScalar() || (tw.Scalar() != "true" && tw.Scalar() != "false"))
      fail(origin, "distributed_slip.tendon_widths", "must be true or false");
    s.tendon_widths = tw.Scalar() == "true";
    if (s.tendon_widths && s.element_count() > kMaxSlipElements)
      fail(origin, "distributed_slip.elements",
           "must be 1 .. " + std::to_string(kMaxSlipElements / 2) +
               " with tendon_widths (one family per tendon)");
  }
  if (node["coulomb_play"]) {
    const YAML::Node& cp = node["coulomb_play"];
    if (!cp.IsScalar() || (cp.Scalar() != "true" && cp.Scalar() != "false"))
      fail(origin, "distributed_slip.coulomb_play", "must be true or false");
    s.coulomb_play = cp.Scalar() == "true";
  }
  if (node["distal_elements"]) {
    const double d = number(node["distal_elements"], origin, "distributed_slip.distal_elements");
    if (d != std::round(d) || d < 0.0 || d > static_cast<double>(kMaxDistalElements))
      fail(origin, "distributed_slip.distal_elements",
           "must be an integer 0 .. " + std::to_string(kMaxDistalElements));
    s.distal_elements = static_cast<int>(d);
  }
  if (node["distal_position"]) {
    s.distal_position = number(node["distal_position"], origin, "distributed_slip.distal_position");
    if (!(s.distal_position > 0.0 && s.distal_position <= 1.0))
      fail(origin, "distributed_slip.distal_position", "must be a number in (0, 1]");
  }
  if (node["distal_position2"]) {
    s.distal_position2 =
        number(node["distal_position2"], origin, "distributed_slip.distal_position2");
    if (!(s.distal_position2 > 0.0 && s.distal_position2 <= 1.0))
      fail(origin, "distributed_slip.distal_position2", "must be a number in (0, 1]");
    if (s.distal_elements < 2)
      fail(origin, "distributed_slip.distal_position2",
           "needs distal_elements >= 2 (one sub-family per position)");
    if (s.distal_position2 == s.distal_position)
      fail(origin, "distributed_slip.distal_position2", "must differ from distal_position");
  }
  if (!node["weights"]) fail(origin, "distributed_slip.weights", "missing");
  read_weights(node["weights"], s, origin, "weights", s.weight);
  if (node["tension_weights"]) {
    s.tension_copies = true;
    s.tension_ref = number(node["tension_ref"], origin, "distributed_slip.tension_ref");
    read_weights(node["tension_weights"], s, origin, "tension_weights", s.tension_weight);
  } else if (node["tension_ref"]) {
    s.tension_ref = number(node["tension_ref"], origin, "distributed_slip.tension_ref");
  }
  if (node["load_weights"]) {
    s.load_copies = true;
    read_weights(node["load_weights"], s, origin, "load_weights", s.load_weight);
  }
  if (node["drive_weights"]) {
    s.drive_copies = true;
    read_weights(node["drive_weights"], s, origin, "drive_weights", s.drive_weight);
  }
  return s;
}

void emit_weights(YAML::Emitter& out, const char* key, const DistributedSlipSpec& s,
                  const std::array<double, kMaxSlipBasis>& w) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (std::size_t k = 0; k < s.basis_count(); ++k)
    out << w[s.basis_index(k)];
  out << YAML::EndSeq;
}

void emit_slip(YAML::Emitter& out, const DistributedSlipSpec& s) {
  out << YAML::Key << "distributed_slip" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "elements" << YAML::Value << s.elements;
  out << YAML::Key << "width_min" << YAML::Value << s.width_min;
  out << YAML::Key << "width_max" << YAML::Value << s.width_max;
  out << YAML::Key << "smoothing" << YAML::Value << s.smoothing;
  out << YAML::Key << "stribeck_speed" << YAML::Value << s.stribeck_speed;
  if (s.tendon_widths) out << YAML::Key << "tendon_widths" << YAML::Value << true;
  if (s.coulomb_play) out << YAML::Key << "coulomb_play" << YAML::Value << true;
  if (s.distal_elements > 0) {
    out << YAML::Key << "distal_elements" << YAML::Value << s.distal_elements;
    out << YAML::Key << "distal_position" << YAML::Value << s.distal_position;
    if (s.distal_position2 > 0.0)
      out << YAML::Key << "distal_position2" << YAML::Value << s.distal_position2;
  }
  emit_weights(out, "weights", s, s.weight);
  if (s.tension_copies || s.tendon_widths)
    out << YAML::Key << "tension_ref" << YAML::Value << s.tension_ref;
  if (s.tension_copies) emit_weights(out, "tension_weights", s, s.tension_weight);
  if (s.load_copies) emit_weights(out, "load_weights", s, s.load_weight);
  if (s.drive_copies) emit_weights(out, "drive_weights", s, s.drive_weight);
  out << YAML::EndMap;
}

std::unique_ptr<FrictionModel> parse_tsm(const YAML::Node& root, const std::string& origin) {
  reject_unknown_keys(root,
                      {"model", "core", "terms", "distributed_slip", "fixed", "format", "radius_m"},
                      origin, "");
  TsmModelSpec spec;
  spec.fixed.clear();
  const YAML::Node core = root["core"];
  if (!core || !core.IsMap()) fail(origin, "core", "missing (a map with theta, gamma, n, sigma)");
  reject_unknown_keys(core, {"theta", "gamma", "n", "sigma"}, origin, "core");
  spec.theta = number(core["theta"], origin, "core.theta");
  spec.gamma = number(core["gamma"], origin, "core.gamma");
  spec.n = number(core["n"], origin, "core.n");
  spec.sigma = number(core["sigma"], origin, "core.sigma");
  if (const YAML::Node slip = root["distributed_slip"]) spec.slip = parse_slip(slip, origin);
  const YAML::Node terms = root["terms"];
  const bool no_terms = !terms || (terms.IsMap() && terms.size() == 0);
  if (no_terms && !spec.slip.enabled)
    fail(origin, "terms",
         "missing (a map of term name to its parameters; empty only with distributed_slip)");
  if (terms && !terms.IsMap())
    fail(origin, "terms", "must be a map of term name to its parameters");
  for (const auto& kv : no_terms ? YAML::Node(YAML::NodeType::Map) : terms) {
    const auto name = kv.first.as<std::string>();
    const auto kind = term_kind_from_name(name);
    if (!kind) {
      std::string list;
      for (const auto& info : term_catalog())
        list += (list.empty() ? "" : ", ") + std::string(info.name);
      fail(origin, "terms." + name, "unknown term (known: " + list + ")");
    }
    const auto& info = term_info(*kind);
    const std::string where = "terms." + name;
    if (!kv.second.IsMap()) fail(origin, where, "must be a map of parameter values");
    std::set<std::string> known;
    for (const auto& ps : info.params)
      known.insert(std::string(ps.name));
    reject_unknown_keys(kv.second, known, origin, where);
    Term term{*kind, {}};
    for (std::size_t k = 0; k < info.params.size(); ++k) {
      const auto pname = std::string(info.params[k].name);
      const YAML::Node v = kv.second[pname];
      if (!v && !info.params[k].identified) {
        term.p[k] = info.params[k].default_value;
      } else {
        term.p[k] = number(v, origin, where + "." + pname);
      }
    }
    spec.terms.push_back(term);
  }
  if (const YAML::Node fixed = root["fixed"]) {
    if (!fixed.IsSequence()) fail(origin, "fixed", "must be a list of parameter names");
    for (const auto& f : fixed)
      spec.fixed.push_back(f.as<std::string>());
  }
  try {
    auto model = std::make_unique<TsmFrictionModel>(spec);
    std::set<std::string> names;
    for (const auto& p : model->parameters())
      names.insert(p.name);
    for (const auto& f : spec.fixed) {
      if (!names.count(f)) fail(origin, "fixed", "'" + f + "' is not a parameter of this model");
    }
    return model;
  } catch (const std::invalid_argument& e) {
    fail(origin, "", e.what());
  }
}

template <class Model>
std::unique_ptr<FrictionModel> parse_baseline(const YAML::Node& root, const std::string& origin) {
  reject_unknown_keys(root, {"model", "params", "format", "radius_m"}, origin, "");
  const YAML::Node params = root["params"];
  if (!params || !params.IsMap()) fail(origin, "params", "missing (a map of parameter values)");
  Model model;
  const auto spec = model.parameters();
  std::set<std::string> known;
  for (const auto& p : spec)
    known.insert(p.name.substr(p.name.find('.') + 1));
  reject_unknown_keys(params, known, origin, "params");
  std::vector<double> values;
  for (const auto& p : spec)
    values.push_back(number(params[p.name.substr(p.name.find('.') + 1)], origin, p.name));
  try {
    model.set_values(values);
  } catch (const std::invalid_argument& e) {
    fail(origin, "", e.what());
  }
  return std::make_unique<Model>(model);
}

}  // namespace

std::vector<std::string> preset_names() {
  return {"paper",        "paper_memory", "distributed",    "dahl",
          "dahl_classic", "lugre",        "coulomb_capstan"};
}

std::unique_ptr<FrictionModel> parse_model(const std::string& text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    fail(origin, "", "not valid YAML (line " + std::to_string(e.mark.line + 1) + "): " + e.msg);
  }
  if (!root.IsMap()) fail(origin, "", "expected a YAML map with a 'model' field");
  // `core: {theta: 15.5, theta: 99}` would otherwise use the first value.
  if (const auto dup = files::find_duplicate_key(root, origin)) throw ParamsError(*dup);
  const YAML::Node kind = root["model"];
  if (!kind || !kind.IsScalar())
    fail(origin, "model", "missing (tsm, dahl, lugre or coulomb_capstan)");
  const auto k = kind.as<std::string>();
  if (k == "tsm") return parse_tsm(root, origin);
  if (k == "dahl") return parse_baseline<DahlModel>(root, origin);
  if (k == "lugre") return parse_baseline<LuGreModel>(root, origin);
  if (k == "coulomb_capstan") return parse_baseline<CoulombCapstanModel>(root, origin);
  fail(origin, "model", "unknown model '" + k + "' (tsm, dahl, lugre or coulomb_capstan)");
}

std::unique_ptr<FrictionModel> load_model(const std::string& name) {
  if (name == "paper") return std::make_unique<TsmFrictionModel>(paper_spec());
  if (name == "paper_memory") return std::make_unique<TsmFrictionModel>(paper_memory_spec());
  if (name == "distributed") return std::make_unique<TsmFrictionModel>(distributed_spec());
  if (name == "dahl") return std::make_unique<TsmFrictionModel>(dahl_spec());
  if (name == "dahl_classic") return std::make_unique<DahlModel>();
  if (name == "lugre") return std::make_unique<LuGreModel>();
  if (name == "coulomb_capstan") return std::make_unique<CoulombCapstanModel>();
  std::error_code ec;
  if (!std::filesystem::exists(std::filesystem::symlink_status(name, ec))) {
    std::string list;
    for (const auto& p : preset_names())
      list += (list.empty() ? "" : ", ") + p;
    throw ParamsError(name + ": no such file, and not a preset (" + list + ")");
  }
  // Bounded and never blocking: `params: /dev/zero` grew the server to
  // 24 GB, and a FIFO stopped its start-up where no signal reached it.
  std::string text;
  try {
    text = files::read_file(name, files::kMaxConfigBytes);
  } catch (const files::FileError& e) {
    throw ParamsError(e.what());
  }
  return parse_model(text, name);
}

std::string model_to_yaml(const FrictionModel& model, const std::vector<std::string>& header) {
  YAML::Emitter out;
  out.SetDoublePrecision(10);
  for (const auto& h : header)
    out << YAML::Comment(h) << YAML::Newline;
  out << YAML::BeginMap << YAML::Key << "model" << YAML::Value << model.kind();
  const auto params = model.parameters();
  if (const auto* tsm = dynamic_cast<const TsmFrictionModel*>(&model)) {
    const auto& s = tsm->spec();
    out << YAML::Key << "core" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
        << "theta" << YAML::Value << s.theta << YAML::Key << "gamma" << YAML::Value << s.gamma
        << YAML::Key << "n" << YAML::Value << s.n << YAML::Key << "sigma" << YAML::Value << s.sigma
        << YAML::EndMap;
    out << YAML::Key << "terms" << YAML::Value << YAML::BeginMap;
    for (const auto& t : s.terms) {
      const auto& info = term_info(t.kind);
      out << YAML::Key << std::string(info.name) << YAML::Value << YAML::Flow << YAML::BeginMap;
      for (std::size_t k = 0; k < info.params.size(); ++k)
        out << YAML::Key << std::string(info.params[k].name) << YAML::Value << t.p[k];
      out << YAML::EndMap;
    }
    out << YAML::EndMap;
    if (s.slip.enabled) emit_slip(out, s.slip);
    out << YAML::Key << "fixed" << YAML::Value << YAML::Flow << s.fixed;
  } else {
    out << YAML::Key << "params" << YAML::Value << YAML::BeginMap;
    for (const auto& p : params)
      out << YAML::Key << p.name.substr(p.name.find('.') + 1) << YAML::Value << p.value;
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

void save_model(const FrictionModel& model, const std::filesystem::path& path,
                const std::vector<std::string>& header) {
  write_text_atomically(path, model_to_yaml(model, header));
}

}  // namespace tsmh::estimator
