// Malformed LCM logs: an event length of 0x7fffffff (liblcm's reader dies
// with SIGSEGV), a log cut off mid-event (which must not convert silently to
// half its rows), corrupt regions; the reader must say what is wrong, where,
// and how many events were lost, and never crash. The same logs seed the
// libFuzzer target (bridge/fuzz/fuzz_log_reader.cpp); here they are replayed
// and mutated at random under GCC, so every build checks them.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <lcm/lcm-cpp.hpp>
#include <random>
#include <string>
#include <vector>

#include "bridge/codec.hpp"
#include "bridge/log_events.hpp"
#include "bridge/log_reader.hpp"
#include "process.hpp"
#include "test_support.hpp"

namespace tsmh::bridge {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

fs::path temp_dir() {
  const fs::path dir = fs::temp_directory_path() / test::cat("tsmh_logev_", test::unique_prefix());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

Bytes read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const fs::path& p, const Bytes& b) {
  std::ofstream(p, std::ios::binary)
      .write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

// A valid log written by liblcm: `n` SLAVE_STATE + SLAVE_TRUTH pairs.
Bytes valid_log(int n = 40) {
  const fs::path dir = temp_dir();
  const fs::path p = dir / "valid.lcmlog";
  {
    lcm::LogFile out(p.string(), "w");
    Bytes bytes;
    for (int i = 0; i < n; ++i) {
      encode_sample(test::make_state(i, 1'000'000 + i * 1000), bytes);
      lcm::LogEvent ev{};
      ev.timestamp = 1'700'000'000'000'000 + i * 1000;
      ev.channel = "SLAVE_STATE";
      ev.datalen = static_cast<std::int32_t>(bytes.size());
      ev.data = bytes.data();
      out.writeEvent(&ev);
      encode_sample(test::make_truth(i, 1'000'000 + i * 1000), bytes);
      ev.channel = "SLAVE_TRUTH";
      ev.datalen = static_cast<std::int32_t>(bytes.size());
      ev.data = bytes.data();
      out.writeEvent(&ev);
    }
  }
  Bytes b = read_bytes(p);
  fs::remove_all(dir);
  return b;
}

// Offsets of every event in a valid log.
std::vector<std::size_t> event_offsets(const Bytes& b) {
  std::vector<std::size_t> out;
  LogEventReader r(b);
  for (LogEvent ev; r.next(ev);)
    out.push_back(ev.offset);
  return out;
}

void put_be32(Bytes& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i)
    b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (24 - 8 * i));
}

// The malformed logs above, also the fuzzer's seeds.
struct Seed {
  std::string name;
  Bytes bytes;
};
std::vector<Seed> seeds() {
  const Bytes ok = valid_log();
  const auto at = event_offsets(ok);
  std::vector<Seed> s;
  s.push_back({"valid", ok});
  Bytes huge = ok;
  put_be32(huge, at[10] + 24, 0x7fffffff);  // data length of event 10
  s.push_back({"datalen_0x7fffffff", huge});
  Bytes huge_last = ok;
  put_be32(huge_last, at.back() + 24, 0x7fffffff);
  s.push_back({"datalen_0x7fffffff_last", huge_last});
  Bytes neg = ok;
  put_be32(neg, at[5] + 20, 0xffffffff);  // channel length -1
  s.push_back({"chanlen_negative", neg});
  s.push_back({"cut_mid_event", Bytes(ok.begin(), ok.begin() + static_cast<long>(at[41] + 60))});
  s.push_back({"cut_mid_header", Bytes(ok.begin(), ok.begin() + static_cast<long>(at[41] + 9))});
  Bytes sync = ok;
  sync[at[20]] ^= 0xff;  // a broken sync word mid-file
  s.push_back({"bad_sync", sync});
  s.push_back({"sync_only", Bytes(ok.begin(), ok.begin() + 4)});
  return s;
}

JointSeries read(const Bytes& b, bool accept = false) {
  return read_joint_series(b, "test.lcmlog", 0, "", {.accept_damage = accept});
}

std::string error_of(const Bytes& b) {
  try {
    read(b);
  } catch (const LogError& e) {
    return e.what();
  }
  return "";
}

TEST(LogEvents, ValidLogReadsEveryEventWithoutDamage) {
  const JointSeries js = read(valid_log());
  EXPECT_EQ(js.rows(), 40U);
  EXPECT_FALSE(js.damage.any());
}

// Was SIGSEGV inside liblcm's reader.
TEST(LogEvents, HugeDataLengthIsNamedNotFollowed) {
  const auto s = seeds();
  const std::string e = error_of(s[1].bytes);
  EXPECT_NE(e.find("data length 2147483647 outside 0.."), std::string::npos) << e;
  EXPECT_NE(e.find("--accept-truncated"), std::string::npos) << e;
  const JointSeries js = read(s[1].bytes, true);
  EXPECT_EQ(js.damage.corrupt_regions, 1U);
  EXPECT_EQ(js.damage.events_lost, 1);
  EXPECT_EQ(js.rows(), 39U) << "the SLAVE_STATE of event 10 is lost, its truth has no match";
  // At the end of the file the same header reads as a truncation.
  const std::string last = error_of(s[2].bytes);
  EXPECT_NE(last.find("the file ends inside the event"), std::string::npos) << last;
}

// Was: converted silently to the rows before the cut, rc 0.
TEST(LogEvents, TruncatedLogIsAnErrorUnlessAcceptedThenSaysWhatWasLost) {
  const auto s = seeds();
  for (const Seed& cut : {s[4], s[5]}) {
    SCOPED_TRACE(cut.name);
    const std::string e = error_of(cut.bytes);
    EXPECT_NE(e.find("test.lcmlog: the file ends inside the event at byte"), std::string::npos)
        << e;
    EXPECT_NE(e.find("1 event(s) lost"), std::string::npos) << e;
    const JointSeries js = read(cut.bytes, true);
    EXPECT_TRUE(js.damage.truncated);
    EXPECT_EQ(js.damage.events_lost, 1);
    EXPECT_EQ(js.rows(), 20U) << "events 0..40 intact: 20 state/truth pairs + one state alone";
  }
}

TEST(LogEvents, CorruptRegionsAreSkippedAndCountedByEventNumber) {
  const auto s = seeds();
  for (const Seed& bad : {s[3], s[6]}) {
    SCOPED_TRACE(bad.name);
    EXPECT_NE(error_of(bad.bytes).find("1 corrupt region(s)"), std::string::npos)
        << error_of(bad.bytes);
    const JointSeries js = read(bad.bytes, true);
    EXPECT_EQ(js.damage.events_lost, 1);
    EXPECT_EQ(js.rows(), 39U);
  }
}

// Corpus replay and random mutation: any bytes give rows or a LogError,
// never a crash (under GCC; libFuzzer with ASan/UBSan goes further, see
// bridge/fuzz/). Bounded: 3000 mutants of a 13 kB log.
TEST(LogEvents, RandomMutationsNeverCrash) {
  const auto corpus = seeds();
  if (const char* out = std::getenv("TSMH_WRITE_FUZZ_SEEDS")) {
    fs::create_directories(out);
    for (const Seed& s : corpus)
      write_bytes(fs::path(out) / (s.name + ".lcmlog"), s.bytes);
  }
  std::mt19937_64 rng(15);
  std::size_t rows = 0, errors = 0;
  for (int i = 0; i < 3000; ++i) {
    Bytes b = corpus[rng() % corpus.size()].bytes;
    const int edits = 1 + static_cast<int>(rng() % 8);
    for (int k = 0; k < edits && !b.empty(); ++k) {
      const std::size_t at = rng() % b.size();
      switch (rng() % 5) {
        case 0:
          b[at] ^= static_cast<std::uint8_t>(1U << (rng() % 8));
          break;
        case 1:
          b[at] = static_cast<std::uint8_t>(rng());
          break;
        case 2:
          if (at + 4 <= b.size()) put_be32(b, at, (rng() % 2) ? 0x7fffffff : 0x80000000);
          break;
        case 3:
          b.resize(at);
          break;
        case 4:
          b.insert(b.begin() + static_cast<long>(at), static_cast<std::uint8_t>(rng()));
          break;
      }
    }
    try {
      rows += read(b, rng() % 2 == 0).rows();
    } catch (const LogError&) {
      ++errors;
    }
  }
  EXPECT_GT(rows, 0U);
  EXPECT_GT(errors, 0U);
}

#ifdef TSMH_TSM_BIN
// The command line: `tsm convert` refuses the damaged logs with an error and a
// message (no signal), and converts them with --accept-truncated.
TEST(LogEvents, TsmConvertRefusesDamagedLogsAndAcceptsThemByFlag) {
  const fs::path dir = temp_dir();
  for (const Seed& s : seeds()) {
    if (s.name == "valid" || s.name == "sync_only") continue;
    SCOPED_TRACE(s.name);
    const fs::path log = dir / (s.name + ".lcmlog");
    const fs::path csv = dir / (s.name + ".csv");
    write_bytes(log, s.bytes);
    auto r = test::run({TSMH_TSM_BIN, "convert", log.string(), "--output", csv.string()});
    EXPECT_GT(r.exit_code, 0) << "an error exit, not a signal: " << r.output;
    EXPECT_NE(r.output.find("event(s) lost"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(csv));
    r = test::run(
        {TSMH_TSM_BIN, "convert", log.string(), "--output", csv.string(), "--accept-truncated"});
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("warning"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("event(s) lost"), std::string::npos) << r.output;
  }
  fs::remove_all(dir);
}
#endif

}  // namespace
}  // namespace tsmh::bridge
