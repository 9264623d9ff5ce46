#pragma once
// One rule for the outputs of every tsm command, checked before any work
// starts (docs/data-formats.md, "Outputs"):
//  - a file (--output of fit, simulate, convert): its folder must exist; the
//    path must not be a folder. The file itself is created or replaced.
//  - a folder (fit --report, gap --output): it may not exist yet, but then
//    its parent must: tsm creates at most the last component, never a whole
//    path; an existing path that is not a folder is an error.
// A mistyped path fails at once, not after a long fit, and never leaves a
// tree of folders behind.

#include <initializer_list>
#include <string>

namespace tsmh::tsm_cli {

enum class OutputKind { kFile, kFolder };

struct Output {
  const char* option;  ///< e.g. "--output"
  const std::string& path;
  OutputKind kind;
};

/// Throws std::runtime_error naming the option, the path and what is wrong.
/// Empty paths (an option not given) are skipped.
void check_outputs(std::initializer_list<Output> outputs);

}  // namespace tsmh::tsm_cli
