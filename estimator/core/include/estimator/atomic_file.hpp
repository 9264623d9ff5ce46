#pragma once
// Writing a result file so that it is either complete or absent: the content
// goes to a temporary file beside the target, which is renamed into place
// only after a successful flush. Readers never see half a file, and a failed
// run leaves no output behind.
//
// Not regular files: a path that is a device (/dev/null,
// /dev/full), a FIFO or a socket is written through, never renamed over; a
// symbolic link is followed and its target written atomically beside the
// target, so the link stays a link (a dangling link's target is created).
//
// Public API of estimator::core: haptics writes its trace and evaluation
// report with it (it links estimator::core for the estimator anyway), so no
// output of the project is ever half written (docs/architecture.md
// "Defined once").

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

namespace tsmh::estimator {

/// Calls `write` with a stream to a temporary file, then renames it to
/// `path`. Throws std::runtime_error naming the path on any failure (and
/// removes the temporary file).
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write);

/// Convenience for ready text.
void write_text_atomically(const std::filesystem::path& path, const std::string& text);

}  // namespace tsmh::estimator
