#pragma once
// Paths named by data we do not control: the files of a session directory (a shared drive or a
// participant's machine may hand us one), the logs a fit reads, and every program's output (-o).
// A symbolic link among them is refused, never followed: a link named session.lock or trials.csv
// made a resume truncate or append to whatever file it pointed at. And one rule for every
// program's output path, the strictest any of them had. Each refusal is one line naming the path.
#include <sys/types.h>

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace penumbra::io {

enum class Links { follow, refuse };

// Throws std::runtime_error "<path>: is a symbolic link; refusing to follow it (<why>)" when
// `path` is one (lstat).
void refuse_link(const std::filesystem::path& path, std::string_view why = "give the file itself");

// open(2) with O_NOFOLLOW | O_CLOEXEC added: a link is refused as refuse_link says, any other
// failure is "<path>: cannot open <what>: <strerror>". Returns the descriptor.
int open_no_follow(const std::filesystem::path& path, int flags, mode_t mode, std::string_view what);

// The bytes of a regular file, at most `max_bytes` ("<path>: larger than N bytes"; "<path>: cannot
// read: no such file" / "not a regular file", a device such as /dev/null included). With
// Links::refuse a symbolic link is refused instead of followed.
std::string read_file(const std::filesystem::path& path, std::size_t max_bytes, Links links = Links::follow);

// The one rule for an output path (-o), checked before any work:
//  - it is not a symbolic link;
//  - its folder exists and is a folder: an output creates itself, never missing folders above it
//    (`-o a/b/c/ref.json` created /a when run as root);
//  - an existing directory output is empty or a previous output of the same kind (it holds
//    `marker`; with no marker only an empty one); an existing file output is a regular file.
// Throws std::runtime_error naming the path and what to do.
enum class OutputKind { directory, file };
void check_output(const std::filesystem::path& target, OutputKind kind, std::string_view marker = "");

// Removes `.<name>.partial-<pid>` files (write_file_atomic's temporaries) and `<name>.partial-<pid>`
// directories (StagedDirectory's) beside `target` whose process no longer exists: what a kill left.
void remove_abandoned_partials(const std::filesystem::path& target);

}  // namespace penumbra::io
