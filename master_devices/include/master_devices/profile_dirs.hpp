#pragma once
// Where the device profiles (*.yaml) are found without --profiles: never a
// path compiled in from the build machine's source tree, so the same binary
// works installed (any prefix) and in the build tree (docs/install.md).
//   1. $TSMH_PROFILES_DIR when set and not empty;
//   2. else <exe>/../share/tsm-haptics/profiles: relative to the running
//      binary's bin/ folder. `cmake --install` puts the profiles there, and
//      the build mirrors them to build/share/tsm-haptics/profiles next to
//      build/bin/.

#include <filesystem>

namespace tsmh::master_devices {

/// The environment variable that overrides the profile folder.
inline constexpr const char* kProfilesDirEnv = "TSMH_PROFILES_DIR";

/// The rule above for a given override value (nullptr or "" = unset) and
/// executable path. Pure: does not look at the file system.
std::filesystem::path profiles_dir_for(const char* env_value, const std::filesystem::path& exe);

/// The running program (/proc/self/exe); empty if it cannot be read.
std::filesystem::path current_executable();

/// profiles_dir_for(getenv(TSMH_PROFILES_DIR), current_executable()).
std::filesystem::path default_profiles_dir();

}  // namespace tsmh::master_devices
