#include "output_checks.hpp"

#include <filesystem>
#include <stdexcept>

namespace tsmh::tsm_cli {

namespace fs = std::filesystem;

void check_outputs(std::initializer_list<Output> outputs) {
  for (const Output& o : outputs) {
    if (o.path.empty()) continue;
    const auto fail = [&](const std::string& why) {
      throw std::runtime_error(std::string(o.option) + " " + o.path + ": " + why);
    };
    fs::path p = fs::path(o.path).lexically_normal();
    if (p.filename().empty()) p = p.parent_path();  // "dir/" names dir
    std::error_code ec;
    const fs::file_status st = fs::status(p, ec);  // follows links
    const bool exists = fs::exists(st);
    if (o.kind == OutputKind::kFile && exists && fs::is_directory(st))
      fail("is a folder; name a file to write");
    if (o.kind == OutputKind::kFolder && exists && !fs::is_directory(st))
      fail("exists and is not a folder");
    if (exists) continue;
    const fs::path parent = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    if (!fs::is_directory(parent, ec))
      fail("the folder '" + parent.string() + "' does not exist (" +
           (o.kind == OutputKind::kFile
                ? std::string("outputs are written into existing folders")
                : std::string("tsm creates only the last folder of an output path, never a "
                              "whole path")) +
           "; create it first)");
  }
}

}  // namespace tsmh::tsm_cli
