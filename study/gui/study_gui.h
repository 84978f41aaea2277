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

#include <nlohmann/json.hpp>

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

// How the session of a participant run comes about.
struct SessionStart {
  // A new session: the config (its texts, its consent, the screen check) before the session exists.
  procedure::StudyConfig config;
  // The experimenter types the participant id at the intake screen (no --participant).
  bool intake = false;
  std::string participant;  // --participant
  // Why a typed id cannot start a session ("" if it can).
  std::function<std::string(const std::string& id)> id_problem;
  // Creates the new session (consent: procedure::consent_record, or null without a consent text).
  std::function<procedure::Session(const std::string& participant, const nlohmann::json& consent)> create;
  // Set for --resume: opens the session; `accept` sees it replayed, before anything is written, and
  // may throw to refuse.
  std::function<procedure::Session(const std::function<void(const procedure::Session&)>& accept)> resume;
  // A frame study's prepared frames (stimuli/frame_patch.h), read, never rendered, by the windows.
  std::filesystem::path frame_cache;
};

// Adds --monitor, --windowed, --admin-panel, --iti-ms, --screenshot, --screenshot-at, --refresh-hz to `run`.
void add_options(CLI::App& run, GuiOptions& options);

// What a session remembers of how it was presented (session.json "presentation_options"), so that
// `penumbra-study run --resume DIR` alone shows it the same way: the monitor, the window size, the
// admin panel, the refresh rate given and the blank interval.
nlohmann::json presentation_options(const GuiOptions& options);
// Takes each option the command line did not give (`given("--windowed")` false) from `recorded`
// (a session written before these were recorded has none). Throws std::runtime_error
// "<file>: presentation_options.<key>: ..." for a value of the wrong type or out of range.
void reuse_presentation_options(GuiOptions& options, const nlohmann::json& recorded, const std::function<bool(const std::string&)>& given,
                                const std::string& file);

// "--windowed WxH": the size in pixels; throws std::invalid_argument naming the option otherwise.
void parse_window_size(const std::string& windowed, int& width, int& height);

// Opens the windows and runs the participant's flow (procedure/session_flow.h) until the session is
// finished or stopped. Everything that can refuse (monitors, the stimulus size on this screen, a
// --screenshot-at screen the session would never show, a resumed session without the consent its
// config asks for) comes before a session is created or resumed; a new session is created only once
// the id is known and consent given, so Escape or declining ends the app with nothing written.
// Returns the process exit code (0).
int run_session(const SessionStart& start, const GuiOptions& options);

}  // namespace penumbra::study_gui
