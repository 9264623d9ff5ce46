#include "files/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace tsmh::files {
namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& why) {
  throw FileError(path.string(), why);
}

std::string too_large(std::uint64_t max_bytes) {
  return "larger than " + size_text(max_bytes) + ", the limit for this file";
}

}  // namespace

std::string size_text(std::uint64_t bytes) {
  if (bytes >= (std::uint64_t{1} << 30) && bytes % (std::uint64_t{1} << 30) == 0)
    return std::to_string(bytes >> 30) + " GiB";
  if (bytes >= (std::uint64_t{1} << 20) && bytes % (std::uint64_t{1} << 20) == 0)
    return std::to_string(bytes >> 20) + " MiB";
  return std::to_string(bytes) + " bytes";
}

std::string kind_of(mode_t mode) {
  if (S_ISREG(mode)) return "a regular file";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

InputFile::InputFile(const std::filesystem::path& path, std::uint64_t max_bytes)
    : path_(path), max_bytes_(max_bytes) {
  // O_NONBLOCK: opening a FIFO for reading otherwise waits for a writer,
  // uninterruptibly as far as our blocked stop signals are concerned.
  fd_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd_ < 0) fail(path, std::string("cannot open for reading (") + std::strerror(errno) + ")");
  struct stat st {};
  if (::fstat(fd_, &st) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    fail(path, std::string("cannot stat (") + std::strerror(err) + ")");
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd_);
    fd_ = -1;
    fail(path, "is " + kind_of(st.st_mode) + ", not a regular file");
  }
  if (static_cast<std::uint64_t>(st.st_size) > max_bytes) {
    ::close(fd_);
    fd_ = -1;
    fail(path, "is " + std::to_string(st.st_size) + " bytes, " + too_large(max_bytes));
  }
  // A regular file: blocking reads are what we want from here on.
  const int flags = ::fcntl(fd_, F_GETFL);
  if (flags >= 0) ::fcntl(fd_, F_SETFL, flags & ~O_NONBLOCK);
}

InputFile::~InputFile() {
  if (fd_ >= 0) ::close(fd_);
}

std::size_t InputFile::read_some(char* buf, std::size_t n) {
  // One byte past the bound is read, so a file that grew is noticed.
  const std::uint64_t room = max_bytes_ + 1 - read_;
  if (n > room) n = static_cast<std::size_t>(room);
  ssize_t got = 0;
  do {
    got = ::read(fd_, buf, n);
  } while (got < 0 && errno == EINTR);
  if (got < 0) fail(path_, std::string("read error (") + std::strerror(errno) + ")");
  read_ += static_cast<std::uint64_t>(got);
  if (read_ > max_bytes_) fail(path_, too_large(max_bytes_));
  return static_cast<std::size_t>(got);
}

std::string InputFile::read_all() {
  std::string out;
  char buf[65536];
  while (const std::size_t n = read_some(buf, sizeof buf))
    out.append(buf, n);
  return out;
}

std::string read_file(const std::filesystem::path& path, std::uint64_t max_bytes) {
  return InputFile(path, max_bytes).read_all();
}

}  // namespace tsmh::files
