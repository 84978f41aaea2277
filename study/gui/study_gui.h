#pragma once
// `penumbra-study run` with a participant: the participant view full screen on one monitor and
// the admin view in a second window (or, on a single monitor, a panel the experimenter toggles
// with F12). Answers go through the same Session::record as headless runs, so the log is written
// the same way: one fsynced row per answered trial. Escape or closing a window stops the session
// between trials; the directory stays resumable (`--resume DIR`).
#include <filesystem>
#include <functional>
#include <optional>
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
  // With screenshot_dir: the screen to capture (participant.png only) instead of the first stimulus:
  // intake, consent, welcome, round (the next round's instructions), feedback (after a practice answer).
  std::string screenshot_at = "trial";
};

// A new session whose participant id the experimenter types at the start screen (no --participant):
// the config is known before the session exists (its texts, its consent, the screen check).
struct Intake {
  procedure::StudyConfig config;
  // Why `id` cannot start a session (bad id, an existing session of that participant), "" if it can.
  std::function<std::string(const std::string& id)> problem;
};

// Opens or creates the session; must call `check(config)` before it creates or writes anything.
// `participant`: the id typed at the intake screen ("" without one).
using OpenSession = std::function<procedure::Session(const std::function<void(const procedure::StudyConfig&)>& check,
                                                     const std::string& participant)>;

// Adds --monitor, --windowed, --admin-panel, --iti-ms, --screenshot, --screenshot-at, --refresh-hz to `run`.
void add_options(CLI::App& run, GuiOptions& options);

// "--windowed WxH": the size in pixels; throws std::invalid_argument naming the option otherwise.
void parse_window_size(const std::string& windowed, int& width, int& height);

// Opens the windows, then the session (`open_session` creates or resumes it: after every check
// that can refuse, so a refusal leaves no new session behind), and runs it until it is finished
// or stopped. With `intake`, the participant window first asks for the participant id (refused
// ids are named on screen) and shows the config's consent text; Escape or declining ends the app
// with nothing written. Returns the process exit code (0).
int run_session(const OpenSession& open_session, const GuiOptions& options, const std::optional<Intake>& intake = std::nullopt);

}  // namespace penumbra::study_gui
