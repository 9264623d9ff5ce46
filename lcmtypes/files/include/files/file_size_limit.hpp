#pragma once
// A file-size limit (RLIMIT_FSIZE, `ulimit -f`) must end a write with a
// clear error, not with SIGXFSZ: by default the signal kills the process
// (exit 153, no message) and leaves its temporary files behind. Programs
// call ignore_file_size_signal() first thing in main(), so write() fails
// with EFBIG and the writer reports it and cleans up. (haptic-server blocks
// SIGXFSZ with its other stop signals instead, which also makes write()
// return EFBIG, and then stops the session through its zero-torque path.)

#include <cstdint>
#include <string>

namespace tsmh::files {

/// signal(SIGXFSZ, SIG_IGN).
void ignore_file_size_signal();

/// True when a write that failed with `err` having written `size` bytes of
/// the file hit the file-size limit (EFBIG, or the size reached the limit).
bool hit_file_size_limit(int err, std::uint64_t size);

/// "file size limit reached writing PATH (ulimit -f: N bytes)".
std::string file_size_limit_message(const std::string& path);

}  // namespace tsmh::files
