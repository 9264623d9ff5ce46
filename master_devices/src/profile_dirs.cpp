#include "master_devices/profile_dirs.hpp"

#include <cstdlib>
#include <system_error>

// Set by master_devices/CMakeLists.txt from the install layout
// (cmake/TsmhInstallDirs.cmake); relative to the install prefix.
#ifndef TSMH_PROFILES_RELDIR
#define TSMH_PROFILES_RELDIR "share/tsm-haptics/profiles"
#endif
#ifndef TSMH_BINDIR
#define TSMH_BINDIR "bin"
#endif

namespace tsmh::master_devices {

std::filesystem::path profiles_dir_for(const char* env_value, const std::filesystem::path& exe) {
  if (env_value != nullptr && *env_value != '\0') return std::filesystem::path(env_value);
  const std::filesystem::path reldir(TSMH_PROFILES_RELDIR);
  if (reldir.is_absolute()) return reldir;
  // prefix = the executable's folder with one level removed per component of
  // the bin folder (bin -> one level).
  std::filesystem::path prefix = exe.parent_path();
  const std::filesystem::path bindir(TSMH_BINDIR);
  for (auto it = bindir.begin(); it != bindir.end(); ++it) {
    if (!it->empty() && *it != ".") prefix = prefix.parent_path();
  }
  return (prefix / reldir).lexically_normal();
}

std::filesystem::path current_executable() {
  std::error_code ec;
  std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  return exe;
}

std::filesystem::path default_profiles_dir() {
  return profiles_dir_for(std::getenv(kProfilesDirEnv), current_executable());
}

}  // namespace tsmh::master_devices
