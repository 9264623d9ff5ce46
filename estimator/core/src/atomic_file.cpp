#include "estimator/atomic_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include "files/file_size_limit.hpp"
#include "files/link_target.hpp"

namespace tsmh::estimator {
namespace {

namespace fs = std::filesystem;

std::string errno_text() {
  return errno != 0 ? std::string(" (") + std::strerror(errno) + ")" : std::string();
}

// A failed write: under a file-size limit (ulimit -f) say so plainly, naming
// the file the user asked for (not the temporary one).
[[noreturn]] void write_failed(const fs::path& path, const fs::path& written) {
  const int err = errno;
  std::error_code ec;
  const auto size = fs::file_size(written, ec);
  if (files::hit_file_size_limit(err, ec ? 0 : size))
    throw std::runtime_error(files::file_size_limit_message(path.string()));
  errno = err;
  throw std::runtime_error(path.string() + ": write failed" + errno_text());
}

}  // namespace

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write) {
  // A symbolic link stays a link: its target is what gets written (atomically,
  // beside the target), never the link replaced by a regular file.
  fs::path target;
  try {
    target = files::final_link_target(path);
  } catch (const files::FileError& e) {
    throw std::runtime_error(e.what());
  }
  std::error_code ec;
  const fs::file_status st = fs::status(target, ec);
  if (fs::is_directory(st)) throw std::runtime_error(path.string() + ": is a directory");
  if (fs::exists(st) && !fs::is_regular_file(st)) {
    // A device (/dev/null, /dev/full), a FIFO or a socket: written through,
    // never renamed over (that replaced /dev/null with a regular file). Not
    // atomic -- there is nothing to be atomic about -- but every error counts.
    errno = 0;
    std::ofstream out(target, std::ios::out | std::ios::binary);
    if (!out) throw std::runtime_error(path.string() + ": cannot open for writing" + errno_text());
    write(out);
    out.flush();
    if (!out) write_failed(path, target);
    return;
  }
  const fs::path tmp = target.string() + ".tmp-" + std::to_string(static_cast<long>(::getpid()));
  try {
    errno = 0;
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw std::runtime_error(path.string() + ": cannot open for writing" + errno_text());
    write(out);
    out.flush();
    if (!out) write_failed(path, tmp);
    out.close();
    if (!out) write_failed(path, tmp);
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw std::runtime_error(path.string() +
                             ": cannot move the finished file into place: " + ec.message());
  }
}

void write_text_atomically(const std::filesystem::path& path, const std::string& text) {
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace tsmh::estimator
