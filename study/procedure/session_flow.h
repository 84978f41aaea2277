#pragma once
// The participant's way through a session as a state machine without windows: the intake screen
// (the experimenter types the id), consent, the welcome screen, each round's instructions, practice
// with feedback, trials with a blank between them, breaks, the experimenter's pause and round end,
// and the end screen. The windows (study/gui) draw `screen()` with `text()` and feed the flow key
// presses, button clicks, admin actions and the times of their swaps; tests step through it the
// same way with a clock of their own. Each transition says one line (the operator's terminal and
// the GUI tests read them); answers go to the log through Session::record.
//
// Two rules a lab relies on live here:
//  - Consent: a config with a consent text is agreed to before the session exists, however the
//    participant id arrives (typed at the intake screen or given with --participant); declining
//    writes nothing; session.json records when consent was given and a fingerprint of the text.
//  - Rests: breaks come after break_every_trials trials since the last rest screen (the welcome,
//    a round's instructions or a break) and never next to a practice trial.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "log/trial_log.h"
#include "procedure/session.h"

namespace penumbra::procedure {

enum class Screen { intake, consent, welcome, round, blank, trial, feedback, pause, rest, finished, closed };
// What the participant sees, in words ("trial on screen"), for the admin view.
const char* describe(Screen screen);
// The screen's name for --screenshot-at (intake, consent, welcome, round, feedback, trial, ...).
const char* name_of(Screen screen);

// The two answers: first = left (2afc) / yes (yesno); second = right / no.
enum class Answer { none, first, second };
// The log's response for an answer: left|right (2afc), yes|no (yesno).
std::string response_for(Answer answer, const std::string& task);

// session.json's "consent" for a text shown and agreed to at `utc`: the time and a fingerprint of
// the exact text (FNV-1a 64 in hex, as display calibrations are fingerprinted).
nlohmann::json consent_record(const std::string& consent_text, const std::string& utc);
// Resume: a config with a consent text needs a session that recorded consent to that text. Throws
// std::runtime_error "<session.json>: consent: ..." otherwise.
void check_consent_record(const nlohmann::json& session_json, const StudyConfig& config, const std::string& file);

// Why `target` would never be shown ("" if it can be): --screenshot-at refuses such a screen before
// anything is opened. `resumed`: the session a resume continues (null for a new one): the intake
// screen only with `intake`, consent only with a consent text and never on a resume, a round screen
// only with a round after the one the welcome screen introduces, feedback only with practice
// feedback still to come.
std::string unreachable(Screen target, const StudyConfig& config, bool intake, const Session* resumed);

// What the flow needs from the app.
struct FlowSetup {
  StudyConfig config;  // known before the session exists (intake and consent show its texts)
  // The experimenter types the participant id at the intake screen ("" participant below).
  bool intake = false;
  // Why a typed id cannot start a session ("" if it can); intake only.
  std::function<std::string(const std::string& id)> id_problem;
  // Creates the session once the id is known and consent given; `consent` is consent_record(...)
  // or null when the config has no consent text.
  std::function<Session(const std::string& participant, const nlohmann::json& consent)> open;
  std::string participant;  // given on the command line (no intake)
  double iti_ms = 400;      // blank screen between trials
  double refresh_hz = 0;    // of the participant display; 0: unknown (dropped frames not judged)
  bool admin_panel = false;  // the admin view is a panel over the participant's view (F12)
};

// What happens outside the flow when it moves on. Each may be empty.
struct FlowHooks {
  std::function<void(const std::string& line)> say;
  // Draw this trial's stimuli now (they are shown once the blank interval is over).
  std::function<void(const TrialPlan& plan)> present;
  // Draw the instruction screens' examples: this stimulus, jagged and straight (the round's
  // pattern and contrast with the config's largest artifact and no filter to speak of, 1 px).
  std::function<void(const stimuli::StimulusSpec& example)> examples;
};

// Everything a screen says (the config's texts, filled in).
struct ScreenText {
  std::string title, body, button, progress;  // button "": none
  bool examples = false;                      // the instruction screens' jagged and straight examples
  std::string jagged_label, straight_label;
  std::string round_line;                     // below the examples on the welcome screen ("Round 1 of 4")
  std::string question, first, second;        // trial screens
  std::string feedback;                       // after a practice answer: shown instead of the question
  bool feedback_correct = false;
};

// For the admin view.
struct FlowStatus {
  std::string screen;       // describe(screen())
  bool paused = false;
  std::string last_answer;  // e.g. "trial 12: right (correct), 532 ms"
  std::string last_timing;  // e.g. "trial 12: 41 frames, mean 16.7 ms, max 17.9 ms"
  double dropped_frame_ms = 0;  // an interval over this is a dropped frame; 0: refresh rate unknown
  int timed_trials = 0;
  int trials_with_drops = 0;
  int dropped_frames = 0;
};

class SessionFlow {
 public:
  // A new session: the intake screen (setup.intake), or the consent screen when the config has a
  // consent text, or the session opened at once and the welcome screen. `now_s`: the flow's clock
  // (the windows' steady clock; frame onsets in the log count from `clock_start_s`).
  SessionFlow(FlowSetup setup, FlowHooks hooks, double clock_start_s);
  // An opened session (a resume): the welcome screen.
  SessionFlow(Session session, FlowSetup setup, FlowHooks hooks, double clock_start_s);

  // ---- What the participant does
  void submit_id(const std::string& id);  // intake: Enter or the button
  void agree();                           // consent: Enter or the button
  // Escape: cancels the intake, declines consent, or stops the session between trials.
  void escape();
  void space();  // Space or the screen's button: start, continue
  // An answer by key (at `when_s`, its press time) or button (`when_s`: the click's time, at the
  // earliest the onset). Ignored unless a trial is on screen and `when_s` is not before its onset.
  void answer(Answer answer, double when_s);

  // ---- What the experimenter does
  void toggle_pause();
  void end_round();
  void quit();
  void toggle_panel();  // F12 with the admin panel: open while a trial is up withdraws it

  // ---- Time
  // Timers: the blank interval's end (the trial comes up), the practice feedback's end.
  void tick(double now_s);
  // After each swap of the participant window: the screen that frame drew and the swap's time.
  // The first frame of a trial is its onset; later ones are the stimulus frames' intervals.
  void swapped(Screen drawn, double swap_s);

  // ---- State
  Screen screen() const { return screen_; }
  bool done() const { return screen_ == Screen::closed; }
  bool has_session() const { return session_.has_value(); }
  const Session& session() const { return *session_; }
  const std::optional<TrialPlan>& plan() const { return plan_; }
  bool paused() const { return paused_; }
  bool panel_visible() const { return panel_visible_; }
  // The trial is up and its first frame has been shown: answers count from `onset_s()`.
  bool answerable() const { return screen_ == Screen::trial && onset_s_ >= 0; }
  double onset_s() const { return onset_s_; }
  const std::string& intake_problem() const { return intake_problem_; }
  ScreenText text() const;
  FlowStatus status() const;
  // "Round 2 of 4": the round's 1-based position in this session.
  std::string round_line(int round) const;

 private:
  void say(const std::string& line) const;
  void open_session(const nlohmann::json& consent);
  void welcome();
  void advance();
  void present();
  void show_examples(int round);
  std::string progress() const;
  bool panel_covers() const { return setup_.admin_panel && panel_visible_; }

  FlowSetup setup_;
  FlowHooks hooks_;
  double clock_start_s_ = 0;
  std::optional<Session> session_;
  std::string participant_;
  bool resumed_ = false;
  Screen screen_ = Screen::welcome;
  std::optional<TrialPlan> plan_;
  std::string intake_problem_;
  bool paused_ = false, panel_visible_ = false, practice_first_ = false;
  double now_s_ = 0, blank_until_ = 0, feedback_until_ = 0, onset_s_ = -1, last_swap_s_ = -1;
  int introduced_round_ = -1, examples_round_ = -1, intake_frames_ = 0;
  int trials_since_rest_ = 0;  // answered since the last rest screen (welcome, round, break)
  bool last_was_practice_ = false;
  std::string feedback_;
  bool feedback_correct_ = false;
  std::vector<double> stimulus_frames_ms_;  // the current stimulus's frames' intervals
  FlowStatus status_;
};

}  // namespace penumbra::procedure
