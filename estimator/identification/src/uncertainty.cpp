#include "estimator/uncertainty.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cstdio>
#include <limits>

#include "estimator/fit_metrics.hpp"
#include "estimator/parameter_map.hpp"
#include "estimator/simulate.hpp"
#include "estimator/tsm_model.hpp"
#include "number_text.hpp"

namespace tsmh::estimator {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Each parameter's value, bounds and whether it sits at a bound.
void describe_parameters(const std::vector<Parameter>& params, const UncertaintyOptions& o,
                         UncertaintyReport& rep) {
  for (const auto& p : params) {
    ParameterEstimate e;
    e.name = p.name;
    e.unit = p.unit;
    e.value = p.value;
    e.lower = p.lower;
    e.upper = p.upper;
    e.fixed = p.fixed;
    const double range = p.upper - p.lower;
    e.at_bound = !p.fixed && range > 0.0 &&
                 (p.value - p.lower <= o.bound_margin * range ||
                  p.upper - p.value <= o.bound_margin * range);
    rep.parameters.push_back(e);
  }
}

// d friction / d parameter at the train samples, by central differences
// inside the bounds (rows: train samples, columns: free parameters).
Eigen::MatrixXd train_jacobian(const FrictionModel& fitted, const FitData& data,
                               const ParameterMap& map, const std::vector<std::size_t>& train,
                               const UncertaintyOptions& o) {
  auto model = fitted.clone();
  const std::vector<double> values = map.template_values();
  const std::size_t n = train.size(), p = map.size();
  Eigen::MatrixXd jac(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(p));
  std::vector<double> plus(data.size()), minus(data.size());
  for (std::size_t j = 0; j < p; ++j) {
    const auto& fp = map.free()[j];
    const double v = values[fp.index];
    const double range = fp.upper - fp.lower;
    const double h = o.relative_step * std::max(std::fabs(v), 1e-3 * range);
    const double hi = std::min(v + h, fp.upper);
    const double lo = std::max(v - h, fp.lower);
    std::vector<double> trial = values;
    trial[fp.index] = hi;
    model->set_values(trial);
    simulate_friction_into(*model, data.motion, plus);
    trial[fp.index] = lo;
    model->set_values(trial);
    simulate_friction_into(*model, data.motion, minus);
    const double span = hi - lo;
    for (std::size_t k = 0; k < n; ++k) {
      jac(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j)) =
          span > 0.0 ? (plus[train[k]] - minus[train[k]]) / span : 0.0;
    }
  }
  return jac;
}

// The parameters' covariance from the Jacobian, in column-scaled units.
struct ScaledCovariance {
  Eigen::VectorXd norms;         // column norms (the scaling)
  Eigen::MatrixXd cov;           // pseudo-inverse of the scaled J^T J
  std::vector<bool> degenerate;  // in an undetermined direction
  double condition_number = kInf;
};

ScaledCovariance scaled_covariance(Eigen::MatrixXd jac) {
  const auto p = static_cast<std::size_t>(jac.cols());
  ScaledCovariance c;
  // Scale columns to unit norm so the conditioning reflects redundancy, not units.
  c.norms = jac.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < c.norms.size(); ++j) {
    if (c.norms(j) > 0.0) jac.col(j) /= c.norms(j);
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(jac, Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  const double smax = sv.size() > 0 ? sv(0) : 0.0;
  const double smin = sv.size() > 0 ? sv(sv.size() - 1) : 0.0;
  c.condition_number = smin > 0.0 ? (smax / smin) * (smax / smin) : kInf;
  // Pseudo-inverse of the scaled J^T J: directions with singular values below
  // 1e-6 smax (condition 1e12) are treated as undetermined.
  const double tol = 1e-6 * smax;
  c.cov = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(p));
  c.degenerate.assign(p, false);
  for (Eigen::Index k = 0; k < sv.size(); ++k) {
    const Eigen::VectorXd vk = svd.matrixV().col(k);
    if (sv(k) > tol) {
      c.cov += vk * vk.transpose() / (sv(k) * sv(k));
    } else {
      for (std::size_t j = 0; j < p; ++j) {
        if (std::fabs(vk(static_cast<Eigen::Index>(j))) > 0.3) c.degenerate[j] = true;
      }
    }
  }
  return c;
}

// A warning per poorly identified or bound-hugging parameter; sets
// well_identified on each free parameter.
void warn_per_parameter(const ParameterMap& map, const std::vector<double>& stds,
                        const UncertaintyOptions& o, UncertaintyReport& rep) {
  for (std::size_t j = 0; j < stds.size(); ++j) {
    const auto& fp = map.free()[j];
    auto& e = rep.parameters[fp.index];
    e.std_error = stds[j];
    const double range = fp.upper - fp.lower;
    bool poor = false;
    if (!std::isfinite(stds[j])) {
      rep.warnings.push_back(e.name +
                             ": not identifiable from this data (the friction does not "
                             "depend on it, or only through other parameters)");
      poor = true;
    } else if (stds[j] > o.max_range_std * range) {
      rep.warnings.push_back(e.name + ": poorly identified (standard error " + num(stds[j]) + ", " +
                             num(100.0 * stds[j] / range, 2) + " % of its search range)");
      poor = true;
    } else if (std::fabs(e.value) > 0.0 && stds[j] > o.max_relative_std * std::fabs(e.value)) {
      rep.warnings.push_back(e.name + ": poorly identified (standard error " + num(stds[j]) + ", " +
                             num(100.0 * stds[j] / std::fabs(e.value), 2) + " % of its value)");
      poor = true;
    }
    if (e.at_bound)
      rep.warnings.push_back(e.name + ": " + at_bound_text(e) + "; " + bound_consequence(e));
    e.well_identified = !poor && !e.at_bound;
  }
}

void warn_correlated(const UncertaintyOptions& o, UncertaintyReport& rep) {
  const std::size_t p = rep.free_names.size();
  for (std::size_t a = 0; a < p; ++a) {
    for (std::size_t b = a + 1; b < p; ++b) {
      const double r = rep.correlation[a][b];
      if (std::fabs(r) > o.max_correlation) {
        rep.warnings.push_back(rep.free_names[a] + " and " + rep.free_names[b] +
                               " strongly correlated (r = " + num(r, 3) +
                               "): the data determine mainly a combination of them");
      }
    }
  }
}

bool near_lower(const ParameterEstimate& p) {
  return std::fabs(p.value - p.lower) <= std::fabs(p.value - p.upper);
}

}  // namespace

std::string at_bound_text(const ParameterEstimate& p) {
  const bool low = near_lower(p);
  return std::string("at its ") + (low ? "lower" : "upper") + " bound (value " + num(p.value, 4) +
         ", bound " + num(low ? p.lower : p.upper, 4) + ")";
}

std::string bound_consequence(const ParameterEstimate& p) {
  const auto dot = p.name.find('.');
  const std::string term = dot == std::string::npos ? "" : p.name.substr(0, dot);
  const std::string param = dot == std::string::npos ? p.name : p.name.substr(dot + 1);
  const bool low = near_lower(p);
  const std::string drop = "drop '" + term + "' from the model's terms (or list " + p.name +
                           " under fixed:) and fit again";
  // A term's size at zero: the term adds nothing on this data.
  const bool size =
      param == "mu1" || param == "mu2" || param == "mu3" || param == "c_v" || param == "w2";
  if (low && size && p.lower == 0.0)
    return "the '" + term +
           "' term adds no friction at this value: the effect is likely absent "
           "on this slave; " +
           drop;
  if (term == "stribeck" && !low)
    return "the Stribeck bump pushed to its ceiling (" + param +
           (param == "mu1" ? ": its height" : ": how fast it decays with speed") +
           ") is the fit using it for something else, not a Stribeck effect: the term is likely "
           "absent on this slave and standing in for an effect the model lacks (tsm gap names "
           "it); " +
           drop;
  if (low)
    return "the fit wanted it at or below its lowest allowed value: the data do not pin it down, "
           "or its term stands in for an effect the model lacks (tsm gap names it)";
  return "the fit wanted it at or beyond its highest allowed value: the data do not pin it down, "
         "or its term stands in for an effect the model lacks (tsm gap names it)";
}

UncertaintyReport estimate_uncertainty(const FrictionModel& fitted, const FitData& data,
                                       const UncertaintyOptions& o) {
  UncertaintyReport rep;
  const auto params = fitted.parameters();
  const ParameterMap map(params);
  describe_parameters(params, o, rep);
  if (dynamic_cast<const TsmFrictionModel*>(&fitted) != nullptr) {
    rep.notes.push_back(
        "core.gamma is fixed: it is not identifiable, because (gamma c, theta / c, every level "
        "/ c) gives exactly the same friction for any c > 0");
    rep.notes.push_back("core.n is fixed: an integer shape exponent, chosen, not fitted");
  }

  std::vector<std::size_t> train;
  for (std::size_t i = 0; i < data.size(); ++i) {
    if (data.role[i] == SampleRole::kTrain) train.push_back(i);
  }
  const std::size_t n = train.size();
  const std::size_t p = map.size();
  if (p == 0 || n <= p) {
    rep.warnings.push_back("no uncertainty: too few train samples or no free parameters");
    return rep;
  }

  // The residual's scale and correlation time: the standard errors count
  // independent samples, not rows.
  const std::vector<double> base = simulate_friction(*fitted.clone(), data.motion);
  std::vector<double> resid(n);
  double ssr = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    resid[k] = data.measured[train[k]] - base[train[k]];
    ssr += resid[k] * resid[k];
  }
  rep.residual_std = std::sqrt(ssr / static_cast<double>(n - p));
  rep.correlation_time = correlation_time(resid);

  const ScaledCovariance c = scaled_covariance(train_jacobian(fitted, data, map, train, o));
  rep.condition_number = c.condition_number;
  const double scale2 = rep.residual_std * rep.residual_std * rep.correlation_time;
  rep.correlation.assign(p, std::vector<double>(p, 0.0));
  std::vector<double> stds(p);
  for (std::size_t j = 0; j < p; ++j) {
    const auto jj = static_cast<Eigen::Index>(j);
    stds[j] = c.norms(jj) > 0.0 && !c.degenerate[j]
                  ? std::sqrt(std::max(0.0, c.cov(jj, jj) * scale2)) / c.norms(jj)
                  : kInf;
    rep.free_names.push_back(map.free()[j].name);
  }
  for (std::size_t a = 0; a < p; ++a) {
    for (std::size_t b = 0; b < p; ++b) {
      const auto ia = static_cast<Eigen::Index>(a), ib = static_cast<Eigen::Index>(b);
      const double d = std::sqrt(c.cov(ia, ia) * c.cov(ib, ib));
      rep.correlation[a][b] = d > 0.0 ? c.cov(ia, ib) / d : (a == b ? 1.0 : 0.0);
    }
  }
  warn_per_parameter(map, stds, o, rep);
  warn_correlated(o, rep);
  return rep;
}

std::vector<std::string> grouped_warnings(const UncertaintyReport& rep,
                                          const UncertaintyOptions& o) {
  const std::size_t p = rep.free_names.size();
  const auto estimate = [&](std::size_t j) -> const ParameterEstimate* {
    for (const auto& e : rep.parameters)
      if (e.name == rep.free_names[j]) return &e;
    return nullptr;
  };
  const auto term_of = [](const std::string& name) { return name.substr(0, name.find('.')); };
  std::vector<bool> doubtful(p, false);
  for (std::size_t j = 0; j < p; ++j) {
    const auto* e = estimate(j);
    doubtful[j] = e && !e->well_identified;
  }
  // Union-find over the free parameters: strongly correlated pairs, and the
  // doubtful parameters of one term.
  std::vector<std::size_t> parent(p);
  for (std::size_t j = 0; j < p; ++j)
    parent[j] = j;
  const auto find = [&](std::size_t j) {
    while (parent[j] != j)
      j = parent[j] = parent[parent[j]];
    return j;
  };
  const auto correlated = [&](std::size_t a, std::size_t b) {
    return a < rep.correlation.size() && b < rep.correlation[a].size() &&
           std::fabs(rep.correlation[a][b]) > o.max_correlation;
  };
  for (std::size_t a = 0; a < p; ++a)
    for (std::size_t b = a + 1; b < p; ++b)
      if (correlated(a, b) ||
          (doubtful[a] && doubtful[b] && term_of(rep.free_names[a]) == term_of(rep.free_names[b])))
        parent[find(a)] = find(b);

  std::vector<std::string> out;
  for (const auto& w : rep.warnings) {
    const bool about_a_parameter =
        std::any_of(rep.free_names.begin(), rep.free_names.end(),
                    [&](const std::string& n) { return w.find(n) == 0; });
    if (!about_a_parameter) out.push_back(w);
  }
  for (std::size_t root = 0; root < p; ++root) {
    std::vector<std::size_t> members;
    bool any_problem = false;
    for (std::size_t j = 0; j < p; ++j) {
      if (find(j) != root) continue;
      members.push_back(j);
      any_problem = any_problem || doubtful[j];
    }
    bool any_pair = false;
    for (std::size_t a : members)
      for (std::size_t b : members)
        any_pair = any_pair || (a < b && correlated(a, b));
    if (members.empty() || (!any_problem && !any_pair)) continue;
    std::string names, status, pairs;
    std::string last_term;
    for (std::size_t j : members) {
      const std::string& n = rep.free_names[j];
      const std::string term = term_of(n);
      names += (names.empty() ? "" : ", ") + (term == last_term ? n.substr(term.size() + 1) : n);
      last_term = term;
      const auto* e = estimate(j);
      if (!e || e->well_identified) continue;
      std::string s;
      if (e->at_bound) {
        s = at_bound_text(*e) + " (" + bound_consequence(*e) + ")";
      } else if (!std::isfinite(e->std_error)) {
        s = "not identifiable";
      } else {
        s = "standard error " +
            num(100.0 * e->std_error / std::max(std::fabs(e->value), 1e-300), 2) +
            " % of the value";
      }
      const std::string who = members.size() > 1 ? n.substr(n.find('.') + 1) + " " : "";
      status += (status.empty() ? "" : "; ") + who + s;
    }
    for (std::size_t a : members)
      for (std::size_t b : members)
        if (a < b && correlated(a, b))
          pairs += (pairs.empty() ? "" : ", ") +
                   rep.free_names[a].substr(rep.free_names[a].find('.') + 1) + "~" +
                   rep.free_names[b].substr(rep.free_names[b].find('.') + 1) +
                   " r = " + num(rep.correlation[a][b], 3);
    std::string line = names + ":";
    if (!status.empty()) line += " " + status;
    if (!pairs.empty())
      line += std::string(status.empty() ? "" : ";") + " correlated " + pairs +
              ": the data determine mainly a combination";
    else
      line += ": the data do not pin it down";
    out.push_back(line);
  }
  return out;
}

}  // namespace tsmh::estimator
