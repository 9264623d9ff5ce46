// Two pieces identification relies on: the closed-form integration of eq. (4)
// for long travels (n = 1, 2, any sigma >= 1/2), checked against a fine RK4
// reference; and output directories that appear whole or not at all.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "estimator/bouc_wen_state.hpp"
#include "estimator/staged_output.hpp"

namespace tsmh::estimator {
namespace {

namespace fs = std::filesystem;

// du/da of the normalised state (bouc_wen_state.hpp), integrated finely.
double reference(double u, double travel, double n, double sigma) {
  const int steps = 20000;
  const double h = travel / steps;
  const auto f = [&](double v) {
    const double p = std::pow(std::fabs(v), n);
    return v >= 0.0 ? 1.0 - p : 1.0 + (2.0 * sigma - 1.0) * p;
  };
  for (int i = 0; i < steps; ++i) {
    const double k1 = f(u), k2 = f(u + 0.5 * h * k1), k3 = f(u + 0.5 * h * k2), k4 = f(u + h * k3);
    u += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  return u;
}

TEST(BoucWenClosedForm, LongTravelsMatchAFineReference) {
  for (double n : {1.0, 2.0}) {
    for (double sigma : {0.5, 0.75, 1.0, 3.0}) {
      for (double u0 : {-2.0, -0.9, -0.2, 0.0, 0.4, 0.999, 1.7}) {
        for (double travel : {0.15, 0.6, 1.5, 4.0, 30.0}) {
          // theta = 1, ff = 1, g = 1: travel a = dt.
          const double z = advance_bouc_wen_state(u0, 1.0, 1.0, travel, {1.0, n, sigma});
          EXPECT_NEAR(z, reference(u0, travel, n, sigma), 1e-7)
              << "n " << n << " sigma " << sigma << " u0 " << u0 << " travel " << travel;
          // Negative drive mirrors it.
          const double zm = advance_bouc_wen_state(-u0, 1.0, -1.0, travel, {1.0, n, sigma});
          EXPECT_NEAR(zm, -z, 1e-12);
        }
      }
    }
  }
}

TEST(BoucWenClosedForm, CostDoesNotGrowWithTravel) {
  // A dropped second of samples at high speed: one call, exact fixed point.
  EXPECT_DOUBLE_EQ(advance_bouc_wen_state(-0.5, 0.01, 5.0, 1.0, {1000.0, 2.0, 1.0}), 0.01);
}

TEST(StagedDirectory, CommitMovesFilesAndLeavesNoStaging) {
  const fs::path target =
      fs::temp_directory_path() / ("tsmh_staged_ok_" + std::to_string(::getpid()));
  fs::remove_all(target);
  fs::path staging;
  {
    StagedDirectory d(target);
    staging = d.staging();
    EXPECT_TRUE(fs::is_directory(staging));
    EXPECT_FALSE(fs::exists(target));
    std::ofstream(d.file("a.txt")) << "a";
    std::ofstream(d.file("b.txt")) << "b";
    const auto moved = d.commit();
    EXPECT_EQ(moved.size(), 2U);
  }
  EXPECT_TRUE(fs::exists(target / "a.txt"));
  EXPECT_TRUE(fs::exists(target / "b.txt"));
  EXPECT_FALSE(fs::exists(staging));
  fs::remove_all(target);
}

TEST(StagedDirectory, FailureBeforeCommitWritesNothing) {
  const fs::path target =
      fs::temp_directory_path() / ("tsmh_staged_fail_" + std::to_string(::getpid()));
  fs::remove_all(target);
  fs::path staging;
  try {
    StagedDirectory d(target);
    staging = d.staging();
    std::ofstream(d.file("report.json")) << "{}";
    throw std::runtime_error("the fit failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_FALSE(fs::exists(target));
  EXPECT_FALSE(fs::exists(staging));
}

TEST(StagedDirectory, RollBackRemovesCommittedFilesAndTheCreatedTarget) {
  const fs::path target =
      fs::temp_directory_path() / ("tsmh_staged_rollback_" + std::to_string(::getpid()));
  fs::remove_all(target);
  StagedDirectory d(target);
  std::ofstream(d.file("x.txt")) << "x";
  d.commit();
  EXPECT_TRUE(fs::exists(target / "x.txt"));
  d.roll_back();
  EXPECT_FALSE(fs::exists(target));
}

}  // namespace
}  // namespace tsmh::estimator
