#pragma once
// What the command-line tests of the study's tools (and penumbra-fit's, tests/analysis/fit_exe.h) share: a fresh scratch folder per test, a
// file's bytes, and a run of a tool as a user types it in a folder, stdout and stderr apart.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace penumbra::test {

// An empty folder in the temporary directory, `prefix` + `name` + this process's id.
inline std::filesystem::path fresh_dir(const std::string& prefix, const std::string& name) {
  const std::filesystem::path d = std::filesystem::temp_directory_path() / (prefix + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

inline std::string bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A tool's exit status (-1: no normal exit), stdout and stderr.
struct Ran {
  int status = -1;
  std::string out, err;
};

// `exe args` through the shell in `dir` (relative paths in `args` are the folder's), stdout and
// stderr through dir/stdout.txt and dir/stderr.txt.
inline Ran run_in(const std::filesystem::path& dir, const std::string& exe, const std::string& args) {
  const std::string command = "cd '" + dir.string() + "' && '" + exe + "' " + args + " > stdout.txt 2> stderr.txt";
  const int raw = std::system(command.c_str());
  Ran ran;
  ran.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  ran.out = bytes(dir / "stdout.txt");
  ran.err = bytes(dir / "stderr.txt");
  return ran;
}

}  // namespace penumbra::test
