#include "io/atomic_file.h"

#include "io/safe_path.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace penumbra::io {

int write_all(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    if (n == 0) return ENOSPC;
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
  return 0;
}

void write_file_atomic(const std::filesystem::path& path, std::string_view bytes) {
  // The rename would replace anything: never a directory, a device (-o /dev/null as root), a fifo
  // or a symbolic link (it would be replaced by a file, not written through; said, not done).
  struct stat existing {};
  if (::lstat(path.c_str(), &existing) == 0 && S_ISLNK(existing.st_mode)) refuse_link(path);
  if (::stat(path.c_str(), &existing) == 0 && !S_ISREG(existing.st_mode))
    throw std::runtime_error(path.string() + ": cannot write: exists and is not a regular file");
  remove_abandoned_partials(path);  // the temporary of a run killed while it wrote this file
  const std::filesystem::path tmp =
      path.parent_path() / ("." + path.filename().string() + ".partial-" + std::to_string(::getpid()));
  auto fail = [&](int error, const char* step) {
    ::unlink(tmp.c_str());
    throw std::runtime_error(path.string() + ": cannot write" + step + ": " + std::strerror(error));
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int error = errno;
    throw std::runtime_error(path.string() + ": cannot write: " + std::strerror(error));
  }
  int error = write_all(fd, bytes);
  if (error == 0 && ::fsync(fd) != 0) error = errno;
  if (::close(fd) != 0 && error == 0) error = errno;
  if (error != 0) fail(error, "");
  if (::rename(tmp.c_str(), path.c_str()) != 0) fail(errno, " (rename)");
}

}  // namespace penumbra::io
