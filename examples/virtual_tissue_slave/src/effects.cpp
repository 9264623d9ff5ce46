#include "virtual_tissue_slave/effects.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace tsmh::virtual_tissue_slave {
namespace {

double parse_number(const std::string& text, const std::string& where) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v))
    throw std::invalid_argument(where + ": '" + text + "' is not a finite number");
  return v;
}

}  // namespace

std::string effect_names() {
  return "viscous=C, capstan=0|1, position=G";
}

FrictionEffects parse_effects(const std::vector<std::string>& specs, FrictionEffects e) {
  for (const std::string& spec : specs) {
    const auto eq = spec.find('=');
    const std::string where = "--effect " + spec;
    if (eq == std::string::npos || eq == 0)
      throw std::invalid_argument(where + ": expected NAME=VALUE (known: " + effect_names() + ")");
    const std::string name = spec.substr(0, eq);
    const double v = parse_number(spec.substr(eq + 1), where);
    if (name == "viscous") {
      if (v < 0) throw std::invalid_argument(where + ": viscous drag must be >= 0");
      e.viscous = v;
    } else if (name == "capstan") {
      if (v != 0.0 && v != 1.0) throw std::invalid_argument(where + ": capstan must be 0 or 1");
      e.capstan = v == 1.0;
    } else if (name == "position") {
      e.wrap_position_gain = v;
    } else {
      throw std::invalid_argument(where + ": unknown effect '" + name +
                                  "' (known: " + effect_names() + ")");
    }
  }
  return e;
}

std::pair<double, double> parse_pair(const std::string& text, const std::string& option) {
  const auto comma = text.find(',');
  const std::string where = option + " " + text;
  if (comma == std::string::npos)
    return {parse_number(text, where), std::numeric_limits<double>::quiet_NaN()};
  return {parse_number(text.substr(0, comma), where), parse_number(text.substr(comma + 1), where)};
}

}  // namespace tsmh::virtual_tissue_slave
