#pragma once
// An output directory that appears whole or not at all (and named by io::check_output's rule: not a
// link, in a folder that exists, new, empty or a previous output): files are written under
// `DIR.partial-<pid>` and swapped with DIR by commit() in one renameat2(RENAME_EXCHANGE), so at
// every instant DIR holds the old or the new output in full; without commit() the staging
// directory is removed, so a failure leaves a previous DIR untouched and nothing half-written. Staging
// directories of killed runs (their process gone) are removed by the next run to the same DIR.
#include <filesystem>
#include <string>

namespace penumbra::io {

class StagedDirectory {
 public:
  // Throws std::runtime_error when `target` breaks io::check_output's rule: a link, a folder that
  // does not exist, or an existing directory that is neither empty nor a previous output of the
  // same kind (holding `marker`, e.g. "report.json").
  StagedDirectory(const std::string& target, const std::string& marker);
  ~StagedDirectory();
  StagedDirectory(const StagedDirectory&) = delete;
  StagedDirectory& operator=(const StagedDirectory&) = delete;

  const std::filesystem::path& path() const { return staging_; }  // write here
  const std::filesystem::path& target() const { return target_; }
  void commit();  // replaces the target with the staging directory

 private:
  std::filesystem::path target_;
  std::filesystem::path staging_;
  bool committed_ = false;
};

}  // namespace penumbra::io
