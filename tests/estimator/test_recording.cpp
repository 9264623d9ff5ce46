#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "estimator/recording.hpp"

namespace tsmh::estimator {
namespace {

class RecordingCsv : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("tsmh_rec_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path write(const std::string& text) {
    const auto p = dir_ / "data.csv";
    std::ofstream(p) << text;
    return p;
  }
  std::string error_of(const std::string& text, RecordingRequirements need = {}) {
    try {
      read_recording_csv(write(text), std::nullopt, need);
    } catch (const DataError& e) {
      return e.what();
    }
    return "";
  }
  std::filesystem::path dir_;
};

TEST_F(RecordingCsv, ReadsContractWithCommentsAndRadius) {
  const auto rec =
      read_recording_csv(write("# radius_m: 0.01\n# a note\nt,x_in,T1,T3,tau_out,extra\n"
                               "0,0.1,20,10,0.05,7\n# mid comment\n0.001,0.2,21,10,0.06,8\n"));
  EXPECT_DOUBLE_EQ(rec.radius_m, 0.01);
  ASSERT_EQ(rec.size(), 2u);
  EXPECT_DOUBLE_EQ(rec.tau_in[1], 0.01 * 11.0);  // tau_in = R (T1 - T3)
  const auto f = rec.measured_friction();
  EXPECT_NEAR(f[0], (0.1 - 0.05) / 0.01, 1e-12);
}

TEST_F(RecordingCsv, RadiusOverrideWins) {
  const auto rec = read_recording_csv(write("# radius_m: 0.01\nt,x_in\n0,0\n"), 0.02);
  EXPECT_DOUBLE_EQ(rec.radius_m, 0.02);
}

TEST_F(RecordingCsv, BadInputNamesFileLineAndColumn) {
  const auto nan = error_of("t,x_in,tau_in,tau_out\n0,0,0,0\n0.001,nan,0,0\n");
  EXPECT_NE(nan.find("data.csv:3"), std::string::npos) << nan;
  EXPECT_NE(nan.find("x_in"), std::string::npos) << nan;
  const auto text = error_of("t,x_in\n0,0\n0.001,abc\n");
  EXPECT_NE(text.find(":3: column 'x_in': not a number: 'abc'"), std::string::npos) << text;
  const auto time = error_of("t,x_in\n0,0\n0.002,0\n0.001,0\n");
  EXPECT_NE(time.find(":4: column 't': time is not strictly increasing"), std::string::npos)
      << time;
  const auto missing = error_of("t,tau_in\n0,0\n");
  EXPECT_NE(missing.find("column 'x_in': required column is missing"), std::string::npos)
      << missing;
  const auto count = error_of("t,x_in\n0,0,5\n");
  EXPECT_NE(count.find(":2: expected 2 values, found 3"), std::string::npos) << count;
  const auto radius = error_of("t,x_in,tau_in,tau_out\n0,0,0,0\n", {.radius = true});
  EXPECT_NE(radius.find("no pulley radius"), std::string::npos) << radius;
  const auto tau_out = error_of("# radius_m: 0.01\nt,x_in,tau_in\n0,0,0\n", {.tau_out = true});
  EXPECT_NE(tau_out.find("tau_out"), std::string::npos) << tau_out;
  EXPECT_NE(error_of("").find("no header"), std::string::npos);
  EXPECT_NE(error_of("t,x_in\n0,inf\n").find("not finite"), std::string::npos);
}

TEST_F(RecordingCsv, WriteThenReadRoundTripsExactly) {
  Recording rec;
  rec.source = "mem";
  rec.radius_m = 0.0125;
  rec.t = {0.0, 0.001, 0.0025};
  rec.x_in = {0.1, 1.0 / 3.0, -2.5e-7};
  rec.tau_in = {0.01, 0.02, 0.03};
  rec.tau_out = {0.001, 0.002, 0.003};
  const auto path = dir_ / "out.csv";
  write_recording_csv(rec, path);
  const auto back = read_recording_csv(path);
  EXPECT_DOUBLE_EQ(back.radius_m, rec.radius_m);
  EXPECT_EQ(back.x_in, rec.x_in);  // shortest round-trip formatting: bit exact
  EXPECT_EQ(back.tau_out, rec.tau_out);
}

}  // namespace
}  // namespace tsmh::estimator
