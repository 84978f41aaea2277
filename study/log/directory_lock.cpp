#include "log/directory_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "io/safe_path.h"

namespace penumbra::trial_log {

DirectoryLock::DirectoryLock(const std::filesystem::path& dir) {
  path_ = dir / kFileName;
  // The lock file is removed when the lock is released (a refused run leaves nothing behind), so
  // a process may lock a file another has just unlinked: it then holds a lock nobody else sees.
  // Locking is therefore checked against the path: the locked file must still be the one there.
  for (int attempt = 0; attempt < 100; ++attempt) {
    fd_ = io::open_no_follow(path_, O_RDWR | O_CREAT, 0644, "the lock file");
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      char buf[32] = {};
      const ssize_t n = ::pread(fd_, buf, sizeof buf - 1, 0);
      ::close(fd_);
      fd_ = -1;
      if (error != EWOULDBLOCK) throw std::runtime_error(path_.string() + ": cannot lock: " + std::strerror(error));
      std::string pid(buf, n > 0 ? static_cast<std::size_t>(n) : 0);
      while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
      if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos) pid = "unknown";
      throw std::runtime_error(dir.string() + ": in use by another process (pid " + pid + "); refusing to touch it");
    }
    struct stat locked {}, named {};
    if (::fstat(fd_, &locked) == 0 && ::lstat(path_.c_str(), &named) == 0 && locked.st_dev == named.st_dev &&
        locked.st_ino == named.st_ino)
      break;
    ::close(fd_);  // unlinked by its last holder between our open and our lock: take the new one
    fd_ = -1;
  }
  if (fd_ < 0) throw std::runtime_error(path_.string() + ": cannot lock: the lock file keeps being replaced");
  const std::string pid = std::to_string(::getpid()) + "\n";
  // The pid is only a courtesy for the refusal message; the flock is the lock.
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size())) {
    // A full disk: the lock holds all the same, the message will say "pid unknown".
  }
}

void DirectoryLock::release() {
  if (fd_ < 0) return;
  ::unlink(path_.c_str());  // while still locked: no other process can hold this file now
  ::close(fd_);
  fd_ = -1;
}

DirectoryLock::~DirectoryLock() { release(); }

DirectoryLock::DirectoryLock(DirectoryLock&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), path_(std::move(other.path_)) {}

DirectoryLock& DirectoryLock::operator=(DirectoryLock&& other) noexcept {
  if (this != &other) {
    release();
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
  }
  return *this;
}

}  // namespace penumbra::trial_log
