#include "files/file_size_limit.hpp"

#include <signal.h>
#include <sys/resource.h>

#include <cerrno>

namespace tsmh::files {

void ignore_file_size_signal() {
  ::signal(SIGXFSZ, SIG_IGN);
}

bool hit_file_size_limit(int err, std::uint64_t size) {
  if (err == EFBIG) return true;
  rlimit lim{};
  if (::getrlimit(RLIMIT_FSIZE, &lim) != 0 || lim.rlim_cur == RLIM_INFINITY) return false;
  return size >= static_cast<std::uint64_t>(lim.rlim_cur);
}

std::string file_size_limit_message(const std::string& path) {
  std::string text = "file size limit reached writing " + path;
  rlimit lim{};
  if (::getrlimit(RLIMIT_FSIZE, &lim) == 0 && lim.rlim_cur != RLIM_INFINITY)
    text += " (the limit, ulimit -f, is " + std::to_string(lim.rlim_cur) + " bytes)";
  return text;
}

}  // namespace tsmh::files
