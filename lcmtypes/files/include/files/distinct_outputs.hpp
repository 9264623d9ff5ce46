#pragma once
// One rule for every program that writes files: an output is never one of
// the run's inputs (recordings, params, its configuration, the link key) and
// never another output of the same run. Checked before any work, so a typo
// such as `--output run.lcmlog` on the recording itself, or `--trace
// link.key`, is an error and nothing is touched.
//
// Files are compared by what they are, not by how they are spelt: device and
// inode, through symbolic links (./a, a, ../dir/a and a link to a are one
// file). An output that does not exist yet is the pair (its folder's device
// and inode, its name), after following a dangling link the way the atomic
// writer does. A folder output (`tsm fit --report DIR`) replaces files in
// DIR, so an input lying in DIR is refused too.
//
// Outputs that are devices or FIFOs (/dev/null) are written through, never
// replaced, and may be shared by several outputs.

#include <filesystem>
#include <string>
#include <vector>

#include "files/input_file.hpp"  // FileError

namespace tsmh::files {

/// A file the run reads. `role` says what it is for messages: "the input",
/// "--params", "the link key", "the configuration".
struct NamedInput {
  std::string role;
  std::filesystem::path path;
};

/// A file (or folder) the run writes. `role` is its option: "--output",
/// "--trace", "evaluation.report".
struct NamedOutput {
  std::string role;
  std::filesystem::path path;
  bool folder = false;  ///< a folder whose files the run creates or replaces
};

/// Throws FileError "ROLE PATH: is the same file as ROLE' PATH' ...; choose
/// another name". Empty paths (an option not given) and inputs that do not
/// exist (reported by their readers) are skipped.
void check_distinct_outputs(const std::vector<NamedInput>& inputs,
                            const std::vector<NamedOutput>& outputs);

}  // namespace tsmh::files
