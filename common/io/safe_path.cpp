#include "io/safe_path.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>

namespace fs = std::filesystem;

namespace penumbra::io {

namespace {

[[noreturn]] void link_refused(const fs::path& path, std::string_view why) {
  throw std::runtime_error(path.string() + ": is a symbolic link; refusing to follow it (" + std::string(why) + ")");
}

}  // namespace

void refuse_link(const fs::path& path, std::string_view why) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode)) link_refused(path, why);
}

int open_no_follow(const fs::path& path, int flags, mode_t mode, std::string_view what) {
  const int fd = ::open(path.c_str(), flags | O_NOFOLLOW | O_CLOEXEC, mode);
  if (fd >= 0) return fd;
  const int error = errno;
  if (error == ELOOP) link_refused(path, "a session directory, a log or an output is never reached through a link");
  throw std::runtime_error(path.string() + ": cannot open " + std::string(what) + ": " + std::strerror(error));
}

std::string read_file(const fs::path& path, std::size_t max_bytes, Links links) {
  const std::string file = path.string();
  struct stat st {};
  const int looked = links == Links::refuse ? ::lstat(path.c_str(), &st) : ::stat(path.c_str(), &st);
  if (looked != 0) throw std::runtime_error(file + ": cannot read: " + (errno == ENOENT ? "no such file" : std::strerror(errno)));
  if (S_ISLNK(st.st_mode)) link_refused(path, "give the file itself");
  if (!S_ISREG(st.st_mode))
    throw std::runtime_error(file + ": cannot read: not a regular file" + (S_ISDIR(st.st_mode) ? " (a directory)" : ""));
  if (static_cast<std::size_t>(st.st_size) > max_bytes)
    throw std::runtime_error(file + ": larger than " + std::to_string(max_bytes) + " bytes (" + std::to_string(st.st_size) + ")");
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | (links == Links::refuse ? O_NOFOLLOW : 0));
  if (fd < 0) {
    if (errno == ELOOP) link_refused(path, "give the file itself");
    throw std::runtime_error(file + ": cannot read: " + std::strerror(errno));
  }
  std::string bytes;
  char buffer[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int error = errno;
      ::close(fd);
      throw std::runtime_error(file + ": cannot read: " + std::strerror(error));
    }
    if (n == 0) break;
    bytes.append(buffer, static_cast<std::size_t>(n));
    if (bytes.size() > max_bytes) {
      ::close(fd);
      throw std::runtime_error(file + ": larger than " + std::to_string(max_bytes) + " bytes");
    }
  }
  ::close(fd);
  return bytes;
}

void check_output(const fs::path& target_in, OutputKind kind, std::string_view marker) {
  if (target_in.empty()) throw std::runtime_error("output: expected a path, got ''");
  // "out/" and "out" name the same output.
  fs::path target = target_in.lexically_normal();
  if (!target.has_filename() && target.has_parent_path()) target = target.parent_path();
  const std::string name = target_in.string();
  refuse_link(target, "an output is written where it is named, not through a link");
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  const fs::file_status parent = fs::status(folder, ec);
  if (!fs::exists(parent))
    throw std::runtime_error(name + ": the folder " + folder.string() + " does not exist (create it first: an output never creates the folders above it)");
  if (!fs::is_directory(parent)) throw std::runtime_error(name + ": " + folder.string() + " is not a folder");
  const fs::file_status status = fs::symlink_status(target, ec);
  if (!fs::exists(status)) return;
  if (kind == OutputKind::file) {
    if (!fs::is_regular_file(status)) throw std::runtime_error(name + ": exists and is not a regular file");
    return;
  }
  if (!fs::is_directory(status)) throw std::runtime_error(name + ": exists and is not a directory");
  if (fs::is_empty(target, ec)) return;
  if (marker.empty())
    throw std::runtime_error(name + ": exists and is not empty; choose a new output directory");
  if (!fs::exists(fs::symlink_status(target / marker, ec)))
    throw std::runtime_error(name + ": exists and is not a previous output (no " + std::string(marker) +
                             "); choose another output directory");
}

void remove_abandoned_partials(const fs::path& target) {
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  const std::string name = target.filename().string();
  std::error_code ec;
  for (const std::string& prefix : {"." + name + ".partial-", name + ".partial-"}) {
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
      const std::string entry_name = entry.path().filename().string();
      if (entry_name.size() <= prefix.size() || entry_name.compare(0, prefix.size(), prefix) != 0) continue;
      const std::string_view digits = std::string_view(entry_name).substr(prefix.size());
      if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string_view::npos) continue;
      const pid_t pid = static_cast<pid_t>(std::stol(std::string(digits)));
      if (pid <= 0 || pid == ::getpid()) continue;
      if (::kill(pid, 0) != 0 && errno == ESRCH) fs::remove_all(entry.path(), ec);  // never follows a link: removes it
    }
  }
}

}  // namespace penumbra::io
