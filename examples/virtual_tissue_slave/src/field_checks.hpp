#pragma once
// The checks every validate() of the virtual slave runs on its parameters,
// each error naming the parameter set and the field
// ("joint 'joint1': field 'radius_m' must be > 0").

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace tsmh::virtual_tissue_slave {

class FieldChecks {
 public:
  /// `owner`: what the fields belong to, as the error names it
  /// ("controller", "joint 'joint1':").
  explicit FieldChecks(std::string owner) : owner_(std::move(owner)) {}

  /// Throws std::invalid_argument "<owner> field '<field>' <why>" unless `ok`.
  void require(bool ok, const char* field, const char* why) const {
    if (!ok) throw std::invalid_argument(owner_ + " field '" + field + "' " + why);
  }
  void positive(double v, const char* field) const {
    require(std::isfinite(v) && v > 0, field, "must be > 0");
  }
  void non_negative(double v, const char* field) const {
    require(std::isfinite(v) && v >= 0, field, "must be >= 0");
  }

 private:
  std::string owner_;
};

}  // namespace tsmh::virtual_tissue_slave
