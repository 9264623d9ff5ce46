// libFuzzer target: the LCM log reader (our event-header validation, then
// SLAVE_STATE / SLAVE_TRUTH decoding and row building) must return rows or a
// LogError for any bytes, never crash, read out of bounds or trip UB. Seeds:
// the malformed logs of LogEvents (bridge/fuzz/corpus, written by
// TSMH_WRITE_FUZZ_SEEDS=bridge/fuzz/corpus build/bin/bridge_tests
// --gtest_filter=LogEvents.RandomMutationsNeverCrash).
//   CC=clang CXX=clang++ cmake -S . -B build-fuzz && cmake --build build-fuzz -t
//   fuzz_bridge_log_reader build-fuzz/bin/fuzz_bridge_log_reader -max_total_time=60
//   bridge/fuzz/corpus

#include <cstddef>
#include <cstdint>
#include <span>

#include "bridge/log_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  for (const bool accept : {false, true}) {
    try {
      const auto js =
          tsmh::bridge::read_joint_series(bytes, "fuzz", 0, "", {.accept_damage = accept});
      // Rows come out strictly increasing in time, as the CSV contract needs.
      for (std::size_t i = 1; i < js.t.size(); ++i)
        if (!(js.t[i] > js.t[i - 1])) __builtin_trap();
    } catch (const tsmh::bridge::LogError&) {
    }
  }
  return 0;
}
