#pragma once
// `penumbra-study run` with a participant: the participant view full screen on one monitor and
// the admin view in a second window (or, on a single monitor, a panel the experimenter toggles
// with F12). Answers go through the same Session::record as headless runs, so the log is written
// the same way: one fsynced row per answered trial. Escape or closing a window stops the session
// between trials; the directory stays resumable (`--resume DIR`).
#include <filesystem>
#include <functional>
#include <string>

#include "procedure/session.h"

namespace CLI {
class App;
}

namespace penumbra::study_gui {

struct GuiOptions {
  int monitor = -1;            // participant monitor (GLFW index); -1: the config's display.monitor
  std::string windowed;        // "WxH": a window instead of full screen (testing, demos)
  bool admin_panel = false;    // single-monitor setups: the admin view is a panel (F12) in the participant window
  double iti_ms = 400;         // blank screen between trials
  std::filesystem::path screenshot_dir;  // write participant.png (+ admin.png) at the first stimulus onset (or the end screen), then stop
  double refresh_hz = 0;       // the participant display's refresh rate where its video mode reports none (0: not given)
};

// Adds --monitor, --windowed, --admin-panel, --iti-ms, --screenshot, --refresh-hz to `run`.
void add_options(CLI::App& run, GuiOptions& options);

// "--windowed WxH": the size in pixels; throws std::invalid_argument naming the option otherwise.
void parse_window_size(const std::string& windowed, int& width, int& height);

// Opens the windows, then the session (`open_session` creates or resumes it: after every check
// that can refuse, so a refusal leaves no new session behind), and runs it until it is finished
// or stopped. Returns the process exit code (0).
// `open_session(check)` opens or resumes the session and must call `check(config)` before it
// creates or writes anything: it refuses a config whose stimuli do not fit the participant screen.
int run_session(const std::function<procedure::Session(const std::function<void(const procedure::StudyConfig&)>&)>& open_session,
                const GuiOptions& options);

}  // namespace penumbra::study_gui
