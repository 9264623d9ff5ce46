// Hostile files against the real programs (tsm, haptic-server,
// virtual-slave, tsm-devices), each run through bash as a user would:
// outputs aimed at the run's own inputs, key or configuration (also through
// symbolic links and other spellings), a file-size limit (`ulimit -f`),
// duplicate YAML keys, FIFOs and devices where a file is expected, a
// gigabyte line, absurd numbers in headers and flags, a byte-order mark.
// Every case is a clear error before any work (or, for the size limit, a
// clear error and nothing left behind), and the inputs are untouched.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "estimator/recording.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/tsm_model.hpp"
#include "run_shell.hpp"

namespace tsmh::files::test {
namespace {

namespace fs = std::filesystem;

const std::string kTsm = TSMH_TSM_BIN;
const std::string kServer = TSMH_HAPTIC_SERVER;
const std::string kSlave = TSMH_VIRTUAL_SLAVE;
const std::string kDevices = TSMH_TSM_DEVICES;

// haptic-server runs that the old code did not refuse stay on a port of
// their own, confined to this host (ttl=0).
const std::string kUrl = "udpm://239.255.76.67:7743?ttl=0";

class HostileFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("tsmh_hostile_files_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  /// Runs `script` in the scratch folder (through bash).
  ShellRun sh(const std::string& script, double timeout_s = 60.0) {
    return run_shell("cd " + q(dir_.string()) + " && " + script, dir_ / "run.log", timeout_s);
  }

  std::string slurp(const fs::path& p) const {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  void write(const fs::path& p, const std::string& text) const {
    std::ofstream(p, std::ios::binary) << text;
  }

  /// A synthetic recording with tau_in, tau_out and '# radius_m:' (1 kHz).
  fs::path data_csv(double seconds, const std::string& name = "data.csv") const {
    estimator::SyntheticConfig c;
    c.seed = 34;
    c.duration_s = seconds;
    const fs::path p = dir_ / name;
    estimator::write_recording_csv(
        estimator::make_synthetic(estimator::TsmFrictionModel(estimator::paper_spec()), c)
            .recording,
        p);
    return p;
  }

  /// A link key readable by its owner only.
  fs::path key(const std::string& name = "link.key") const {
    const fs::path p = dir_ / name;
    write(p, std::string(64, 'a') + "\n");
    fs::permissions(p, fs::perms::owner_read | fs::perms::owner_write);
    return p;
  }

  /// A two-joint server configuration on the simulated console; `joint`
  /// replaces the first joint's entry.
  fs::path server_config(const std::string& joint = "{params: paper, max_torque_nm: 0.3}",
                         const std::string& name = "server.yaml") const {
    const fs::path p = dir_ / name;
    write(p,
          "rate_hz: 1000\nfeedback: naive\ndevice: {driver: sim}\n"
          "realtime: {sched_fifo: false, lock_memory: false, cpu_dma_latency: false}\n"
          "joints:\n  - " +
              joint + "\n  - {params: paper, max_torque_nm: 0.3}\n");
    return p;
  }

  std::string server(const fs::path& cfg, const std::string& more) const {
    return "exec " + kServer + " --config " + q(cfg.string()) + " --lcm-url " + q(kUrl) +
           " --quiet " + more;
  }

  /// No temporary file of an atomic write is left in the scratch folder.
  void expect_no_temporaries() const {
    for (const auto& e : fs::recursive_directory_iterator(dir_))
      EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  }

  fs::path dir_;
};

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// --- outputs that would destroy inputs -----------------------------------

TEST_F(HostileFiles, TsmOutputsOverTheirOwnInputsAreRefusedAndTheInputsKept) {
  const fs::path data = data_csv(2.0);
  const std::string before = slurp(data);
  for (const std::string& cmd : std::vector<std::string>{
           "simulate --params paper data.csv --output data.csv", "fit data.csv --output data.csv",
           "gap data.csv --output . --max-effects 1"}) {
    const ShellRun r = sh("exec " + kTsm + " " + cmd);
    EXPECT_EQ(r.code, 2) << cmd << "\n" << r.output;
    EXPECT_TRUE(has(r.output, "the data") || has(r.output, "the input")) << cmd << "\n" << r.output;
    EXPECT_EQ(slurp(data), before) << cmd << ": the recording was replaced";
  }
  // An LCM log converted onto itself.
  fs::copy_file(fs::path(TSMH_SOURCE_DIR) / "bridge/fuzz/corpus/valid.lcmlog", dir_ / "run.lcmlog");
  const std::string log = slurp(dir_ / "run.lcmlog");
  const ShellRun r = sh("exec " + kTsm + " convert run.lcmlog --output run.lcmlog");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "--output run.lcmlog: is the same file as the log run.lcmlog"))
      << r.output;
  EXPECT_EQ(slurp(dir_ / "run.lcmlog"), log);
}

TEST_F(HostileFiles, AliasesThroughLinksAndSpellingsAreTheSameFile) {
  const fs::path data = data_csv(2.0);
  const std::string before = slurp(data);
  fs::create_directories(dir_ / "sub");
  fs::create_symlink("data.csv", dir_ / "link.csv");
  fs::create_symlink("../link.csv", dir_ / "sub" / "chain.csv");  // a link to a link
  fs::create_directory_symlink(".", dir_ / "here");
  for (const std::string& out : std::vector<std::string>{
           "link.csv", "sub/chain.csv", "./sub/../data.csv", "here/data.csv", path("data.csv")}) {
    const ShellRun r = sh("exec " + kTsm + " simulate --params paper data.csv --output " + out);
    EXPECT_EQ(r.code, 2) << out << "\n" << r.output;
    EXPECT_TRUE(has(r.output, "is the same file as the input data.csv")) << r.output;
    EXPECT_EQ(slurp(data), before) << out;
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir_ / "link.csv")));
  }
  // Input through the link, output by its real name.
  const ShellRun r = sh("exec " + kTsm + " simulate --params paper link.csv --output data.csv");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_EQ(slurp(data), before);
}

TEST_F(HostileFiles, FitsModelFileTheKeyAndTheReportFolderCountAsInputs) {
  data_csv(2.0);
  write(dir_ / "start.yaml",
        "model: tsm\ncore: {theta: 15.5, gamma: 9.5, n: 2, sigma: 1}\n"
        "terms: {coulomb: {rho1: 1.0}}\n");
  const std::string start = slurp(dir_ / "start.yaml");
  ShellRun r = sh("exec " + kTsm + " fit data.csv --model start.yaml --output start.yaml");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "is the same file as --model start.yaml")) << r.output;
  EXPECT_EQ(slurp(dir_ / "start.yaml"), start);

  // The report folder replaces files in it: an input inside it is refused.
  fs::create_directories(dir_ / "rep");
  data_csv(2.0, "rep/report.json");
  const std::string in_rep = slurp(dir_ / "rep/report.json");
  r = sh("exec " + kTsm + " fit rep/report.json --output p.yaml --report rep");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "lies in this folder")) << r.output;
  EXPECT_EQ(slurp(dir_ / "rep/report.json"), in_rep);

  // The link key (found through TSMH_LINK_KEY) is never an output.
  const fs::path k = key();
  r = sh("TSMH_LINK_KEY=" + q(k.string()) + " exec " + kTsm +
         " simulate --params paper data.csv --output link.key");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "is the same file as the link key")) << r.output;
  EXPECT_EQ(slurp(k), std::string(64, 'a') + "\n");
}

TEST_F(HostileFiles, ServerTraceNeverReplacesItsKeyConfigParamsOrReport) {
  const fs::path k = key();
  write(dir_ / "p.yaml",
        "model: tsm\ncore: {theta: 15.5, gamma: 9.5, n: 2, sigma: 1}\n"
        "terms: {coulomb: {rho1: 1.0}}\n");
  const fs::path cfg = server_config("{params: p.yaml, max_torque_nm: 0.3}");
  const std::string cfg_text = slurp(cfg);
  const std::string params_text = slurp(dir_ / "p.yaml");
  fs::create_symlink("server.yaml", dir_ / "cfg-link.yaml");
  struct Case {
    std::string args;
    std::string says;
  };
  for (const Case& c : std::vector<Case>{
           {"--key link.key --trace link.key",
            "--trace link.key: is the same file as the link key"},
           {"--key link.key --trace server.yaml", "is the same file as the configuration"},
           {"--key link.key --report cfg-link.yaml", "is the same file as the configuration"},
           {"--key link.key --trace p.yaml", "is the same file as the params of joint"},
           {"--key link.key --trace out.csv --report out.csv",
            "--report out.csv: is the same file as --trace out.csv"},
           {"--key link.key --trace out.csv --report ./out.csv", "is the same file as --trace"}}) {
    const ShellRun r = sh(server(cfg, "--duration 0.3 " + c.args), 20);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.output;
    EXPECT_TRUE(has(r.output, c.says)) << c.args << "\n" << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "out.csv")) << c.args;
  }
  EXPECT_EQ(slurp(k), std::string(64, 'a') + "\n");
  EXPECT_EQ(fs::status(k).permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write);
  EXPECT_EQ(slurp(cfg), cfg_text);
  EXPECT_EQ(slurp(dir_ / "p.yaml"), params_text);
}

TEST_F(HostileFiles, VirtualSlaveOutputOverTheKeyIsRefused) {
  const fs::path k = key();
  const ShellRun r = sh("TSMH_LINK_KEY=" + q(k.string()) + " exec " + kSlave +
                        " --offline --scenario sine --duration 1 --output link.key");
  EXPECT_NE(r.code, 0) << r.output;
  EXPECT_TRUE(has(r.output, "--output link.key: is the same file as the link key")) << r.output;
  EXPECT_EQ(slurp(k), std::string(64, 'a') + "\n");
}

// --- a file-size limit ---------------------------------------------------

// `bash -c 'ulimit -f 50; ...'`: 50 blocks of 1024 bytes. Before: tsm and
// virtual-slave died of SIGXFSZ (exit 153, no message) and left *.tmp-PID.
TEST_F(HostileFiles, AFileSizeLimitIsAClearErrorAndLeavesNothingBehind) {
  data_csv(8.0);
  write(dir_ / "out.csv", "old\n");
  ShellRun r =
      sh("ulimit -f 50; exec " + kTsm + " simulate --params paper data.csv --output out.csv");
  EXPECT_EQ(r.signal, 0) << r.output;
  EXPECT_GE(r.code, 1) << r.output;
  EXPECT_LE(r.code, 127) << r.output;
  EXPECT_TRUE(has(r.output, "file size limit reached writing out.csv")) << r.output;
  EXPECT_EQ(slurp(dir_ / "out.csv"), "old\n") << "the old output was lost";
  expect_no_temporaries();

  r = sh("ulimit -f 50; exec " + kTsm + " fit data.csv --output p.yaml --report rep --starts 1",
         300);
  EXPECT_EQ(r.signal, 0) << r.output;
  EXPECT_GE(r.code, 1) << r.output;
  EXPECT_LE(r.code, 127) << r.output;
  EXPECT_TRUE(has(r.output, "file size limit reached writing")) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "rep"));
  EXPECT_FALSE(fs::exists(dir_ / "p.yaml"));
  expect_no_temporaries();

  write(dir_ / "slave.csv", "old\n");
  r = sh("ulimit -f 50; exec " + kSlave +
         " --offline --scenario sine --duration 5 --output slave.csv");
  EXPECT_EQ(r.signal, 0) << r.output;
  EXPECT_GE(r.code, 1) << r.output;
  EXPECT_LE(r.code, 127) << r.output;
  EXPECT_TRUE(has(r.output, "file size limit reached writing slave.csv")) << r.output;
  EXPECT_EQ(slurp(dir_ / "slave.csv"), "old\n");
  expect_no_temporaries();
}

// haptic-server spools its trace while it runs: the limit ends the session
// through the zero-torque path and says what happened.
TEST_F(HostileFiles, AFileSizeLimitStopsTheServerWithAClearError) {
  const fs::path cfg = server_config();
  const ShellRun r = sh("ulimit -f 50; " + server(cfg, "--duration 2 --trace trace.csv"), 60);
  EXPECT_EQ(r.signal, 0) << r.output;
  EXPECT_GE(r.code, 1) << r.output;
  EXPECT_LE(r.code, 127) << r.output;
  EXPECT_TRUE(has(r.output, "file size limit reached writing the trace's spool file")) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "trace.csv"));
  expect_no_temporaries();
}

// --- duplicate keys -------------------------------------------------------

TEST_F(HostileFiles, DuplicateKeysAreErrorsInEveryYaml) {
  data_csv(1.0);
  write(dir_ / "dup.yaml",
        "model: tsm\ncore: {theta: 15.5, theta: 99, gamma: 9.5, n: 2, sigma: 1}\n"
        "terms: {coulomb: {rho1: 1.0}}\n");
  ShellRun r = sh("exec " + kTsm + " simulate --params dup.yaml data.csv --output out.csv");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "dup.yaml: core.theta: duplicate key (line 2; first at line 2)"))
      << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));

  // The server's per-joint params.
  const fs::path cfg = server_config("{params: dup.yaml, max_torque_nm: 0.3}");
  r = sh(server(cfg, "--duration 0.3"), 20);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "core.theta: duplicate key")) << r.output;

  // tsm-devices settings, and a device profile file.
  write(dir_ / "settings.yaml", "scenario: sine\nscenario: step\n");
  r = sh("exec " + kDevices + " --monitor sim --seconds 0.2 --config settings.yaml", 20);
  EXPECT_NE(r.code, 0) << r.output;
  EXPECT_TRUE(has(r.output, "settings.yaml: scenario: duplicate key (line 2; first at line 1)"))
      << r.output;
  write(dir_ / "console.yaml", "name: x\nname: y\n");
  write(dir_ / "settings.yaml", "profile: console.yaml\n");
  r = sh("exec " + kDevices + " --monitor hid --seconds 0.2 --config settings.yaml", 20);
  EXPECT_NE(r.code, 0) << r.output;
  EXPECT_TRUE(has(r.output, "console.yaml: name: duplicate key (line 2; first at line 1)"))
      << r.output;
}

// --- reads that block or grow --------------------------------------------

TEST_F(HostileFiles, FifosAndDevicesWhereAFileIsExpectedAreRefusedAtOnce) {
  data_csv(1.0);
  ASSERT_EQ(::mkfifo(path("fifo").c_str(), 0600), 0);
  struct Case {
    std::string script;
    std::string says;
  };
  const fs::path fifo_params =
      server_config("{params: fifo, max_torque_nm: 0.3}", "fifo-params.yaml");
  const fs::path zero_params =
      server_config("{params: /dev/zero, max_torque_nm: 0.3}", "zero-params.yaml");
  const std::vector<Case> cases{
      {"exec " + kTsm + " simulate --params fifo data.csv --output out.csv",
       "fifo: is a FIFO (named pipe), not a regular file"},
      {"exec " + kTsm + " simulate --params paper fifo --output out.csv",
       "fifo: is a FIFO (named pipe), not a regular file"},
      {"exec " + kTsm + " simulate --params /dev/zero data.csv --output out.csv",
       "/dev/zero: is a character device, not a regular file"},
      {"exec " + kTsm + " fit /dev/zero --output p.yaml", "/dev/zero: is a character device"},
      {server(fifo_params, "--duration 0.3"), "is a FIFO (named pipe)"},
      {server(zero_params, "--duration 0.3"), "/dev/zero: is a character device"},
      {"exec " + kServer + " --config fifo --duration 0.3", "is a FIFO (named pipe)"},
      {server(server_config(), "--key fifo --duration 0.3"), "fifo is not a regular file"},
      {"exec " + kDevices + " --monitor sim --seconds 0.2 --config fifo", "is a FIFO"},
  };
  for (const Case& c : cases) {
    const ShellRun r = sh(c.script, 8.0);
    EXPECT_FALSE(r.timed_out) << c.script << ": blocked (killed after 8 s)\n" << r.output;
    EXPECT_LT(r.seconds, 5.0) << c.script;
    EXPECT_NE(r.code, 0) << c.script << "\n" << r.output;
    EXPECT_TRUE(has(r.output, c.says)) << c.script << "\n" << r.output;
    EXPECT_LT(r.max_rss_kb, 200 * 1024) << c.script << ": read without a bound";
  }
}

TEST_F(HostileFiles, ReadsAreBoundedWhileStreaming) {
  // A one-line CSV of 512 MB (sparse: no disk used): refused after its
  // first MiB, not after reading it all (before: 2.1 GB for 1 GB).
  { std::ofstream(dir_ / "huge.csv") << "t,x_in\n0,"; }
  fs::resize_file(dir_ / "huge.csv", std::uintmax_t{512} << 20);
  ShellRun r = sh("exec " + kTsm + " simulate --params paper huge.csv --output out.csv", 60);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "huge.csv:2: line is longer than 1048576 bytes")) << r.output;
  EXPECT_LT(r.max_rss_kb, 100 * 1024) << "peak " << r.max_rss_kb << " kB";

  // A params file and a link key of 8 MB: over their bounds, said so.
  write(dir_ / "big.yaml", "model: tsm\n# " + std::string(8 << 20, 'x') + "\n");
  r = sh("exec " + kTsm + " simulate --params big.yaml huge.csv --output out.csv");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "big.yaml: is " + std::to_string(fs::file_size(dir_ / "big.yaml")) +
                                " bytes, larger than 1 MiB"))
      << r.output;
  write(dir_ / "big.key", std::string(8 << 20, 'a'));
  fs::permissions(dir_ / "big.key", fs::perms::owner_read | fs::perms::owner_write);
  r = sh(server(server_config(), "--key big.key --duration 0.3"), 20);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "big.key: is 8388608 bytes, larger than 4096 bytes")) << r.output;
}

// --- absurd numbers, a byte-order mark -----------------------------------

TEST_F(HostileFiles, AbsurdRadiusHeadersAreRefusedWithTheFieldAndRange) {
  const fs::path data = data_csv(2.0);
  std::string text = slurp(data);
  const auto at = text.find("# radius_m: ");
  ASSERT_NE(at, std::string::npos);
  for (const std::string& radius :
       std::vector<std::string>{"1e308", "inf", "nan", "0", "-0.01", "1e-300"}) {
    std::string bad = text;
    bad.replace(at, text.find('\n', at) - at, "# radius_m: " + radius);
    write(dir_ / "bad.csv", bad);
    for (const std::string& cmd :
         std::vector<std::string>{"simulate --params paper bad.csv --output out.csv",
                                  "fit bad.csv --output p.yaml --starts 1"}) {
      const ShellRun r = sh("exec " + kTsm + " " + cmd, 120);
      EXPECT_EQ(r.code, 2) << radius << ": " << cmd << "\n" << r.output;
      EXPECT_TRUE(has(r.output, "column 'radius_m'") && has(r.output, "[0.0001, 1]"))
          << radius << ": " << r.output;
      EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
    }
  }
  const ShellRun r =
      sh("exec " + kTsm + " simulate --params paper data.csv --radius 1e308 --output out.csv");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "--radius: a pulley radius in m within [0.0001, 1]")) << r.output;
}

TEST_F(HostileFiles, NonFiniteAndHugeDurationsAreRefused) {
  const fs::path cfg = server_config();
  for (const std::string& d : std::vector<std::string>{"nan", "inf", "1e10", "-1"}) {
    ShellRun r = sh(server(cfg, "--duration " + d), 10);
    EXPECT_FALSE(r.timed_out) << d << ": ran on";
    EXPECT_EQ(r.code, 2) << d << "\n" << r.output;
    EXPECT_TRUE(has(r.output, "--duration") && has(r.output, "[0, 1e+07] s")) << r.output;
    r = sh("exec " + kSlave + " --offline --scenario sine --output o.csv --duration " + d, 10);
    EXPECT_FALSE(r.timed_out) << d;
    EXPECT_NE(r.code, 0) << d << "\n" << r.output;
    EXPECT_TRUE(has(r.output, "[0, 1e+07] s")) << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "o.csv"));
  }
  const ShellRun r = sh(server(cfg, "--duration 0.2 --rate nan"), 10);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "[1, 4000] Hz")) << r.output;
}

TEST_F(HostileFiles, AByteOrderMarkIsSkippedWithANote) {
  const fs::path data = data_csv(2.0);
  write(dir_ / "bom.csv", "\xEF\xBB\xBF" + slurp(data));
  const ShellRun r = sh("exec " + kTsm + " simulate --params paper bom.csv --output out.csv");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(has(r.output, "note: bom.csv: skipped the UTF-8 byte-order mark")) << r.output;
  EXPECT_TRUE(has(slurp(dir_ / "out.csv"), "t,F,tau_out_est"));
}

}  // namespace
}  // namespace tsmh::files::test
