#include "output_checks.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "bridge/link_security.hpp"
#include "estimator/model_io.hpp"

namespace tsmh::tsm_cli {

namespace fs = std::filesystem;

files::NamedInput model_input(const char* option, const std::string& preset_or_path) {
  const auto presets = estimator::preset_names();
  if (std::find(presets.begin(), presets.end(), preset_or_path) != presets.end()) return {};
  return {option, preset_or_path};
}

files::NamedInput key_input(const LcmLogSelection& sel) {
  if (sel.skip_mac) return {};
  try {
    const auto file = bridge::find_key_file(sel.key_file, std::getenv(bridge::kLinkKeyEnv),
                                            std::getenv("XDG_CONFIG_HOME"), std::getenv("HOME"));
    if (file) return {"the link key", *file};
  } catch (const std::exception&) {
    // A key that cannot be found is reported when a log needs it.
  }
  return {};
}

void check_outputs(std::initializer_list<Output> outputs,
                   const std::vector<files::NamedInput>& inputs) {
  for (const Output& o : outputs) {
    if (o.path.empty()) continue;
    const auto fail = [&](const std::string& why) {
      throw UsageError(std::string(o.option) + " " + o.path + ": " + why);
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
  std::vector<files::NamedOutput> named;
  for (const Output& o : outputs)
    named.push_back({o.option, o.path, o.kind == OutputKind::kFolder});
  try {
    files::check_distinct_outputs(inputs, named);
  } catch (const files::FileError& e) {
    throw UsageError(e.what());
  }
}

}  // namespace tsmh::tsm_cli
