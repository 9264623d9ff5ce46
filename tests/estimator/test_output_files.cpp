// Output files under hostile conditions: special files (a device,
// a FIFO, symbolic links) are written through and never renamed over; a
// write that fails part way (a file-size limit) makes `tsm fit` and `tsm gap`
// fail and leaves no truncated file in their output folder; absurd inputs
// (a time of 1e300, a header-only file, a huge line, a binary file) are
// clear, short errors.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "estimator/atomic_file.hpp"
#include "estimator/fit_data.hpp"
#include "estimator/plotting.hpp"
#include "estimator/recording.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/table.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

namespace fs = std::filesystem;

class OutputFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("tsmh_outfiles_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A private character device (as root: mknod), so no test ever risks the
  // system's /dev/null. 1,3 is null, 1,7 is full.
  fs::path device(const char* name, unsigned minor) {
    const fs::path p = dir_ / name;
    if (::mknod(p.c_str(), S_IFCHR | 0666, makedev(1, minor)) != 0) return {};
    return p;
  }

  std::string slurp(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }

  fs::path dir_;
};

struct Ran {
  int status = -1;  ///< exit code; -1 when killed by a signal
  int signal = 0;
  std::string output;
};

// Runs tsm with stdout+stderr captured; `fsize_limit` > 0 sets RLIMIT_FSIZE
// in the child with SIGXFSZ ignored, so a write beyond it fails with EFBIG
// part way through a file.
Ran run_tsm(const std::vector<std::string>& args, const fs::path& log, rlim_t fsize_limit = 0) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    if (fsize_limit > 0) {
      signal(SIGXFSZ, SIG_IGN);
      const rlimit lim{fsize_limit, fsize_limit};
      setrlimit(RLIMIT_FSIZE, &lim);
    }
    std::vector<char*> argv{const_cast<char*>(TSMH_TSM_BIN)};
    for (const auto& a : args)
      argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int st = 0;
  waitpid(pid, &st, 0);
  Ran r;
  if (WIFEXITED(st)) r.status = WEXITSTATUS(st);
  if (WIFSIGNALED(st)) r.signal = WTERMSIG(st);
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  r.output = ss.str();
  return r;
}

fs::path synthetic_csv(const fs::path& dir, double seconds, unsigned seed = 15) {
  SyntheticConfig c;
  c.seed = seed;
  c.duration_s = seconds;
  const fs::path p = dir / "data.csv";
  write_recording_csv(make_synthetic(TsmFrictionModel(paper_spec()), c).recording, p);
  return p;
}

// --- special files ----------------------------------------------------------

TEST_F(OutputFiles, ADeviceIsWrittenThroughNotReplaced) {
  const fs::path null = device("null", 3);
  const fs::path full = device("full", 7);
  if (null.empty() || full.empty()) GTEST_SKIP() << "mknod needs root";
  write_text_atomically(null, "t,F\n0,1\n");
  EXPECT_TRUE(fs::is_character_file(null)) << "the device was replaced by a regular file";
  try {
    write_text_atomically(full, std::string(100'000, 'x'));
    FAIL() << "writing to a full device succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("write failed (No space left on device)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(fs::is_character_file(full));
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

TEST_F(OutputFiles, AFifoIsWrittenThrough) {
  const fs::path fifo = dir_ / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string got;
  std::thread reader([&] { got = slurp(fifo); });
  write_text_atomically(fifo, "t,F\n0,1\n");
  reader.join();
  EXPECT_EQ(got, "t,F\n0,1\n");
  EXPECT_TRUE(fs::is_fifo(fifo));
}

TEST_F(OutputFiles, ASymlinkStaysALinkAndItsTargetIsWritten) {
  fs::create_directories(dir_ / "real");
  std::ofstream(dir_ / "real" / "out.csv") << "old\n";
  fs::create_symlink("real/out.csv", dir_ / "link.csv");
  write_text_atomically(dir_ / "link.csv", "new\n");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir_ / "link.csv")));
  EXPECT_EQ(slurp(dir_ / "real" / "out.csv"), "new\n");
  // A dangling link: its target is created, the link kept.
  fs::create_symlink("real/fresh.csv", dir_ / "dangling.csv");
  write_text_atomically(dir_ / "dangling.csv", "fresh\n");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir_ / "dangling.csv")));
  EXPECT_EQ(slurp(dir_ / "real" / "fresh.csv"), "fresh\n");
  // A link to a device: written through the device.
  const fs::path null = device("null", 3);
  if (null.empty()) return;
  fs::create_symlink(null, dir_ / "to_null.csv");
  write_text_atomically(dir_ / "to_null.csv", "x\n");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir_ / "to_null.csv")));
  EXPECT_TRUE(fs::is_character_file(null));
}

TEST_F(OutputFiles, TsmSimulateWritesThroughADeviceAndALink) {
  const fs::path data = synthetic_csv(dir_, 2.0);
  const fs::path null = device("null", 3);
  if (null.empty()) GTEST_SKIP() << "mknod needs root";
  auto r = run_tsm(
      {"simulate", "--params", "paper", "--input", data.string(), "--output", null.string()},
      dir_ / "log");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::is_character_file(null));
  fs::create_symlink("sim.csv", dir_ / "sim-link.csv");
  r = run_tsm({"simulate", "--params", "paper", "--input", data.string(), "--output",
               (dir_ / "sim-link.csv").string()},
              dir_ / "log");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir_ / "sim-link.csv")));
  EXPECT_NE(slurp(dir_ / "sim.csv").find("t,F"), std::string::npos);
  const fs::path full = device("full", 7);
  r = run_tsm(
      {"simulate", "--params", "paper", "--input", data.string(), "--output", full.string()},
      dir_ / "log");
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("No space left on device"), std::string::npos) << r.output;
}

// --- partial writes ---------------------------------------------------------

// With writes failing part way, fit and gap must not exit 0 and leave a
// truncated plot-data file in the final folder.
TEST_F(OutputFiles, FitFailsAndLeavesNothingWhenAWriteFailsPartWay) {
  const fs::path data = synthetic_csv(dir_, 8.0);
  const Ran r = run_tsm({"fit", data.string(), "--output", (dir_ / "p.yaml").string(), "--report",
                         (dir_ / "rep").string(), "--starts", "1"},
                        dir_ / "log", 64 * 1024);
  EXPECT_EQ(r.signal, 0) << "killed by signal " << r.signal << ": " << r.output;
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("file size limit reached writing"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "rep")) << "a report folder with truncated files";
  EXPECT_FALSE(fs::exists(dir_ / "p.yaml"));
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

TEST_F(OutputFiles, GapFailsAndLeavesNothingWhenAWriteFailsPartWay) {
  const fs::path data = synthetic_csv(dir_, 8.0);
  const Ran r = run_tsm({"gap", data.string(), "--output", (dir_ / "g").string(), "--max-effects",
                         "1", "--candidates", "viscous", "--threads", "2"},
                        dir_ / "log", 64 * 1024);
  EXPECT_EQ(r.signal, 0) << r.output;
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("file size limit reached writing"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "g")) << "an output folder with truncated files";
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

// --- absurd inputs ----------------------------------------------------------

std::string read_error(const fs::path& p) {
  try {
    read_recording_csv(p, 0.01, {});
  } catch (const DataError& e) {
    return e.what();
  }
  return "";
}

TEST_F(OutputFiles, AbsurdTimeColumnsAreErrors) {
  const fs::path p = dir_ / "t.csv";
  std::ofstream(p) << "t,x_in\n0,0\n0.001,0\n0.002,0\n1e300,0\n";
  EXPECT_NE(read_error(p).find("t.csv:5: column 't': time 1e+300 s is beyond"), std::string::npos)
      << read_error(p);
  std::ofstream(p) << "t,x_in\n0,0\n0.001,0\n0.002,0\n0.003,0\n5000,0\n";
  EXPECT_NE(read_error(p).find("t.csv:6: column 't': time jumps by 5000 s"), std::string::npos)
      << read_error(p);
  std::ofstream(p) << "t,x_in\n0,0\n0.001,0\n30.002,0\n30.003,0\n";
  EXPECT_EQ(read_error(p), "") << "a 30 s pause is still one recording";
}

TEST_F(OutputFiles, AHeaderOnlyFileIsAnErrorForSimulate) {
  const fs::path p = dir_ / "empty.csv";
  std::ofstream(p) << "# radius_m: 0.01\nt,x_in,tau_in\n";
  EXPECT_NE(read_error(p).find("no data rows"), std::string::npos) << read_error(p);
  const Ran r = run_tsm({"simulate", "--params", "paper", "--input", p.string(), "--output",
                         (dir_ / "out.csv").string()},
                        dir_ / "log");
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("no data rows"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
}

TEST_F(OutputFiles, HugeLinesAndBinaryFilesAreQuotedAsShortEscapedExcerpts) {
  const fs::path huge = dir_ / "huge.csv";
  std::ofstream(huge) << "t,x_in\n0," << std::string(3'000'000, '7') << "\n";
  std::string e = read_error(huge);
  EXPECT_NE(e.find("huge.csv:2: line is longer than 1048576 bytes"), std::string::npos) << e.size();
  EXPECT_LT(e.size(), 400U);
  const fs::path wide = dir_ / "wide.csv";
  std::ofstream(wide) << "t,x_in\n0," << std::string(500'000, 'z') << "\n";
  e = read_error(wide);
  EXPECT_NE(e.find("not a number: 'zzz"), std::string::npos) << e.substr(0, 300);
  EXPECT_NE(e.find("... (500000 bytes)"), std::string::npos) << e.substr(0, 300);
  EXPECT_LT(e.size(), 400U);
  const fs::path bin = dir_ / "bin.csv";
  {
    std::ofstream f(bin, std::ios::binary);
    for (int i = 0; i < 5000; ++i)
      f.put(static_cast<char>((i * 37 + 11) % 256));
  }
  e = read_error(bin);
  EXPECT_LT(e.size(), 400U) << e.size();
  EXPECT_NE(e.find("\\x"), std::string::npos) << e;
  for (const char c : e)
    EXPECT_TRUE(c >= 0x20 && c < 0x7f) << "unescaped byte " << static_cast<int>(c);
}

}  // namespace
}  // namespace tsmh::estimator

// --- one rule for outputs, checked before any work ----------------------
namespace tsmh::estimator {
namespace {

// `tsm fit --output /nonexistent/dir/x.yaml` used to fail only after the whole
// fit; `tsm gap --output /nonexistent/a/gap` created the whole path.
TEST_F(OutputFiles, OutputPathsAreCheckedBeforeAnyWorkWithOneRule) {
  const fs::path data = synthetic_csv(dir_, 20.0);
  const fs::path missing = dir_ / "nonexistent" / "dir";
  const auto t0 = std::chrono::steady_clock::now();
  Ran r = run_tsm({"fit", data.string(), "--output", (missing / "x.yaml").string()}, dir_ / "log1");
  const double fit_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("--output " + (missing / "x.yaml").string() + ": the folder '" +
                          missing.string() + "' does not exist"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("model runs"), std::string::npos) << "no fit ran:\n" << r.output;
  EXPECT_LT(fit_s, 5.0);
  r = run_tsm({"fit", data.string(), "--output", (dir_ / "p.yaml").string(), "--report",
               (missing / "rep").string()},
              dir_ / "log2");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("--report"), std::string::npos) << r.output;

  r = run_tsm({"gap", data.string(), "--output", (missing / "gap").string()}, dir_ / "log3");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("never a whole path"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "nonexistent")) << "gap created the path";

  r = run_tsm(
      {"simulate", "--params", "paper", "--input", data.string(), "--output", dir_.string()},
      dir_ / "log4");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("is a folder"), std::string::npos) << r.output;
  r = run_tsm({"convert", data.string(), "--output", (missing / "x.csv").string()}, dir_ / "log5");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
}

// Plots readable at a glance: gnuplot's enhanced text would turn
// "low_speed" into a subscript; the warm-up's large residual (the model
// starts at rest) stretched the residual axis so the scored residual was a
// flat line.
TEST_F(OutputFiles, FitPlotsPrintNamesAsWrittenAndScaleResidualsToScoredSamples) {
  const fs::path data = synthetic_csv(dir_, 20.0);
  const Ran r = run_tsm({"fit", data.string(), "--output", (dir_ / "p.yaml").string(), "--report",
                         (dir_ / "rep").string(), "--starts", "1"},
                        dir_ / "log");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* image : {"friction", "hysteresis", "residual"}) {
    const std::string gp = slurp(dir_ / "rep" / ("fit_" + std::string(image) + ".gp"));
    const auto p = gp.find("set terminal");
    ASSERT_NE(p, std::string::npos) << image << ":\n" << gp;
    EXPECT_NE(gp.substr(p, gp.find('\n', p) - p).find("noenhanced"), std::string::npos) << gp;
  }
  const std::string gp = slurp(dir_ / "rep" / "fit_residual.gp");
  EXPECT_NE(gp.find("set yrange ["), std::string::npos)
      << "residual axis from the scored samples:\n"
      << gp;
}

// The residual is drawn from its envelope per pixel column, computed from
// every sample: a one-sample spike that the plot data's stride (every 2nd
// sample of 40 s) skips is still drawn, in a line of at most 2 points per
// column instead of one per sample.
TEST_F(OutputFiles, FitResidualPlotKeepsEverySpike) {
  FitData d;
  d.source = "spike";
  for (int i = 0; i < 40000; ++i) {
    Motion m;
    m.t = 0.001 * i;
    m.xd = std::sin(m.t);
    d.motion.push_back(m);
    d.measured.push_back(0.1 * std::sin(37.0 * m.t));
    d.role.push_back(i < 500 ? SampleRole::kIgnored : SampleRole::kTrain);
  }
  d.measured[20001] += 5.0;  // odd: not in the plot data
  const std::vector<double> model(d.size(), 0.0);
  const PlotOutcome out = plot_friction(dir_, "fit", d, {{"model", model}}, "spike");
  ASSERT_TRUE(out.error.empty()) << out.error;
  EXPECT_EQ(out.files.size(), 3U);
  EXPECT_EQ(slurp(dir_ / "fit_plot_data.csv").find("\n20.001,"), std::string::npos)
      << "the spike's sample is in the plot data: the test shows nothing";
  std::ifstream in(dir_ / "fit_residual_data.csv");
  std::string line;
  std::size_t rows = 0;
  double largest = 0.0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    ++rows;
    largest = std::max(largest, std::stod(line.substr(line.find(',') + 1)));
  }
  EXPECT_NEAR(largest, d.measured[20001], 1e-5);
  EXPECT_GT(rows, 1400U);
  EXPECT_LE(rows, 2U * 1400U);
}

}  // namespace
}  // namespace tsmh::estimator
