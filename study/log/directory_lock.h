#pragma once
// A directory owned by one process: an advisory flock() on DIR/session.lock, taken before anything
// in the directory is read or written and held for the owner's lifetime (the kernel drops it when
// the process dies, so a crash never leaves a stale lock). The file keeps the holder's pid so a
// refused second process can name it, is never opened through a symbolic link (a link there made
// a resume truncate the file it pointed at), and is removed when the lock is released: a refused
// run leaves no session.lock behind.
#include <filesystem>
#include <string>

namespace penumbra::trial_log {

class DirectoryLock {
 public:
  DirectoryLock() = default;
  // Locks `dir` (which must exist). Throws std::runtime_error
  // "<dir>: in use by another process (pid N); refusing to touch it" when another holds it.
  explicit DirectoryLock(const std::filesystem::path& dir);
  ~DirectoryLock();
  DirectoryLock(DirectoryLock&& other) noexcept;
  DirectoryLock& operator=(DirectoryLock&& other) noexcept;
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;

  bool held() const { return fd_ >= 0; }
  static constexpr const char* kFileName = "session.lock";

 private:
  void release();
  int fd_ = -1;
  std::filesystem::path path_;
};

}  // namespace penumbra::trial_log
