// Where tsm-devices finds device profiles: $TSMH_PROFILES_DIR, else relative
// to the binary's bin/ folder (installed tree or build tree).

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>

#include "master_devices/profile.hpp"
#include "master_devices/profile_dirs.hpp"

namespace md = tsmh::master_devices;

TEST(ProfileDirs, EnvironmentOverrides) {
  EXPECT_EQ(md::profiles_dir_for("/opt/profiles", "/usr/bin/tsm-devices"),
            std::filesystem::path("/opt/profiles"));
}

TEST(ProfileDirs, EmptyEnvironmentIsUnset) {
  EXPECT_EQ(md::profiles_dir_for("", "/usr/bin/tsm-devices"),
            std::filesystem::path("/usr/share/tsm-haptics/profiles"));
}

TEST(ProfileDirs, RelativeToTheBinFolderOfAnyPrefix) {
  EXPECT_EQ(md::profiles_dir_for(nullptr, "/usr/local/bin/tsm-devices"),
            std::filesystem::path("/usr/local/share/tsm-haptics/profiles"));
  EXPECT_EQ(md::profiles_dir_for(nullptr, "/tmp/x/bin/tsm-devices"),
            std::filesystem::path("/tmp/x/share/tsm-haptics/profiles"));
}

TEST(ProfileDirs, BuildTreeHasTheShippedProfiles) {
  // This test binary sits in build/bin/, the profiles are mirrored to
  // build/share/tsm-haptics/profiles.
  const char* saved = getenv(md::kProfilesDirEnv);
  const std::string saved_value = saved != nullptr ? saved : "";
  unsetenv(md::kProfilesDirEnv);
  const std::filesystem::path dir = md::default_profiles_dir();
  if (saved != nullptr) setenv(md::kProfilesDirEnv, saved_value.c_str(), 1);
  ASSERT_TRUE(std::filesystem::is_directory(dir)) << dir;
  const auto profiles = md::load_profiles(dir);
  ASSERT_FALSE(profiles.empty());
  EXPECT_TRUE(std::filesystem::exists(dir / "tsm-console-2dof.yaml"));
}
