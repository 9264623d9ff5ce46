#pragma once
// One line of haptic-server's log on stderr, "haptic-server: <text>",
// written by the main thread only (never the loop). The event log and the
// recalibration log both write through it.

#include <cstdarg>
#include <cstdio>

namespace tsmh::haptic_server {

/// Writes "haptic-server: " and `fmt` formatted with `ap`, then a newline.
/// `wipe_live`: the live status line is on the terminal; wipe it first so the
/// two do not mix.
__attribute__((format(printf, 2, 0))) inline void vsay(bool wipe_live, const char* fmt,
                                                       va_list ap) {
  if (wipe_live) std::fputs("\r\033[K", stderr);
  std::fputs("haptic-server: ", stderr);
  std::vfprintf(stderr, fmt, ap);
  std::fputc('\n', stderr);
}

}  // namespace tsmh::haptic_server
