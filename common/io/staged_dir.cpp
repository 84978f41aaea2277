#include "io/staged_dir.h"

#include "io/safe_path.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <csignal>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <unistd.h>

namespace fs = std::filesystem;

namespace penumbra::io {

StagedDirectory::StagedDirectory(const std::string& target, const std::string& marker) {
  // "out/" and "out" name the same directory; without the trailing separator the staging
  // directory lands beside it, not inside it.
  if (target.empty()) throw std::runtime_error("output directory: expected a path, got ''");
  target_ = fs::path(target).lexically_normal();
  if (!target_.has_filename() && target_.has_parent_path()) target_ = target_.parent_path();
  check_output(target, OutputKind::directory, marker);
  remove_abandoned_partials(target_);
  staging_ = target_.string() + ".partial-" + std::to_string(::getpid());
  std::error_code ec;
  fs::remove_all(staging_, ec);
  fs::create_directory(staging_, ec);
  if (ec) throw std::runtime_error(target + ": cannot create the output directory: " + ec.message());
}

StagedDirectory::~StagedDirectory() {
  std::error_code ec;
  if (!committed_) fs::remove_all(staging_, ec);
}

void StagedDirectory::commit() {
  std::error_code ec;
  auto fail = [&](const std::error_code& error) {
    throw std::runtime_error(target_.string() + ": cannot move the new output in place: " + error.message());
  };
  if (!fs::exists(fs::symlink_status(target_, ec))) {
    fs::rename(staging_, target_, ec);
    if (ec) fail(ec);
    committed_ = true;
    return;
  }
  // Swap the new output in and the old one out in one step: at every instant a reader (or a kill)
  // finds either the old or the new output in full. The old one then sits at the staging path.
  if (::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, target_.c_str(), RENAME_EXCHANGE) == 0) {
    committed_ = true;
    fs::remove_all(staging_, ec);
    return;
  }
  if (errno != EINVAL && errno != ENOSYS)
    throw std::runtime_error(target_.string() + ": cannot replace the previous output: " + std::strerror(errno));
  // A file system without the exchange: move the old output aside, the new one in, then delete the
  // old (a kill in between leaves the old output whole at <target>.old-<pid>).
  const fs::path old = target_.string() + ".old-" + std::to_string(::getpid());
  fs::remove_all(old, ec);
  fs::rename(target_, old, ec);
  if (ec) fail(ec);
  fs::rename(staging_, target_, ec);
  if (ec) {
    std::error_code back;
    fs::rename(old, target_, back);
    fail(ec);
  }
  committed_ = true;
  fs::remove_all(old, ec);
}

}  // namespace penumbra::io
