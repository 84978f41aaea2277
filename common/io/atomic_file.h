#pragma once
// A file that appears whole or not at all: written under a temporary name in the same folder with
// write(2) (short writes continued, EINTR retried), fsync()ed, then renamed over `path`. A failure
// (a full disk, a file-size limit) removes the temporary, leaves a previous `path` untouched and
// throws std::runtime_error "<path>: cannot write: <strerror of that call>". An existing `path`
// that is not a regular file (a directory, a device, a symbolic link) is refused, not replaced. The
// temporaries of runs killed while writing `path` (their process gone) are removed first.
#include <filesystem>
#include <string_view>

namespace penumbra::io {

void write_file_atomic(const std::filesystem::path& path, std::string_view bytes);

// write(2) of all of `bytes` to `fd`: continues short writes, retries EINTR. Returns 0, or the
// errno of the failing call (ENOSPC for a write that made no progress without one).
int write_all(int fd, std::string_view bytes);

}  // namespace penumbra::io
