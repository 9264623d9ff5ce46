#pragma once
// The test side of an authenticated link: the programs under test find the
// key through TSMH_LINK_KEY (set by ctest, tests/CMakeLists.txt); the test's
// own publishers sign with the same key, as a legitimate peer would.

#include <cstdlib>
#include <memory>

#include "bridge/link_auth.hpp"
#include "bridge/link_security.hpp"

namespace tsmh::haptics::test {

/// The key named by TSMH_LINK_KEY, or null when the variable is not set.
inline std::shared_ptr<const bridge::LinkKey> test_link_key() {
  const char* file = std::getenv(bridge::kLinkKeyEnv);
  if (file == nullptr || file[0] == '\0') return nullptr;
  return std::make_shared<const bridge::LinkKey>(bridge::LinkKey::load(file));
}

/// A signer with that key (null without one: messages go out unsigned).
inline std::unique_ptr<bridge::MessageSigner> test_signer() {
  auto key = test_link_key();
  return key ? std::make_unique<bridge::MessageSigner>(std::move(key)) : nullptr;
}

}  // namespace tsmh::haptics::test
