#include "estimator/atomic_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace tsmh::estimator {
namespace {

namespace fs = std::filesystem;

std::string errno_text() {
  return errno != 0 ? std::string(" (") + std::strerror(errno) + ")" : std::string();
}

// The file a path finally names: itself, or what its chain of symbolic links
// points to (relative links resolve against their own folder). A dangling
// link resolves to the file it would name, which is then created.
fs::path resolve_links(const fs::path& path) {
  fs::path p = path;
  for (int depth = 0; depth < 40; ++depth) {
    std::error_code ec;
    if (!fs::is_symlink(fs::symlink_status(p, ec))) return p;
    const fs::path target = fs::read_symlink(p, ec);
    if (ec) return p;
    p = target.is_absolute() ? target : p.parent_path() / target;
  }
  throw std::runtime_error(path.string() + ": too many levels of symbolic links");
}

}  // namespace

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write) {
  // A symbolic link stays a link: its target is what gets written (atomically,
  // beside the target), never the link replaced by a regular file.
  const fs::path target = resolve_links(path);
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
    if (!out) throw std::runtime_error(path.string() + ": write failed" + errno_text());
    return;
  }
  const fs::path tmp = target.string() + ".tmp-" + std::to_string(static_cast<long>(::getpid()));
  try {
    errno = 0;
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw std::runtime_error(path.string() + ": cannot open for writing" + errno_text());
    write(out);
    out.flush();
    if (!out) throw std::runtime_error(path.string() + ": write failed" + errno_text());
    out.close();
    if (!out) throw std::runtime_error(path.string() + ": write failed" + errno_text());
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
