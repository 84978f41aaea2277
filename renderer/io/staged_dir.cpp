#include "io/staged_dir.h"

#include <stdexcept>
#include <system_error>
#include <unistd.h>

namespace fs = std::filesystem;

namespace penumbra::io {

StagedDirectory::StagedDirectory(const std::string& target, const std::string& marker) {
  // "out/" and "out" name the same directory; without the trailing separator the staging
  // directory lands beside it, not inside it.
  target_ = fs::path(target).lexically_normal();
  if (!target_.has_filename() && target_.has_parent_path()) target_ = target_.parent_path();
  if (fs::exists(target_) && (!fs::is_directory(target_) || (!fs::is_empty(target_) && !fs::exists(target_ / marker))))
    throw std::runtime_error(target + ": exists and is not a previous output (no " + marker + "); choose another output directory");
  staging_ = target_.string() + ".partial-" + std::to_string(::getpid());
  fs::remove_all(staging_);
  fs::create_directories(staging_);
}

StagedDirectory::~StagedDirectory() {
  std::error_code ec;
  if (!committed_) fs::remove_all(staging_, ec);
}

void StagedDirectory::commit() {
  if (fs::exists(target_)) fs::remove_all(target_);
  if (target_.has_parent_path()) fs::create_directories(target_.parent_path());
  fs::rename(staging_, target_);
  committed_ = true;
}

}  // namespace penumbra::io
