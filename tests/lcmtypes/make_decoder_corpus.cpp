// Writes the message decoders' seed corpus (lcmtypes/fuzz/corpus/<type>/):
// valid messages, hostile joint counts, truncations, trailing bytes and
// another type's message. Each file's name says what the decoder must do
// with it: "valid-*" is accepted, "<fault>-*" refused with that fault
// (lcmtypes::fault_name); tests/lcmtypes/test_decoder_corpus.cpp replays them.
// Not run by ctest: the corpus is committed, this program is how it was made.
//
//   build/bin/make_decoder_corpus lcmtypes/fuzz/corpus

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "corpus_messages.hpp"

namespace {

namespace fs = std::filesystem;
using tsmh::lcmtypes::test::Bytes;
using tsmh::lcmtypes::test::encoded;
using tsmh::lcmtypes::test::set_num_joints;

void write(const fs::path& dir, const std::string& name, const Bytes& b) {
  std::ofstream(dir / (name + ".bin"), std::ios::binary)
      .write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

template <class Message, class Other>
void make(const fs::path& root) {
  const fs::path dir = root / Message::getTypeName();
  fs::create_directories(dir);
  for (int n : {1, 2, 8})
    write(dir, "valid-" + std::to_string(n) + "-joints", encoded<Message>(n));

  const Bytes two = encoded<Message>(2);
  auto with_joints = [&](std::int32_t n) {
    Bytes b = two;
    set_num_joints(b, n);
    return b;
  };
  write(dir, "joint_count-2pow28-in-a-2-joint-body", with_joints(1 << 28));
  write(dir, "joint_count-int32-max", with_joints(0x7fffffff));
  write(dir, "joint_count-minus-1", with_joints(-1));
  write(dir, "joint_count-int32-min", with_joints(static_cast<std::int32_t>(0x80000000u)));
  write(dir, "joint_count-zero", with_joints(0));
  write(dir, "joint_count-9-full-size", encoded<Message>(9));

  write(dir, "truncated_header-empty", {});
  write(dir, "truncated_header-27-bytes", Bytes(two.begin(), two.begin() + 27));
  write(dir, "size-header-only", Bytes(two.begin(), two.begin() + 28));
  write(dir, "size-one-byte-short", Bytes(two.begin(), two.end() - 1));
  const auto cut = static_cast<std::ptrdiff_t>(std::min<std::size_t>(33, two.size() - 1));
  write(dir, "size-cut-5-bytes-after-the-header", Bytes(two.begin(), two.begin() + cut));
  Bytes longer = two;
  longer.push_back(0);
  write(dir, "size-one-trailing-byte", longer);
  write(dir, "size-claims-3-joints-has-2", with_joints(3));
  write(dir, "size-claims-1-joint-has-2", with_joints(1));

  write(dir, std::string("type_hash-a-") + Other::getTypeName(), encoded<Other>(2));
  Bytes flipped = two;
  flipped[7] ^= 0x01;
  write(dir, "type_hash-one-bit-flipped", flipped);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_decoder_corpus DIR\n");
    return 2;
  }
  const fs::path root = argv[1];
  make<tsmh::slave_state_t, tsmh::slave_truth_t>(root);
  make<tsmh::slave_truth_t, tsmh::master_command_t>(root);
  make<tsmh::master_command_t, tsmh::master_state_t>(root);
  make<tsmh::master_state_t, tsmh::master_force_t>(root);
  make<tsmh::master_force_t, tsmh::haptic_status_t>(root);
  make<tsmh::haptic_status_t, tsmh::calibration_request_t>(root);
  make<tsmh::calibration_request_t, tsmh::slave_state_t>(root);
  return 0;
}
