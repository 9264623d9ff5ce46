#pragma once
// An output directory that appears complete or not at all: files are written
// into a staging directory beside the target and moved into it only by
// commit(), each with an atomic rename. A run that fails (an exception before
// commit) leaves nothing behind: the destructor removes the staging area.

#include <filesystem>
#include <string>
#include <vector>

namespace tsmh::estimator {

class StagedDirectory {
 public:
  /// Creates the staging directory (TARGET.tmp-PID beside TARGET). Throws
  /// std::runtime_error naming the path when it cannot.
  explicit StagedDirectory(std::filesystem::path target);
  ~StagedDirectory();
  StagedDirectory(const StagedDirectory&) = delete;
  StagedDirectory& operator=(const StagedDirectory&) = delete;

  /// Where to write files now (they keep their names in the target).
  const std::filesystem::path& staging() const { return staging_; }
  const std::filesystem::path& target() const { return target_; }
  std::filesystem::path file(const std::string& name) const { return staging_ / name; }

  /// Creates the target if needed and moves every staged file into it
  /// (replacing files of the same name). Returns the moved files' paths.
  std::vector<std::filesystem::path> commit();
  /// Removes files moved by commit() (for a failure after it).
  void roll_back() noexcept;

 private:
  std::filesystem::path target_;
  std::filesystem::path staging_;
  std::vector<std::filesystem::path> committed_;
  bool target_created_ = false;
  bool done_ = false;
};

}  // namespace tsmh::estimator
