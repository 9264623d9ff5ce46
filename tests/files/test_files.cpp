// The files library on its own: files compared by identity (links, other
// spellings, files still to be created, folder outputs), bounded
// non-blocking reads, the duplicate-key check, the flag range check.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "files/cli_numbers.hpp"
#include "files/distinct_outputs.hpp"
#include "files/input_file.hpp"
#include "files/yaml_keys.hpp"

namespace tsmh::files {
namespace {

namespace fs = std::filesystem;

class Files : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("tsmh_files_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "sub");
    std::ofstream(dir_ / "in.csv") << "t,x_in\n";
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string error_of(const std::vector<NamedInput>& in, const std::vector<NamedOutput>& out) {
    try {
      check_distinct_outputs(in, out);
    } catch (const FileError& e) {
      return e.what();
    }
    return "";
  }

  fs::path dir_;
};

TEST_F(Files, AnOutputIsComparedWithTheInputsAsAFile) {
  const fs::path in = dir_ / "in.csv";
  fs::create_symlink("../in.csv", dir_ / "sub" / "link.csv");
  EXPECT_NE(error_of({{"the input", in}}, {{"--output", in}}), "");
  EXPECT_NE(error_of({{"the input", in}}, {{"--output", dir_ / "sub" / ".." / "in.csv"}}), "");
  EXPECT_NE(error_of({{"the input", in}}, {{"--output", dir_ / "sub" / "link.csv"}}), "");
  EXPECT_NE(error_of({{"the input", dir_ / "sub" / "link.csv"}}, {{"--output", in}}), "");
  EXPECT_EQ(error_of({{"the input", in}}, {{"--output", dir_ / "out.csv"}}), "");
  // A copy is another file.
  fs::copy_file(in, dir_ / "copy.csv");
  EXPECT_EQ(error_of({{"the input", in}}, {{"--output", dir_ / "copy.csv"}}), "");
  // A hard link is the same file.
  fs::create_hard_link(in, dir_ / "hard.csv");
  EXPECT_NE(error_of({{"the input", in}}, {{"--output", dir_ / "hard.csv"}}), "");
  // Inputs that do not exist and options not given are left to their readers.
  EXPECT_EQ(error_of({{"the input", dir_ / "none.csv"}, {"--params", ""}},
                     {{"--output", dir_ / "none.csv"}, {"--report", ""}}),
            "");
}

TEST_F(Files, TwoOutputsStillToBeCreatedAreComparedByFolderAndName) {
  EXPECT_EQ(error_of({}, {{"--trace", dir_ / "a.csv"}, {"--report", dir_ / "b.json"}}), "");
  const std::string e =
      error_of({}, {{"--trace", dir_ / "a.csv"}, {"--report", dir_ / "sub" / ".." / "a.csv"}});
  EXPECT_NE(e.find("is the same file as --trace"), std::string::npos) << e;
  // A dangling link names the file it would create.
  fs::create_symlink("a.csv", dir_ / "dangling");
  EXPECT_NE(error_of({}, {{"--trace", dir_ / "a.csv"}, {"--report", dir_ / "dangling"}}), "");
  // Devices are written through and may be shared.
  EXPECT_EQ(error_of({}, {{"--trace", "/dev/null"}, {"--report", "/dev/null"}}), "");
}

TEST_F(Files, AFolderOutputMayNotHoldAnInput) {
  std::ofstream(dir_ / "sub" / "data.csv") << "t\n";
  const std::string e =
      error_of({{"the data", dir_ / "sub" / "data.csv"}}, {{"--report", dir_ / "sub", true}});
  EXPECT_NE(e.find("lies in this folder"), std::string::npos) << e;
  EXPECT_EQ(error_of({{"the data", dir_ / "in.csv"}}, {{"--report", dir_ / "sub", true}}), "");
}

TEST_F(Files, ReadsAreBoundedAndRefuseWhatIsNotARegularFile) {
  std::ofstream(dir_ / "small") << std::string(100, 'x');
  EXPECT_EQ(read_file(dir_ / "small", 100).size(), 100U);
  try {
    read_file(dir_ / "small", 99);
    FAIL() << "read past the bound";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("is 100 bytes, larger than 99 bytes"), std::string::npos)
        << e.what();
  }
  ASSERT_EQ(::mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  EXPECT_THROW(read_file(dir_ / "fifo", 100), FileError);  // returns at once, no writer needed
  EXPECT_THROW(read_file("/dev/zero", 100), FileError);
  EXPECT_THROW(read_file(dir_, 100), FileError);
  EXPECT_THROW(read_file(dir_ / "none", 100), FileError);
}

TEST(FilesYaml, DuplicateKeysAreFoundAnywhereWithTheirLines) {
  EXPECT_FALSE(find_duplicate_key(YAML::Load("a: 1\nb: {c: 2}\n"), "f.yaml"));
  auto dup = find_duplicate_key(YAML::Load("a: 1\nb: {c: 2, c: 3}\n"), "f.yaml");
  ASSERT_TRUE(dup);
  EXPECT_EQ(*dup, "f.yaml: b.c: duplicate key (line 2; first at line 2)");
  dup = find_duplicate_key(YAML::Load("joints:\n  - {x: 1}\n  - x: 1\n    x: 2\n"), "s");
  ASSERT_TRUE(dup);
  EXPECT_EQ(*dup, "s: joints[1].x: duplicate key (line 4; first at line 3)");
}

TEST(FilesCli, FiniteRangeRefusesNanInfinityAndOutOfRange) {
  const CLI::Validator v = finite_range(0.0, 10.0, "s");
  for (std::string bad : {"nan", "inf", "-inf", "1e10", "-1", "x", "1s"}) {
    EXPECT_NE(v(bad), "") << bad;
  }
  for (std::string good : {"0", "10", "2.5"}) {
    EXPECT_EQ(v(good), "") << good;
  }
}

}  // namespace
}  // namespace tsmh::files
