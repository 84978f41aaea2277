#pragma once
// What the penumbra-fit command-line tests share: a fresh scratch folder per test and a run of
// the tool as a user types it (PENUMBRA_FIT_EXE, defined by the test's target), stdout and stderr
// together.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

namespace penumbra::test {

// An empty folder in the temporary directory, `prefix` + `name` + this process's id.
inline std::filesystem::path fresh_dir(const std::string& prefix, const std::string& name) {
  const std::filesystem::path d = std::filesystem::temp_directory_path() / (prefix + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

// `penumbra-fit ARGS 2>&1` through the shell; its exit status (-1: no normal exit) and, when
// `output` is given, what it printed.
inline int run_fit(const std::string& args, std::string* output) {
  const std::string command = std::string(PENUMBRA_FIT_EXE) + " " + args + " 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  std::string out;
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) out.append(buf, n);
  const int status = ::pclose(pipe);
  if (output) *output = out;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace penumbra::test
