// tsm-link keygen / fingerprint, and `tsm keygen`, its alias: real processes
// writing real key files.

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "bridge/link_auth.hpp"
#include "process.hpp"

namespace tsmh::bridge {
namespace {

namespace fs = std::filesystem;

struct ScratchDir {
  fs::path path;
  ScratchDir() {
    char tmpl[] = "/tmp/tsm_link_XXXXXX";
    path = mkdtemp(tmpl);
  }
  ~ScratchDir() { fs::remove_all(path); }
};

/// A key file's one line, with its newline.
std::string text_of(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  return in ? line + "\n" : line;
}

TEST(TsmLink, KeygenWritesAPrivateKeyOfHexDigits) {
  ScratchDir dir;
  const fs::path key = dir.path / "sub" / "link.key";
  const auto r = test::run({TSMH_TSM_LINK_BIN, "keygen", "--output", key.string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.rfind(key.string() + "\n", 0), 0u) << r.output;  // the file, first
  struct stat st {};
  ASSERT_EQ(stat(key.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  const std::string text = text_of(key);
  EXPECT_EQ(text.size(), 65u);
  const LinkKey loaded = LinkKey::load(key);
  // Its report names the fingerprint peers compare.
  EXPECT_NE(r.output.find("fingerprint " + loaded.fingerprint()), std::string::npos) << r.output;
}

TEST(TsmLink, KeygenKeepsAnExistingKeyUnlessForced) {
  ScratchDir dir;
  const fs::path key = dir.path / "link.key";
  ASSERT_EQ(test::run({TSMH_TSM_LINK_BIN, "keygen", "--output", key.string()}).exit_code, 0);
  const std::string first = text_of(key);
  const auto again = test::run({TSMH_TSM_LINK_BIN, "keygen", "--output", key.string()});
  EXPECT_NE(again.exit_code, 0) << again.output;
  EXPECT_EQ(text_of(key), first);
  ASSERT_EQ(test::run({TSMH_TSM_LINK_BIN, "keygen", "--output", key.string(), "--force"}).exit_code,
            0);
  EXPECT_NE(text_of(key), first);
}

TEST(TsmLink, FingerprintNamesTheKeyAndItsFile) {
  ScratchDir dir;
  const fs::path key = dir.path / "link.key";
  LinkKey::generate().save(key);
  const auto r = test::run({TSMH_TSM_LINK_BIN, "fingerprint", "--key", key.string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, LinkKey::load(key).fingerprint() + "  " + key.string() + "\n");
}

TEST(TsmLink, FingerprintFollowsTheProgramsSearchAndSaysHowToMakeAKey) {
  ScratchDir dir;
  // No --key, no $TSMH_LINK_KEY, an empty home: no key anywhere.
  const auto none = test::run({"env", "-u", "TSMH_LINK_KEY", "-u", "XDG_CONFIG_HOME",
                               "HOME=" + dir.path.string(), TSMH_TSM_LINK_BIN, "fingerprint"});
  EXPECT_EQ(none.exit_code, 1) << none.output;
  EXPECT_NE(none.output.find("tsm-link keygen"), std::string::npos) << none.output;
  // The user's default place, where keygen writes without --output.
  const auto made = test::run({"env", "-u", "TSMH_LINK_KEY", "-u", "XDG_CONFIG_HOME",
                               "HOME=" + dir.path.string(), TSMH_TSM_LINK_BIN, "keygen"});
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const fs::path key = dir.path / ".config" / "tsmh" / "link.key";
  const auto found = test::run({"env", "-u", "TSMH_LINK_KEY", "-u", "XDG_CONFIG_HOME",
                                "HOME=" + dir.path.string(), TSMH_TSM_LINK_BIN, "fingerprint"});
  ASSERT_EQ(found.exit_code, 0) << found.output;
  EXPECT_EQ(found.output, LinkKey::load(key).fingerprint() + "  " + key.string() + "\n");
}

#ifdef TSMH_TSM_BIN
TEST(TsmLink, TsmKeygenIsAnAliasOfTheSameCommand) {
  ScratchDir dir;
  const fs::path key = dir.path / "link.key";
  const auto r = test::run({TSMH_TSM_BIN, "keygen", "--output", key.string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NO_THROW(LinkKey::load(key));
  // The same options and help, word for word, but for the program's name.
  auto help_of = [](const std::string& bin) {
    std::string help = test::run({bin, "keygen", "--help"}).output;
    const auto at = help.find(bin);
    if (at != std::string::npos) help.erase(at, bin.size());
    return help;
  };
  const std::string tsm_help = help_of(TSMH_TSM_BIN);
  EXPECT_NE(tsm_help.find("--force"), std::string::npos) << tsm_help;
  EXPECT_EQ(tsm_help, help_of(TSMH_TSM_LINK_BIN));
}
#endif

}  // namespace
}  // namespace tsmh::bridge
