#pragma once
// For the tests that drive penumbra-study's windows under Xvfb: the app in the background with
// its stdout and stderr captured in a file, and xdotool input into a window found by its exact
// title.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

namespace penumbra::test {

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// `exe args...` in the background, its stdout and stderr in one file.
class App {
 public:
  App(const std::string& exe, const std::vector<std::string>& args)
      : capture_(std::filesystem::temp_directory_path() /
                 ("penumbra-app-capture-" + std::to_string(++count_) + "-" + std::to_string(::getpid()))) {
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = ::open(capture_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, 1);
      dup2(fd, 2);
      std::vector<char*> argv{const_cast<char*>(exe.c_str())};
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      execv(exe.c_str(), argv.data());
      _exit(127);
    }
  }
  App(const App&) = delete;
  App& operator=(const App&) = delete;
  ~App() {
    if (running()) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    std::filesystem::remove(capture_);
  }
  std::string output() const { return slurp(capture_); }
  // Stops and continues the app (SIGSTOP, SIGCONT): input sent in between waits in the X server's
  // queue and arrives in one glfwPollEvents, as it does when a loaded machine delays a frame.
  void pause() { kill(pid_, SIGSTOP); }
  void resume() { kill(pid_, SIGCONT); }
  bool running() {
    if (pid_ > 0 && waitpid(pid_, &status_, WNOHANG) == pid_) pid_ = -1;
    return pid_ > 0;
  }
  // Until the app printed one of `texts`: its index, or -1 when it exited first or after 20 s.
  int wait_for_any(const std::vector<std::string>& texts) {
    using namespace std::chrono_literals;
    for (auto end = std::chrono::steady_clock::now() + 20s; std::chrono::steady_clock::now() < end;) {
      const bool alive = running();
      const std::string out = output();
      for (std::size_t i = 0; i < texts.size(); ++i)
        if (out.find(texts[i]) != std::string::npos) return static_cast<int>(i);
      if (!alive) return -1;
      std::this_thread::sleep_for(15ms);
    }
    return -1;
  }
  bool wait_for(const std::string& text) { return wait_for_any({text}) == 0; }
  // The exit code, or -1 when it did not exit normally within `limit`.
  int wait_exit(std::chrono::seconds limit = std::chrono::seconds(20)) {
    using namespace std::chrono_literals;
    for (auto end = std::chrono::steady_clock::now() + limit; std::chrono::steady_clock::now() < end;) {
      if (!running()) return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1;
      std::this_thread::sleep_for(15ms);
    }
    return -1;
  }

 private:
  std::filesystem::path capture_;
  pid_t pid_ = -1;
  int status_ = 0;
  static inline int count_ = 0;
};

// xdotool with real XTEST input into `app`'s window titled exactly `title`: focuses it, then runs
// `args` ("key Return", "type P07", "mousemove X Y click 1"). xdotool stops a chain at its first
// failing step, so a chain that failed before its last step sent nothing: such a failure (seen
// on CI as `windowfocus --sync` failing while the window was up) is retried while the app still
// runs, up to three tries, each bounded to 10 s, with xdotool's own words on stderr. False when
// every try failed or the app exited. A key that closes the window can be delivered and still
// fail: xdotool then touches the destroyed window (seen: "BadWindow" on X_SendEvent after the
// Escape that declined consent), so callers check such keys by the app's exit, not by this.
inline bool xdo(App& app, const std::string& title, const std::string& args) {
  using namespace std::chrono_literals;
  const std::filesystem::path errors = std::filesystem::temp_directory_path() /
                                       ("penumbra-xdotool-" + std::to_string(::getpid()) + ".txt");
  const std::string cmd = "timeout 10 xdotool search --sync --name '^" + title + "$' windowfocus --sync " + args +
                          " >/dev/null 2>" + errors.string();
  bool ok = false;
  for (int attempt = 1; attempt <= 3 && !ok; ++attempt) {
    if (attempt > 1) std::this_thread::sleep_for(200ms);
    if (!app.running()) break;
    ok = std::system(cmd.c_str()) == 0;
    if (ok) break;
    const std::string said = slurp(errors);
    std::cerr << "xdotool try " << attempt << " of 3 failed (" << args << "): " << said
              << (app.running() ? "" : " [the app has exited]") << "\n";
    if (said.find("BadWindow") != std::string::npos) break;  // the window went away: the input may have arrived
  }
  std::filesystem::remove(errors);
  return ok;
}

}  // namespace penumbra::test
