#pragma once
// Baseline friction models behind the same interface, for comparison with the
// paper's model (docs/friction-model.md): Dahl, LuGre, and Kaneko's
// Coulomb/capstan model of a tendon-sheath pair.

#include <cmath>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "estimator/friction_model.hpp"

namespace tsmh::estimator {

/// One value of a baseline's Params: its name, where it is, the fit's bounds
/// and unit as parameters() lists them, and the values the model accepts.
template <class P>
struct BaselineField {
  enum class Valid { kPositive, kNonNegative, kFraction };  ///< > 0, >= 0, in [0, 1)
  const char* name;                                         ///< "params.<field>"
  double P::*value;
  double fit_lower, fit_upper;
  const char* unit;
  Valid valid;
};

/// What the baselines share: their parameters (a table of BaselineField, one
/// row per value of Params, in its order), checked when the model is built,
/// the friction they gave last, their kind (Derived::kKind), setting their
/// values, resetting and copying themselves. `Derived` is the model, `P` its
/// parameters: doubles only.
template <class Derived, class P>
class BaselineModel : public FrictionModel {
 public:
  using Params = P;
  using Field = BaselineField<P>;
  std::string kind() const override { return Derived::kKind; }
  std::vector<Parameter> parameters() const override {
    std::vector<Parameter> out;
    for (const Field& f : fields_)
      out.push_back({f.name, p_.*f.value, f.fit_lower, f.fit_upper, false, f.unit});
    return out;
  }
  double friction() const noexcept override { return f_; }
  /// The model rebuilt (its constructor checks them) from one value per
  /// field of Params, in parameters()' order.
  void set_values(std::span<const double> values) override {
    if (values.size() != kCount)
      throw std::invalid_argument(std::string(Derived::kKind) +
                                  ": wrong number of parameter values");
    static_cast<Derived&>(*this) = Derived(params_of(values, std::make_index_sequence<kCount>{}));
  }
  void reset() noexcept override { f_ = 0.0; }
  std::unique_ptr<FrictionModel> clone() const override {
    return std::make_unique<Derived>(static_cast<const Derived&>(*this));
  }

 protected:
  /// `fields`: a table with static storage, one row per value of Params.
  /// Throws std::invalid_argument naming the first value out of its range.
  BaselineModel(Params p, std::span<const Field, sizeof(P) / sizeof(double)> fields)
      : p_(p), fields_(fields) {
    for (const Field& f : fields_) {
      const double v = p_.*f.value;
      const bool ok = f.valid == Field::Valid::kPositive      ? v > 0.0
                      : f.valid == Field::Valid::kNonNegative ? v >= 0.0
                                                              : v >= 0.0 && v < 1.0;
      if (!(std::isfinite(v) && ok))
        throw std::invalid_argument(std::string(f.name) + ": must be " +
                                    (f.valid == Field::Valid::kPositive      ? "> 0"
                                     : f.valid == Field::Valid::kNonNegative ? ">= 0"
                                                                             : "in [0, 1)"));
    }
  }
  Params p_;
  double f_ = 0.0;

 private:
  static_assert(std::is_aggregate_v<Params> && sizeof(Params) % sizeof(double) == 0,
                "a baseline's Params holds its values as doubles");
  static constexpr std::size_t kCount = sizeof(Params) / sizeof(double);
  template <std::size_t... I>
  static Params params_of(std::span<const double> v, std::index_sequence<I...>) {
    return Params{v[I]...};
  }
  std::span<const Field, kCount> fields_;
};

/// Dahl: dF/dt = sigma0 (xd - |xd| F / Fc). Integrated exactly for the
/// velocity held over each interval (F relaxes exponentially towards sgn(xd) Fc).
struct DahlParams {
  double sigma0 = 148.4;  ///< N/rad, initial stiffness
  double fc = 9.2;        ///< N, Coulomb level
};

class DahlModel final : public BaselineModel<DahlModel, DahlParams> {
 public:
  static constexpr const char* kKind = "dahl";
  explicit DahlModel(Params p = {});
  double step(const Motion& m, double dt) noexcept override;
};

/// LuGre: dz/dt = v - sigma0 |v| z / g(v), g(v) = Fc + (Fs - Fc) e^-(v/vs)^2,
/// F = sigma0 z + sigma1 dz/dt + sigma2 v. Bristle state integrated exactly
/// for the held velocity.
struct LuGreParams {
  double sigma0 = 148.4;  ///< N/rad, bristle stiffness
  double sigma1 = 1.0;    ///< N s/rad, bristle damping
  double sigma2 = 0.0;    ///< N s/rad, viscous
  double fc = 9.2;        ///< N, Coulomb level
  double fs = 15.0;       ///< N, static (Stribeck) level
  double vs = 0.2;        ///< rad/s, Stribeck velocity
};

class LuGreModel final : public BaselineModel<LuGreModel, LuGreParams> {
 public:
  static constexpr const char* kKind = "lugre";
  explicit LuGreModel(Params p = {});
  void reset() noexcept override {
    z_ = 0.0;
    f_ = 0.0;
  }
  double step(const Motion& m, double dt) noexcept override;

 private:
  double z_ = 0.0;
};

/// Kaneko's Coulomb model of a tendon-sheath pair with the capstan law: in
/// sliding each tendon loses tension by e^(-mu Theta); for a pair carrying the
/// load L = |tau_in|/R over pretension this gives F = sgn(xd) (f0 + capstan L).
/// The sign is regularised over v_eps because the pure Coulomb switch is
/// discontinuous at zero velocity (the paper's criticism of this model).
struct CoulombCapstanParams {
  double f0 = 9.2;       ///< N, friction at zero load (pretension 2 T0 sinh(mu Theta))
  double capstan = 0.3;  ///< friction per N of transmitted load, 1 - e^(-mu Theta)
  double v_eps = 0.02;   ///< rad/s, width of the regularised sign
};

class CoulombCapstanModel final : public BaselineModel<CoulombCapstanModel, CoulombCapstanParams> {
 public:
  static constexpr const char* kKind = "coulomb_capstan";
  explicit CoulombCapstanModel(Params p = {});
  double step(const Motion& m, double dt) noexcept override;
};

}  // namespace tsmh::estimator
