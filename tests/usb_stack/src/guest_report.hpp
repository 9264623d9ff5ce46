#pragma once
// The line protocol between the guest programs and the host harness
// (scripts/qemu-usb-test): "RESULT <name> PASS|FAIL|SKIP <detail>" and
// "METRIC <name> <value> <unit>" on stdout, one line each, flushed at once so
// that lines from concurrent programs do not interleave mid-line.

#include <cstdio>
#include <string_view>

namespace tsmh::usb_stack {

enum class Verdict { kPass, kFail, kSkip };

inline const char* to_string(Verdict v) {
  switch (v) {
    case Verdict::kPass:
      return "PASS";
    case Verdict::kFail:
      return "FAIL";
    case Verdict::kSkip:
      return "SKIP";
  }
  return "FAIL";
}

inline void result(std::string_view name, Verdict v, std::string_view detail) {
  std::printf("RESULT %.*s %s %.*s\n", static_cast<int>(name.size()), name.data(), to_string(v),
              static_cast<int>(detail.size()), detail.data());
  std::fflush(stdout);
}

inline void result(std::string_view name, bool pass, std::string_view detail) {
  result(name, pass ? Verdict::kPass : Verdict::kFail, detail);
}

inline void metric(std::string_view name, double value, std::string_view unit) {
  std::printf("METRIC %.*s %.6g %.*s\n", static_cast<int>(name.size()), name.data(), value,
              static_cast<int>(unit.size()), unit.data());
  std::fflush(stdout);
}

}  // namespace tsmh::usb_stack
