#pragma once
// The file a path finally names: itself, or what its chain of symbolic links
// points to (relative links resolve against their own folder). A dangling
// link resolves to the file it would name. The atomic writer writes there
// (so a link stays a link), and the distinct-outputs check compares there.

#include <filesystem>

#include "files/input_file.hpp"  // FileError

namespace tsmh::files {

/// Throws FileError after 40 levels of links (a loop).
std::filesystem::path final_link_target(const std::filesystem::path& path);

}  // namespace tsmh::files
