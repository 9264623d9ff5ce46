#pragma once
// A test fixture with a scratch folder of its own, named per process and per
// test so parallel ctest runs never share or remove each other's files.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace tsmh::haptics::test {

class ScratchDirTest : public ::testing::Test {
 protected:
  explicit ScratchDirTest(std::string stem) : stem_(std::move(stem)) {}
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           (stem_ + "-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::filesystem::path dir_;

 private:
  std::string stem_;
};

}  // namespace tsmh::haptics::test
