#include "files/link_target.hpp"

#include <system_error>

#include "files/input_file.hpp"

namespace tsmh::files {

std::filesystem::path final_link_target(const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  fs::path p = path;
  for (int depth = 0; depth < 40; ++depth) {
    std::error_code ec;
    if (!fs::is_symlink(fs::symlink_status(p, ec))) return p;
    const fs::path target = fs::read_symlink(p, ec);
    if (ec) return p;
    p = target.is_absolute() ? target : p.parent_path() / target;
  }
  throw FileError(path.string(), "too many levels of symbolic links");
}

}  // namespace tsmh::files
