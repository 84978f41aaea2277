#pragma once
// Runs a plotting script with the user's Python (penumbra-demo, penumbra-bench).
#include <spawn.h>
#include <sys/stat.h>
#include <unistd.h>
#include <sys/wait.h>

#include <stdexcept>
#include <string>
#include <vector>

extern char** environ;

namespace penumbra::apps {

// Checks, before any work, that `python` can be started and `script` exists, so that a run of
// minutes does not end in "cannot be started". run_python_script starts it with posix_spawn,
// which does not search PATH: it must be a path to an executable file. Throws one line beginning with the option (exit 2: the command line must change).
inline void check_python(const std::string& python, const std::string& script, const std::string& what) {
  struct stat st {};
  if (python.empty() || ::stat(python.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || ::access(python.c_str(), X_OK) != 0)
    throw std::runtime_error("--python " + python + ": not an executable file (give its path, or --no-plot to skip " + what + ")");
  if (::stat(script.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
    throw std::runtime_error("--plot-script " + script + ": no such file (use --no-plot to skip " + what + ")");
}

// Runs `python script args...` and waits for it. Throws one line naming the interpreter (when it
// cannot be started) or the script and its exit status (when it fails), with the hint to pass
// --no-plot to skip `what` (e.g. "the chart").
inline void run_python_script(const std::string& python, const std::string& script, const std::vector<std::string>& args,
                              const std::string& what) {
  std::vector<std::string> all = {python, script};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, python.c_str(), nullptr, nullptr, argv.data(), environ) != 0)
    throw std::runtime_error("--python " + python + ": cannot be started (use --no-plot to skip " + what + ")");
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error(script + " failed (status " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                             "); use --no-plot to skip " + what);
}

}  // namespace penumbra::apps
