#pragma once
// Reading a file the user named, so that no read can hang or exhaust memory:
//  - opening never blocks: O_NONBLOCK, then fstat(); anything but a regular
//    file (a FIFO, a device such as /dev/zero, a directory, a socket) is
//    refused at once with an error naming what it is. A FIFO opened without
//    O_NONBLOCK blocked start-up in open() where no stop signal reached it.
//  - every read has a size bound, checked while reading (a file may grow
//    after fstat()): configuration, parameter and key files are small; a
//    recording is large but not unbounded (docs/data-formats.md "Size
//    limits").
//
// Errors are FileError with "PATH: what is wrong"; callers add what the file
// was for ("link key", "params") and turn it into their own error type.

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace tsmh::files {

/// "WHERE: WHY"; why() alone for callers that name the file their own way.
class FileError : public std::runtime_error {
 public:
  FileError(const std::string& where, const std::string& why)
      : std::runtime_error(where + ": " + why), why_(why) {}
  const std::string& why() const { return why_; }

 private:
  std::string why_;
};

/// YAML configuration, device profiles, friction-model params: a few kB in
/// practice; 1 MiB leaves a wide margin and bounds what yaml-cpp builds.
inline constexpr std::uint64_t kMaxConfigBytes = std::uint64_t{1} << 20;
/// The link key: 64 hex digits and a newline.
inline constexpr std::uint64_t kMaxKeyBytes = 4096;
/// A recording (CSV data contract): 4 GiB, about 8 hours of one joint at
/// 1 kHz with every optional column. Counted while streaming.
inline constexpr std::uint64_t kMaxRecordingBytes = std::uint64_t{4} << 30;

/// "4 GiB", "1 MiB", "4096 bytes": a bound for messages.
std::string size_text(std::uint64_t bytes);

/// "a FIFO (named pipe)", "a character device", "a directory", ...
std::string kind_of(mode_t mode);

/// A regular file open for reading (the descriptor is closed on destruction).
class InputFile {
 public:
  /// Opens without blocking and checks it is a regular file no larger than
  /// `max_bytes`. Throws FileError "PATH: ...".
  InputFile(const std::filesystem::path& path, std::uint64_t max_bytes);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  /// Up to `n` bytes into `buf`; 0 at the end. Throws FileError when the
  /// file has grown past the bound while being read, or on a read error.
  std::size_t read_some(char* buf, std::size_t n);
  /// The rest of the file (bounded as above).
  std::string read_all();

  const std::filesystem::path& path() const { return path_; }
  std::uint64_t max_bytes() const { return max_bytes_; }

 private:
  std::filesystem::path path_;
  std::uint64_t max_bytes_;
  std::uint64_t read_ = 0;
  int fd_ = -1;
};

/// The whole of a small file: InputFile(path, max_bytes).read_all().
std::string read_file(const std::filesystem::path& path, std::uint64_t max_bytes);

}  // namespace tsmh::files
