#include "estimator/staged_output.hpp"

#include <unistd.h>

#include <stdexcept>
#include <system_error>

namespace tsmh::estimator {

namespace fs = std::filesystem;

StagedDirectory::StagedDirectory(fs::path target) : target_(std::move(target)) {
  if (target_.empty()) throw std::runtime_error("output directory: empty path");
  if (fs::exists(target_) && !fs::is_directory(target_))
    throw std::runtime_error(target_.string() + ": exists and is not a directory");
  fs::path clean = target_.lexically_normal();
  if (clean.filename().empty()) clean = clean.parent_path();
  staging_ = clean;
  staging_ += ".tmp-" + std::to_string(static_cast<long>(::getpid()));
  std::error_code ec;
  fs::remove_all(staging_, ec);
  if (!fs::create_directories(staging_, ec) || ec)
    throw std::runtime_error(staging_.string() + ": cannot create a staging directory (" +
                             ec.message() + ")");
}

StagedDirectory::~StagedDirectory() {
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

std::vector<fs::path> StagedDirectory::commit() {
  std::error_code ec;
  if (!fs::exists(target_)) {
    fs::create_directories(target_, ec);
    if (ec) throw std::runtime_error(target_.string() + ": cannot create (" + ec.message() + ")");
    target_created_ = true;
  }
  for (const auto& entry : fs::directory_iterator(staging_)) {
    const fs::path dest = target_ / entry.path().filename();
    fs::rename(entry.path(), dest, ec);
    if (ec) {
      roll_back();
      throw std::runtime_error(dest.string() + ": cannot move into place (" + ec.message() + ")");
    }
    committed_.push_back(dest);
  }
  done_ = true;
  fs::remove_all(staging_, ec);
  return committed_;
}

void StagedDirectory::roll_back() noexcept {
  std::error_code ec;
  for (const auto& p : committed_)
    fs::remove(p, ec);
  committed_.clear();
  if (target_created_) fs::remove(target_, ec);
}

}  // namespace tsmh::estimator
