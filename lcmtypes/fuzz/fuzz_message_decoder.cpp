// libFuzzer target for one message decoder (TSMH_FUZZ_MESSAGE names the
// type, TSMH_FUZZ_HEADER its header; lcmtypes/CMakeLists.txt builds one per type). Beyond "no
// crash, no sanitizer report, no huge allocation" (run with -rss_limit_mb and -malloc_limit_mb),
// every input it accepts must be exactly a message: the joint count in range, every array that
// long, and re-encoding it gives the same bytes back.
//
//   build-fuzz/bin/fuzz_decode_master_state_t -max_total_time=60 -malloc_limit_mb=64 \
//       lcmtypes/fuzz/corpus/master_state_t

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "lcmtypes/message_decoder.hpp"
#include TSMH_FUZZ_HEADER  // "tsmh/<type>.hpp"

namespace {

using Message = tsmh::TSMH_FUZZ_MESSAGE;

// The bridge's range (1..kMaxJoints = 8); the lcm driver's exact counts are a
// sub-range of it.
tsmh::lcmtypes::MessageDecoder<Message>& decoder() {
  static tsmh::lcmtypes::MessageDecoder<Message> d({1, 8});
  return d;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto& d = decoder();
  const auto error = d.decode(data, size);
  if (error) {
    if (error->what[0] == '\0' ||
        std::memchr(error->what.data(), '\0', error->what.size()) == nullptr)
      std::abort();  // every refusal says why, NUL-terminated
    return 0;
  }
  const Message& m = d.message();
  if (m.num_joints < 1 || m.num_joints > 8 || static_cast<std::size_t>(m.getEncodedSize()) != size)
    std::abort();
  std::vector<std::uint8_t> again(size);
  if (m.encode(again.data(), 0, static_cast<int>(size)) != static_cast<int>(size) ||
      std::memcmp(again.data(), data, size) != 0)
    std::abort();  // accepted bytes that are not exactly this message
  return 0;
}
