#pragma once
// One rule for the outputs of every tsm command, checked before any work
// starts (docs/data-formats.md, "Outputs"):
//  - a file (--output of fit, simulate, convert): its folder must exist; the
//    path must not be a folder. The file itself is created or replaced.
//  - a folder (fit --report, gap --output): it may not exist yet, but then
//    its parent must: tsm creates at most the last component, never a whole
//    path; an existing path that is not a folder is an error.
//  - no output is one of the run's inputs (DATA, the params or starting
//    model file, the link key) or another of its outputs, compared as files
//    (device and inode, through links: files/distinct_outputs.hpp).
// A mistyped path fails at once, not after a long fit, and never leaves a
// tree of folders behind or destroys an input.

#include <initializer_list>
#include <stdexcept>
#include <string>
#include <vector>

#include "files/distinct_outputs.hpp"
#include "lcm_log_source.hpp"

namespace tsmh::tsm_cli {

/// A command line that cannot run (an output that is missing its folder or
/// would destroy an input): tsm exits 2, as for bad data, before any work.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class OutputKind { kFile, kFolder };

struct Output {
  const char* option;  ///< e.g. "--output"
  const std::string& path;
  OutputKind kind;
};

/// Throws UsageError naming the option, the path and what is wrong.
/// Empty paths (an option not given) are skipped.
void check_outputs(std::initializer_list<Output> outputs,
                   const std::vector<files::NamedInput>& inputs = {});

/// A model option's file (--params, --model, --base), or nothing for a preset.
files::NamedInput model_input(const char* option, const std::string& preset_or_path);
/// The link key an LCM log would be verified with (--key, else the search of
/// docs/bridge.md), or nothing.
files::NamedInput key_input(const LcmLogSelection& sel);

}  // namespace tsmh::tsm_cli
