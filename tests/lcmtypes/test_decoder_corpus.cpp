// Replays every file of the decoders' fuzzing corpus (lcmtypes/fuzz/corpus/
// <type>/, the seeds of the clang-only libFuzzer targets) through the same
// decoder in the GCC build: no crash, and each file gets the verdict its name
// states -- "valid-*" accepted and re-encoded to the same bytes, "<fault>-*"
// refused with that fault and a reason. Files without such a name (inputs a
// fuzzer found) must only decode without crashing, and round-trip if accepted.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <tsmh/calibration_request_t.hpp>
#include <tsmh/haptic_status_t.hpp>
#include <tsmh/master_command_t.hpp>
#include <tsmh/master_force_t.hpp>
#include <tsmh/master_state_t.hpp>
#include <tsmh/slave_state_t.hpp>
#include <tsmh/slave_truth_t.hpp>
#include <vector>

#include "lcmtypes/message_decoder.hpp"

namespace tsmh::lcmtypes {
namespace {

namespace fs = std::filesystem;

std::vector<std::uint8_t> read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// What the file name promises: "valid", a fault name, or "" (no promise).
std::string expectation(const std::string& name) {
  const auto dash = name.find('-');
  const std::string head = name.substr(0, dash);
  if (head == "valid") return head;
  for (auto f : {DecodeFault::kTruncatedHeader, DecodeFault::kTypeHash, DecodeFault::kJointCount,
                 DecodeFault::kSize, DecodeFault::kMalformed})
    if (head == fault_name(f)) return head;
  return "";
}

// Replays one type's folder; returns {files, accepted}.
template <class Message>
std::pair<int, int> replay(const fs::path& corpus) {
  const fs::path dir = corpus / Message::getTypeName();
  EXPECT_TRUE(fs::is_directory(dir)) << dir;
  MessageDecoder<Message> decoder({1, 8});  // the bridge's range, as the fuzzers use
  int files = 0, accepted = 0;
  std::map<std::string, int> by_expectation;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const std::string name = entry.path().filename().string();
    SCOPED_TRACE(entry.path().string());
    const auto bytes = read_file(entry.path());
    const auto error = decoder.decode(bytes.data(), bytes.size());
    const std::string expected = expectation(name);
    ++files;
    ++by_expectation[expected];
    if (!error) {
      ++accepted;
      EXPECT_TRUE(expected == "valid" || expected.empty()) << "accepted, but named " << expected;
      const Message& m = decoder.message();
      EXPECT_GE(m.num_joints, 1);
      EXPECT_LE(m.num_joints, 8);
      if (m.num_joints < 1 || m.num_joints > 8) continue;
      std::vector<std::uint8_t> again(static_cast<std::size_t>(m.getEncodedSize()));
      m.encode(again.data(), 0, static_cast<int>(again.size()));
      EXPECT_EQ(again, bytes) << "accepted bytes that are not exactly one message";
      continue;
    }
    EXPECT_NE(expected, "valid") << "refused: " << error->what.data();
    if (!expected.empty() && expected != "valid") {
      EXPECT_EQ(fault_name(error->fault), expected) << error->what.data();
    }
    EXPECT_GT(std::strlen(error->what.data()), 10u) << "a refusal says why";
    EXPECT_EQ(error->size, bytes.size());
  }
  // The seed corpus covers every verdict for every type.
  for (const char* e : {"valid", "truncated_header", "type_hash", "joint_count", "size"})
    EXPECT_GT(by_expectation[e], 0) << Message::getTypeName() << " has no " << e << " seed";
  return {files, accepted};
}

TEST(DecoderCorpus, EveryFileGetsTheVerdictItsNameStates) {
  const fs::path corpus = TSMH_DECODER_CORPUS;
  int files = 0;
  for (auto [f, a] : {replay<slave_state_t>(corpus), replay<slave_truth_t>(corpus),
                      replay<master_command_t>(corpus), replay<master_state_t>(corpus),
                      replay<master_force_t>(corpus), replay<haptic_status_t>(corpus),
                      replay<calibration_request_t>(corpus)}) {
    files += f;
    EXPECT_GE(a, 3) << "each type has three valid seeds";
  }
  EXPECT_GE(files, 7 * 19);
}

}  // namespace
}  // namespace tsmh::lcmtypes
