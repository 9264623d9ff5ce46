// One line per problem: doubtful parameters are grouped with those they are
// strongly correlated with and with the other doubtful ones of their term.
#include <gtest/gtest.h>

#include "estimator/uncertainty.hpp"

namespace tsmh::estimator {
namespace {

ParameterEstimate estimate(const std::string& name, double value, double se, bool at_bound,
                           bool well) {
  ParameterEstimate e;
  e.name = name;
  e.value = value;
  e.std_error = se;
  e.lower = 0.0;
  e.upper = 100.0;
  e.at_bound = at_bound;
  e.well_identified = well;
  return e;
}

TEST(GroupedWarnings, OneLinePerProblem) {
  UncertaintyReport rep;
  rep.parameters = {estimate("core.theta", 15.0, 0.1, false, true),
                    estimate("acceleration_dependence.mu2", 0.04, 0.25, false, false),
                    estimate("acceleration_dependence.kappa2", 0.03, 0.19, false, false),
                    estimate("stribeck.kappa1", 100.0, 1.0, true, false)};
  rep.free_names = {"core.theta", "acceleration_dependence.mu2", "acceleration_dependence.kappa2",
                    "stribeck.kappa1"};
  rep.correlation = {{1, 0, 0, 0}, {0, 1, -0.99, 0}, {0, -0.99, 1, 0}, {0, 0, 0, 1}};
  // What estimate_uncertainty writes for this: five lines.
  rep.warnings = {"acceleration_dependence.mu2: poorly identified (...)",
                  "acceleration_dependence.kappa2: poorly identified (...)",
                  "stribeck.kappa1: at its upper bound (100); ...",
                  "acceleration_dependence.mu2 and acceleration_dependence.kappa2 strongly "
                  "correlated (r = -0.99): ...",
                  "no uncertainty: too few train samples or no free parameters"};
  const auto lines = grouped_warnings(rep);
  ASSERT_EQ(lines.size(), 3U);
  EXPECT_EQ(lines[0], "no uncertainty: too few train samples or no free parameters");
  EXPECT_NE(lines[1].find("acceleration_dependence.mu2, kappa2:"), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find("correlated mu2~kappa2 r = -0.99"), std::string::npos) << lines[1];
  // The one wording of a bound (value and bound), with what it means.
  EXPECT_NE(lines[2].find("stribeck.kappa1: at its upper bound (value 100, bound 100) (the "
                          "Stribeck bump pushed to its ceiling"),
            std::string::npos)
      << lines[2];
  EXPECT_NE(lines[2].find("likely absent"), std::string::npos) << lines[2];
  for (const auto& l : lines)
    EXPECT_EQ(l.find("core.theta"), std::string::npos) << "a well identified parameter: " << l;
}

}  // namespace
}  // namespace tsmh::estimator
