#pragma once
// What the penumbra-fit command-line tests share: a fresh scratch folder per test (tool_run.h's
// fresh_dir) and a run of the tool as a user types it (PENUMBRA_FIT_EXE, defined by the test's
// target), stdout and stderr together.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "../study/tool_run.h"  // fresh_dir

namespace penumbra::test {

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
