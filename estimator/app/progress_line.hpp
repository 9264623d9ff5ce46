#pragma once
// A progress line on stderr for long-running subcommands (fit, gap): redrawn
// in place on a terminal, and printed as occasional plain lines when stderr
// is a file or pipe, so logs stay readable.

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace tsmh::tsm_cli {

class ProgressLine {
 public:
  explicit ProgressLine(std::string prefix, double log_interval_s = 2.0)
      : prefix_(std::move(prefix)),
        tty_(::isatty(STDERR_FILENO) == 1),
        log_interval_s_(log_interval_s) {}
  ~ProgressLine() { finish(); }
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  void update(const std::string& text) {
    const auto now = std::chrono::steady_clock::now();
    if (tty_) {
      std::fprintf(stderr, "\r\033[K%s: %s", prefix_.c_str(), text.c_str());
      std::fflush(stderr);
      open_ = true;
    } else if (std::chrono::duration<double>(now - last_).count() >= log_interval_s_) {
      std::fprintf(stderr, "%s: %s\n", prefix_.c_str(), text.c_str());
      last_ = now;
    }
  }

  /// Ends the line (a newline on a terminal) before other output.
  void finish() {
    if (open_) std::fputc('\n', stderr);
    open_ = false;
  }

 private:
  std::string prefix_;
  bool tty_;
  double log_interval_s_;
  bool open_ = false;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace tsmh::tsm_cli
