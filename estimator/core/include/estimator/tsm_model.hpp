#pragma once
// The paper's dynamic friction model for a pair of tendon-sheath mechanisms
// (eqs. 4-12), with the sliding level Ff composed from named terms
// (sliding_terms.hpp). F = gamma z.

#include <array>
#include <limits>
#include <string>
#include <vector>

#include "estimator/bouc_wen_state.hpp"
#include "estimator/distributed_slip.hpp"
#include "estimator/friction_model.hpp"
#include "estimator/sliding_terms.hpp"

namespace tsmh::estimator {

/// Floor of the sliding level: Ff appears as a divisor in eq. (4); terms with
/// negative contributions (decelerating, c_load < 0) must not drive it to 0.
inline constexpr double kMinSlidingLevel = 1e-3;

struct TsmModelSpec {
  double theta = 15.5181;  ///< eq. (4) rate
  double gamma = 9.5651;   ///< eq. (12) output gain, N per unit of z
  double n = 2.0;          ///< eq. (4) exponent
  double sigma = 1.0;      ///< eq. (4) shape
  /// The level terms of eq. (5). Empty only with distributed slip: then the
  /// model has no Bouc-Wen part (F is the distributed slip's alone).
  std::vector<Term> terms;
  /// Distributed slip (distributed_slip.hpp), added to gamma z; off by default.
  DistributedSlipSpec slip;
  /// Qualified parameter names excluded from identification. By default
  /// core.gamma (it trades exactly against a common scale of z, theta and
  /// every level term, so it is not identifiable), core.n (an integer
  /// shape), and data-derived values like time_varying.t0.
  std::vector<std::string> fixed = {"core.gamma", "core.n"};

  bool has(TermKind kind) const;
  /// Adds a term with its catalog defaults (no-op if present). Returns it.
  Term& add(TermKind kind);
};

/// The built-in `paper` preset: the parameters identified in the paper
/// (docs/friction-model.md), rho1 1.038 ... sigma 1.
TsmModelSpec paper_spec();
/// The `paper_memory` preset: the paper's parameters plus the
/// hysteresis_elements term at its catalog start (w2 0.2, r2 10): a starting
/// point for identifying a sheath whose hysteresis has memory (a capstan
/// whose stuck segments hold their tension), docs/friction-model.md.
TsmModelSpec paper_memory_spec();
/// A Dahl-like base (`dahl` preset): n = 1, one Coulomb level, no offset.
/// With these, eq. (4) reduces exactly to Dahl's model with sigma0 = gamma
/// theta and Fc = gamma rho1.
TsmModelSpec dahl_spec();
/// The `distributed` preset: distributed slip alone (no Bouc-Wen part), at
/// its catalog start (default_distributed_slip()): a starting point for
/// identifying a real sheath, docs/friction-model.md.
TsmModelSpec distributed_spec();

/// Throws std::invalid_argument naming the field when the spec is unusable
/// (non-finite, theta/gamma <= 0, n < 1, sigma < 0.5, kappa4 <= 0, duplicate term,
/// a distributed-slip field out of range).
void validate(const TsmModelSpec& spec);

class TsmFrictionModel final : public FrictionModel {
 public:
  explicit TsmFrictionModel(TsmModelSpec spec);

  std::string kind() const override { return "tsm"; }
  std::vector<Parameter> parameters() const override;
  void set_values(std::span<const double> values) override;
  void reset() noexcept override;
  double step(const Motion& m, double dt) noexcept override;
  StepResult step_with_level(const Motion& m, double dt) noexcept override;
  double friction() const noexcept override { return slip_on_ ? f_ : spec_.gamma * z_; }
  bool reads_acceleration_sign() const noexcept override { return reads_sign_; }
  void preset(double friction, const Motion& m) noexcept override;
  /// gamma Ff at the last step's (or preset's) motion; NaN before either.
  double sliding_friction() const noexcept override {
    return slip_on_ ? slip_level_ : spec_.gamma * level_;
  }
  /// Scales Ff (every level term, after their sum) by k_positive on the
  /// xd >= 0 branch, k_negative on the other; theta, the memory and the
  /// state stay. Kept through reset() and set_values().
  bool set_level_scales(double k_positive, double k_negative) noexcept override;
  double level_scale(bool negative) const noexcept {
    return negative ? level_scale_negative_ : level_scale_positive_;
  }
  std::unique_ptr<FrictionModel> clone() const override;
  bool save_state(DynamicsState& out) const noexcept override {
    // Element by element: the paper's model writes only what it has.
    out.v[0] = z_, out.v[1] = z1_, out.v[2] = z2_, out.v[3] = level_, out.v[4] = xd_prev_;
    out.v[5] = started_ ? 1.0 : 0.0;
    if (slip_on_) save_slip(out);
    return true;
  }
  void restore_state(const DynamicsState& s) noexcept override {
    z_ = s.v[0];
    z1_ = s.v[1];
    z2_ = s.v[2];
    level_ = s.v[3];
    xd_prev_ = s.v[4];
    started_ = s.v[5] != 0.0;
    if (slip_on_) restore_slip(s);
  }

  const TsmModelSpec& spec() const { return spec_; }
  /// Ff at motion m (eq. 5 with the configured terms), floored at kMinSlidingLevel.
  double sliding_level(const Motion& m) const noexcept;
  /// g of eq. (4).
  double drive(double xd, double acc_sign) const noexcept { return xd + lambda_ * acc_sign; }
  double state() const noexcept { return z_; }
  /// True when sliding_level() takes the flat evaluation of the paper's
  /// terms instead of the general sum (see FlatLevel).
  bool uses_flat_level() const noexcept { return flat_.enabled; }
  /// The distributed slip's basis at the last step (identification reads it).
  const SlipBasis& slip_basis() const noexcept { return basis_; }
  /// gamma z of the last step: the Bouc-Wen part's friction (0 without one).
  double bouc_wen_friction() const noexcept { return bouc_wen_ ? spec_.gamma * z_ : 0.0; }

 private:
  void refresh_cache();
  double step_with_slip(const Motion& m, double dt, double xd_mid) noexcept;
  void save_slip(DynamicsState& out) const noexcept;
  void restore_slip(const DynamicsState& s) noexcept;

  // Ff of the paper's terms without the loop over the term list: when the
  // spec has only coulomb, direction_asymmetry, stribeck,
  // acceleration_dependence and reversal_offset (each optional, in catalog
  // order, as the presets and tsm fit write them), Ff is the branch's
  // constant partial sum of coulomb and direction_asymmetry, plus the
  // stribeck and acceleration terms (reversal_offset adds 0), added in the
  // list's order: the same sum as sum_of_term_levels(), bit for bit
  // (test_model_fast_path.cpp).
  struct FlatLevel {
    bool enabled = false;
    double rho_positive = 0.0;  // coulomb + direction_asymmetry for xd >= 0
    double rho_negative = 0.0;  // ... for xd < 0
    bool stribeck = false;
    double mu1 = 0.0;
    double kappa1 = 0.0;
    bool acceleration = false;
    std::array<double, kMaxTermParams> acceleration_p{};
  };

  TsmModelSpec spec_;
  BoucWenShape shape_;
  // hysteresis_elements: z = (1 - w2) z1 + w2 z2, each element following
  // eq. (4) with its own rate; off, the paper's single state (z_).
  bool two_elements_ = false;
  double w2_ = 0.0;
  BoucWenShape shape2_;
  double z1_ = 0.0, z2_ = 0.0;
  FlatLevel flat_;
  bool asymmetric_ = false;
  bool scaling_ = false;  // a multiplicative term (load_scaling, tension_scaling) is present
  double level_scale_positive_ = 1.0, level_scale_negative_ = 1.0;
  double lambda_ = 0.0;
  double z_ = 0.0;
  double level_ = std::numeric_limits<double>::quiet_NaN();  // Ff of the last step
  double xd_prev_ = 0.0;
  bool started_ = false;
  // Distributed slip: its kernel, state, last basis and the total friction.
  bool bouc_wen_ = true;  // terms present: the Bouc-Wen part gamma z
  bool slip_on_ = false;
  bool reads_sign_ = true;
  SlipKernel slip_;
  SlipState slip_state_;
  SlipBasis basis_;
  double f_ = 0.0;
  double slip_level_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace tsmh::estimator
