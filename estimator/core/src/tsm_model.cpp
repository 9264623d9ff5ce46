#include "estimator/tsm_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tsmh::estimator {

bool TsmModelSpec::has(TermKind kind) const {
  return std::any_of(terms.begin(), terms.end(), [&](const Term& t) { return t.kind == kind; });
}

Term& TsmModelSpec::add(TermKind kind) {
  for (auto& t : terms) {
    if (t.kind == kind) return t;
  }
  Term term{kind, {}};
  const auto& params = term_info(kind).params;
  for (std::size_t i = 0; i < params.size(); ++i)
    term.p[i] = params[i].default_value;
  terms.push_back(term);
  for (const auto& ps : params) {
    if (!ps.identified)
      fixed.push_back(std::string(term_info(kind).name) + "." + std::string(ps.name));
  }
  return terms.back();
}

namespace {

// The Bouc-Wen core the paper identified (theta, gamma, sigma), with the
// state's exponent n: 2 in the paper's model, 1 for Dahl's.
TsmModelSpec paper_core(double n) {
  TsmModelSpec s;
  s.theta = 15.5181;
  s.gamma = 9.5651;
  s.n = n;
  s.sigma = 1.0;
  return s;
}

}  // namespace

TsmModelSpec paper_spec() {
  TsmModelSpec s = paper_core(2.0);
  s.add(TermKind::kCoulomb).p = {1.038};
  s.add(TermKind::kDirectionAsymmetry).p = {0.8904};
  s.add(TermKind::kStribeck).p = {1.0978, 6.1264};
  s.add(TermKind::kAccelerationDependence).p = {0.0458, 0.0269, 0.145, 13.248, 6.0297};
  s.add(TermKind::kReversalOffset).p = {0.2};
  return s;
}

TsmModelSpec paper_memory_spec() {
  TsmModelSpec s = paper_spec();
  s.add(TermKind::kHysteresisElements);
  return s;
}

TsmModelSpec dahl_spec() {
  TsmModelSpec s = paper_core(1.0);
  s.add(TermKind::kCoulomb).p = {1.0};
  return s;
}

TsmModelSpec distributed_spec() {
  TsmModelSpec s;
  s.slip = default_distributed_slip();
  return s;
}

void validate(const TsmModelSpec& s) {
  const auto bad = [](const std::string& field, const std::string& why) {
    throw std::invalid_argument(field + ": " + why);
  };
  const auto finite = [&](const std::string& field, double v) {
    if (!std::isfinite(v)) bad(field, "must be a finite number");
  };
  finite("core.theta", s.theta);
  finite("core.gamma", s.gamma);
  finite("core.n", s.n);
  finite("core.sigma", s.sigma);
  if (s.theta <= 0.0) bad("core.theta", "must be > 0");
  if (s.gamma <= 0.0) bad("core.gamma", "must be > 0");
  if (s.n < 1.0) bad("core.n", "must be >= 1");
  if (s.sigma < 0.5) bad("core.sigma", "must be >= 0.5 (smaller values make the state unbounded)");
  if (s.terms.empty() && !s.slip.enabled)
    bad("terms", "at least one term (e.g. coulomb) is needed, or distributed_slip");
  validate(s.slip);
  for (std::size_t i = 0; i < s.terms.size(); ++i) {
    const auto& info = term_info(s.terms[i].kind);
    for (std::size_t j = i + 1; j < s.terms.size(); ++j) {
      if (s.terms[j].kind == s.terms[i].kind)
        bad("terms." + std::string(info.name), "appears twice");
    }
    for (std::size_t k = 0; k < info.params.size(); ++k) {
      finite("terms." + std::string(info.name) + "." + std::string(info.params[k].name),
             s.terms[i].p[k]);
    }
    if (s.terms[i].kind == TermKind::kAccelerationDependence && s.terms[i].p[4] <= 0.0) {
      bad("terms.acceleration_dependence.kappa4", "must be > 0 (divisor of f2, eq. 9)");
    }
    if (s.terms[i].kind == TermKind::kPositionBump && s.terms[i].p[2] <= 0.0)
      bad("terms.position_bump.width", "must be > 0");
    if (s.terms[i].kind == TermKind::kLoadSaturating && s.terms[i].p[1] <= 0.0)
      bad("terms.load_saturating.l_sat", "must be > 0");
  }
}

TsmFrictionModel::TsmFrictionModel(TsmModelSpec spec) : spec_(std::move(spec)) {
  validate(spec_);
  refresh_cache();
}

void TsmFrictionModel::refresh_cache() {
  bouc_wen_ = !spec_.terms.empty();
  slip_on_ = spec_.slip.enabled;
  if (slip_on_) {
    slip_ = SlipKernel(spec_.slip);
    slip_.set_level_scales(level_scale_positive_, level_scale_negative_);
  }
  reads_sign_ =
      spec_.has(TermKind::kReversalOffset) || spec_.has(TermKind::kAccelerationDependence);
  shape_ = {spec_.theta, spec_.n, spec_.sigma};
  two_elements_ = false;
  w2_ = 0.0;
  shape2_ = shape_;
  for (const auto& t : spec_.terms) {
    if (t.kind != TermKind::kHysteresisElements) continue;
    two_elements_ = true;
    w2_ = t.p[0];
    shape2_.theta = spec_.theta * t.p[1];
  }
  asymmetric_ = spec_.has(TermKind::kDirectionAsymmetry);
  scaling_ = std::any_of(spec_.terms.begin(), spec_.terms.end(),
                         [](const Term& t) { return is_multiplicative(t.kind); });
  lambda_ = 0.0;
  for (const auto& t : spec_.terms) {
    if (t.kind == TermKind::kReversalOffset) lambda_ = t.p[0];
  }

  flat_ = {};
  flat_.enabled = true;
  int previous = -1;
  for (const auto& t : spec_.terms) {
    const int order = static_cast<int>(t.kind);
    if (order <= previous || t.kind > TermKind::kReversalOffset) {
      flat_ = {};  // another term, or another order: the general sum
      return;
    }
    previous = order;
    switch (t.kind) {
      // The partial sums of the first terms per branch, as the general sum
      // forms them (the terms' contributions are constant in each branch).
      case TermKind::kCoulomb:
        flat_.rho_positive += t.p[0];
        flat_.rho_negative += asymmetric_ ? 0.0 : t.p[0];
        break;
      case TermKind::kDirectionAsymmetry:
        flat_.rho_positive += 0.0;
        flat_.rho_negative += t.p[0];
        break;
      case TermKind::kStribeck:
        flat_.stribeck = true;
        flat_.mu1 = t.p[0];
        flat_.kappa1 = t.p[1];
        break;
      case TermKind::kAccelerationDependence:
        flat_.acceleration = true;
        flat_.acceleration_p = t.p;
        break;
      default:
        break;  // reversal_offset adds 0 to Ff
    }
  }
}

namespace {

// The distributed slip's parameters, after the terms': its shape (element
// count and reference tension fixed: an integer and a chosen origin), then
// the weights, then the copies in use.
template <class IsFixed>
void append_slip_parameters(const DistributedSlipSpec& s, const IsFixed& is_fixed,
                            std::vector<Parameter>& out) {
  const auto add = [&](const std::string& name, double v, double lo, double hi, bool fixed,
                       const char* unit) {
    const std::string q = "distributed_slip." + name;
    out.push_back({q, v, lo, hi, fixed || is_fixed(q), unit});
  };
  add("elements", s.elements, 1.0, static_cast<double>(kMaxSlipElements), true, "");
  add("width_min", s.width_min, 1e-4, 1.0, false, "rad");
  add("width_max", s.width_max, 1e-3, 3.0, false, "rad");
  add("smoothing", s.smoothing, 1e-4, 1.0, false, "rad/s");
  add("stribeck_speed", s.stribeck_speed, 1e-3, 10.0, false, "rad/s");
  add("tension_ref", s.tension_ref, -1e6, 1e6, true, "N");
  if (s.distal_elements > 0)
    add("distal_elements", s.distal_elements, 1.0, static_cast<double>(kMaxDistalElements), true,
        "");
  for (std::size_t k = 0; k < s.basis_count(); ++k) {
    const std::size_t i = s.basis_index(k);
    const bool signed_weight = i == kSlidingIndex + 3;  // viscous may be negative
    add(std::string("weights.") + slip_basis_name(i), s.weight[i], signed_weight ? -50.0 : 0.0,
        50.0, false, i == kSlidingIndex + 3 ? "N s/rad" : "N");
  }
  if (s.tension_copies) {
    for (std::size_t k = 0; k < s.basis_count(); ++k) {
      const std::size_t i = s.basis_index(k);
      add(std::string("tension_weights.") + slip_basis_name(i), s.tension_weight[i], -5.0, 5.0,
          false, "1");
    }
  }
  if (s.load_copies) {
    for (std::size_t k = 0; k < s.basis_count(); ++k) {
      const std::size_t i = s.basis_index(k);
      add(std::string("load_weights.") + slip_basis_name(i), s.load_weight[i], -kMaxLoadSlope,
          kMaxLoadSlope, false, "1");
    }
  }
  if (s.drive_copies) {
    for (std::size_t k = 0; k < s.basis_count(); ++k) {
      const std::size_t i = s.basis_index(k);
      add(std::string("drive_weights.") + slip_basis_name(i), s.drive_weight[i], -kMaxDriveSlope,
          kMaxDriveSlope, false, "1");
    }
  }
}

std::size_t slip_parameter_count(const DistributedSlipSpec& s) {
  if (!s.enabled) return 0;
  return 6 + (s.distal_elements > 0 ? 1 : 0) +
         s.basis_count() *
             (1 + (s.tension_copies ? 1 : 0) + (s.load_copies ? 1 : 0) + (s.drive_copies ? 1 : 0));
}

// Reads append_slip_parameters()'s values back, from v[i] on.
void read_slip_parameters(DistributedSlipSpec& s, std::span<const double> v, std::size_t& i) {
  const double elements = v[i++];
  if (elements != std::round(elements) || elements < 1.0 ||
      elements > static_cast<double>(kMaxSlipElements))
    throw std::invalid_argument("distributed_slip.elements: must be an integer 1 .. 24");
  if (static_cast<int>(elements) != s.elements)
    throw std::invalid_argument(
        "distributed_slip.elements: cannot change through the parameter values");
  s.width_min = v[i++];
  s.width_max = v[i++];
  s.smoothing = v[i++];
  s.stribeck_speed = v[i++];
  s.tension_ref = v[i++];
  if (s.distal_elements > 0 && v[i++] != static_cast<double>(s.distal_elements))
    throw std::invalid_argument(
        "distributed_slip.distal_elements: cannot change through the parameter values");
  for (std::size_t k = 0; k < s.basis_count(); ++k)
    s.weight[s.basis_index(k)] = v[i++];
  if (s.tension_copies) {
    for (std::size_t k = 0; k < s.basis_count(); ++k)
      s.tension_weight[s.basis_index(k)] = v[i++];
  }
  if (s.load_copies) {
    for (std::size_t k = 0; k < s.basis_count(); ++k)
      s.load_weight[s.basis_index(k)] = v[i++];
  }
  if (s.drive_copies) {
    for (std::size_t k = 0; k < s.basis_count(); ++k)
      s.drive_weight[s.basis_index(k)] = v[i++];
  }
}

}  // namespace

std::vector<Parameter> TsmFrictionModel::parameters() const {
  std::vector<Parameter> out;
  const auto is_fixed = [&](const std::string& name) {
    return std::find(spec_.fixed.begin(), spec_.fixed.end(), name) != spec_.fixed.end();
  };
  // Without level terms there is no Bouc-Wen part: its core values do nothing.
  const bool unused = spec_.terms.empty();
  const auto core = [&](const char* name, double v, double lo, double hi, const char* unit) {
    std::string q = std::string("core.") + name;
    out.push_back({q, v, lo, hi, unused || is_fixed(q), unit});
  };
  core("theta", spec_.theta, 0.1, 1000.0, "1/rad");
  core("gamma", spec_.gamma, 0.1, 100.0, "N");
  core("n", spec_.n, 1.0, 4.0, "");
  core("sigma", spec_.sigma, 0.5, 5.0, "");
  for (const auto& t : spec_.terms) {
    const auto& info = term_info(t.kind);
    for (std::size_t k = 0; k < info.params.size(); ++k) {
      const auto& ps = info.params[k];
      std::string q = std::string(info.name) + "." + std::string(ps.name);
      out.push_back(
          {q, t.p[k], ps.lower, ps.upper, !ps.identified || is_fixed(q), std::string(ps.unit)});
    }
  }
  if (spec_.slip.enabled) append_slip_parameters(spec_.slip, is_fixed, out);
  return out;
}

void TsmFrictionModel::set_values(std::span<const double> v) {
  std::size_t expected = 4;
  for (const auto& t : spec_.terms)
    expected += term_info(t.kind).params.size();
  expected += slip_parameter_count(spec_.slip);
  if (v.size() != expected)
    throw std::invalid_argument("tsm model: wrong number of parameter values");
  TsmModelSpec next = spec_;
  std::size_t i = 0;
  next.theta = v[i++];
  next.gamma = v[i++];
  next.n = v[i++];
  next.sigma = v[i++];
  for (auto& t : next.terms) {
    for (std::size_t k = 0; k < term_info(t.kind).params.size(); ++k)
      t.p[k] = v[i++];
  }
  if (next.slip.enabled) read_slip_parameters(next.slip, v, i);
  validate(next);
  spec_ = std::move(next);
  refresh_cache();
  reset();
}

void TsmFrictionModel::reset() noexcept {
  z_ = 0.0;
  z1_ = z2_ = 0.0;
  level_ = std::numeric_limits<double>::quiet_NaN();
  xd_prev_ = 0.0;
  started_ = false;
  slip_state_ = {};
  basis_ = {};
  f_ = 0.0;
  slip_level_ = std::numeric_limits<double>::quiet_NaN();
}

bool TsmFrictionModel::set_level_scales(double k_positive, double k_negative) noexcept {
  const auto ok = [](double k) { return k > 0.0 && std::isfinite(k); };
  if (!ok(k_positive) || !ok(k_negative)) return false;
  level_scale_positive_ = k_positive;
  level_scale_negative_ = k_negative;
  if (slip_on_) slip_.set_level_scales(k_positive, k_negative);
  return true;
}

double TsmFrictionModel::sliding_level(const Motion& m) const noexcept {
  // The level scales are 1 unless a recalibration set them: x 1.0 is exact,
  // so the identified model's output is unchanged bit for bit.
  if (!flat_.enabled) {
    double level = sum_of_term_levels(spec_.terms, m, asymmetric_);
    if (scaling_) {
      // Multiplicative terms read the distal load as drive less the
      // friction before this step (one sample old: at 1 kHz the friction
      // moves little in a step, and the level stays explicit).
      const double f_before = friction();
      for (const auto& t : spec_.terms)
        if (is_multiplicative(t.kind)) level *= term_scaling(t, m, f_before);
    }
    return std::max(level_scale(negative_branch(m.xd)) * level, kMinSlidingLevel);
  }
  const bool negative = negative_branch(m.xd);
  const double speed = std::fabs(m.xd);
  double level = negative ? flat_.rho_negative : flat_.rho_positive;
  if (flat_.stribeck) level += stribeck_level(flat_.mu1, flat_.kappa1, speed);
  if (flat_.acceleration) level += acceleration_level(flat_.acceleration_p, m, negative, speed);
  return std::max(level_scale(negative) * level, kMinSlidingLevel);
}

double TsmFrictionModel::step(const Motion& m, double dt) noexcept {
  if (!std::isfinite(m.xd) || !std::isfinite(m.xdd) || !std::isfinite(m.x) ||
      !std::isfinite(m.load) || !std::isfinite(m.t) || !(dt > 0.0) || !std::isfinite(dt)) {
    return friction();
  }
  // Trapezoidal velocity over the interval: second-order accurate drive for
  // smooth motion, where holding the end-point velocity would be first order.
  const double xd_mid = started_ ? 0.5 * (xd_prev_ + m.xd) : m.xd;
  xd_prev_ = m.xd;
  started_ = true;
  if (slip_on_) return step_with_slip(m, dt, xd_mid);
  const double g = drive(xd_mid, m.acc_sign);
  level_ = sliding_level(m);
  if (!two_elements_) {
    z_ = advance_bouc_wen_state(z_, level_, g, dt, shape_);
    return friction();
  }
  z1_ = advance_bouc_wen_state(z1_, level_, g, dt, shape_);
  z2_ = advance_bouc_wen_state(z2_, level_, g, dt, shape2_);
  z_ = (1.0 - w2_) * z1_ + w2_ * z2_;
  return friction();
}

FrictionDynamics::StepResult TsmFrictionModel::step_with_level(const Motion& m,
                                                               double dt) noexcept {
  const double f = TsmFrictionModel::step(m, dt);
  return {f, sliding_friction()};
}

double TsmFrictionModel::step_with_slip(const Motion& m, double dt, double xd_mid) noexcept {
  double bouc_wen = 0.0;
  if (bouc_wen_) {
    const double g = drive(xd_mid, m.acc_sign);
    level_ = sliding_level(m);
    if (!two_elements_) {
      z_ = advance_bouc_wen_state(z_, level_, g, dt, shape_);
    } else {
      z1_ = advance_bouc_wen_state(z1_, level_, g, dt, shape_);
      z2_ = advance_bouc_wen_state(z2_, level_, g, dt, shape2_);
      z_ = (1.0 - w2_) * z1_ + w2_ * z2_;
    }
    bouc_wen = spec_.gamma * z_;
  }
  slip_.advance(slip_state_, m.x, m.xd, m.tension, m.drive, m.x_out, basis_);
  f_ = slip_.friction(basis_, m.tension, m.drive, bouc_wen, slip_level_);
  if (bouc_wen_) slip_level_ += spec_.gamma * level_;
  return f_;
}

void TsmFrictionModel::save_slip(DynamicsState& out) const noexcept {
  out.v[6] = slip_state_.x_prev;
  out.v[7] = slip_state_.started ? 1.0 : 0.0;
  out.v[8] = f_;
  out.v[9] = slip_level_;
  for (std::size_t i = 0; i < spec_.slip.element_count(); ++i)
    out.v[10 + i] = slip_state_.e[i];
  out.v[10 + kMaxSlipElements] = slip_state_.coulomb;
  if (spec_.slip.distal_elements == 0) return;
  constexpr std::size_t kDistal = 11 + kMaxSlipElements;
  for (std::size_t j = 0; j < spec_.slip.distal_count(); ++j)
    out.v[kDistal + j] = slip_state_.d[j];
  out.v[kDistal + kMaxDistalElements] = slip_state_.y_prev;
  out.v[kDistal + kMaxDistalElements + 1] = slip_state_.y_measured ? 1.0 : 0.0;
}

void TsmFrictionModel::restore_slip(const DynamicsState& s) noexcept {
  slip_state_.x_prev = s.v[6];
  slip_state_.started = s.v[7] != 0.0;
  f_ = s.v[8];
  slip_level_ = s.v[9];
  for (std::size_t i = 0; i < spec_.slip.element_count(); ++i)
    slip_state_.e[i] = s.v[10 + i];
  slip_state_.coulomb = s.v[10 + kMaxSlipElements];
  if (spec_.slip.distal_elements == 0) return;
  constexpr std::size_t kDistal = 11 + kMaxSlipElements;
  for (std::size_t j = 0; j < spec_.slip.distal_count(); ++j)
    slip_state_.d[j] = s.v[kDistal + j];
  slip_state_.y_prev = s.v[kDistal + kMaxDistalElements];
  slip_state_.y_measured = s.v[kDistal + kMaxDistalElements + 1] != 0.0;
}

void TsmFrictionModel::preset(double friction, const Motion& m) noexcept {
  if (!std::isfinite(friction)) return;
  if (slip_on_) {
    // The same fraction of each part's saturation: the Bouc-Wen part's
    // gamma Ff and the elements' break forces (at rest the sliding functions
    // add nothing).
    const double bw = bouc_wen_ ? spec_.gamma * sliding_level(m) : 0.0;
    const double capacity = bw + slip_.element_capacity(m.tension);
    const double fraction = capacity > 0.0 ? std::clamp(friction / capacity, -1.0, 1.0) : 0.0;
    if (bouc_wen_) {
      level_ = bw / spec_.gamma;
      z_ = z1_ = z2_ = fraction * level_;
    }
    slip_.preset(slip_state_, m.x, fraction, m.tension, m.x_out);
    f_ = fraction * capacity;
    slip_level_ = capacity;
    return;
  }
  level_ = sliding_level(m);
  z_ = std::clamp(friction / spec_.gamma, -level_, level_);
  z1_ = z2_ = z_;
}

std::unique_ptr<FrictionModel> TsmFrictionModel::clone() const {
  return std::make_unique<TsmFrictionModel>(*this);
}

}  // namespace tsmh::estimator
