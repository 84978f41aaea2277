#include "procedure/session_flow.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "json/json_input.h"
#include "text/fingerprint.h"

namespace penumbra::procedure {

const char* describe(Screen s) {
  switch (s) {
    case Screen::intake: return "intake (participant id)";
    case Screen::consent: return "consent";
    case Screen::welcome: return "welcome screen";
    case Screen::round: return "round instructions";
    case Screen::feedback: return "practice feedback";
    case Screen::blank: return "blank (between trials)";
    case Screen::trial: return "trial on screen";
    case Screen::pause: return "paused";
    case Screen::rest: return "break screen";
    case Screen::finished: return "end screen";
    case Screen::closed: return "closed";
  }
  return "";
}

const char* name_of(Screen s) {
  switch (s) {
    case Screen::intake: return "intake";
    case Screen::consent: return "consent";
    case Screen::welcome: return "welcome";
    case Screen::round: return "round";
    case Screen::feedback: return "feedback";
    case Screen::blank: return "blank";
    case Screen::trial: return "trial";
    case Screen::pause: return "pause";
    case Screen::rest: return "break";
    case Screen::finished: return "end";
    case Screen::closed: return "closed";
  }
  return "";
}

std::string response_for(Answer answer, const std::string& task) {
  if (answer == Answer::none) throw std::invalid_argument("response_for: no answer");
  if (task == "2afc") return answer == Answer::first ? "left" : "right";
  return answer == Answer::first ? "yes" : "no";
}

nlohmann::json consent_record(const std::string& consent_text, const std::string& utc) {
  return {{"given", true}, {"utc", utc}, {"text_fingerprint", text::fnv1a64_hex(consent_text)}, {"text_bytes", consent_text.size()}};
}

void check_consent_record(const nlohmann::json& session_json, const StudyConfig& config, const std::string& file) {
  const std::string text = config.text("consent");
  if (text.empty()) return;
  const auto it = session_json.find("consent");
  if (it == session_json.end() || !it->is_object() || it->value("given", false) != true)
    throw std::runtime_error(file + ": consent: the config has a consent text but the session records no consent; "
                                    "a participant who has not agreed cannot be run (start a new session)");
  const auto fingerprint = it->find("text_fingerprint");
  if (fingerprint == it->end() || !fingerprint->is_string() || *fingerprint != text::fnv1a64_hex(text))
    throw std::runtime_error(file + ": consent: text_fingerprint: the participant agreed to another consent text than the config's");
}

SessionFlow::SessionFlow(FlowSetup setup, FlowHooks hooks, double clock_start_s)
    : setup_(std::move(setup)), hooks_(std::move(hooks)), clock_start_s_(clock_start_s), now_s_(clock_start_s) {
  status_.dropped_frame_ms = setup_.refresh_hz > 0 ? trial_log::kDroppedFramePeriods * 1000.0 / setup_.refresh_hz : 0;
  participant_ = setup_.participant;
  if (setup_.intake) {
    screen_ = Screen::intake;  // announced once its field has the keyboard (swapped)
  } else if (!setup_.config.text("consent").empty()) {
    screen_ = Screen::consent;
    say("consent screen: waiting for agree (Enter) or decline (Escape)");
  } else {
    open_session(nullptr);
  }
}

SessionFlow::SessionFlow(Session session, FlowSetup setup, FlowHooks hooks, double clock_start_s)
    : setup_(std::move(setup)), hooks_(std::move(hooks)), clock_start_s_(clock_start_s), now_s_(clock_start_s) {
  status_.dropped_frame_ms = setup_.refresh_hz > 0 ? trial_log::kDroppedFramePeriods * 1000.0 / setup_.refresh_hz : 0;
  session_.emplace(std::move(session));
  setup_.config = session_->config();
  participant_ = session_->session_json().value("participant", std::string());
  resumed_ = session_->trials_done() > 0;
  welcome();
}

void SessionFlow::say(const std::string& line) const {
  if (hooks_.say) hooks_.say(line);
}

void SessionFlow::open_session(const nlohmann::json& consent) {
  session_.emplace(setup_.open(participant_, consent));
  resumed_ = session_->trials_done() > 0;
  welcome();
}

void SessionFlow::welcome() {
  screen_ = Screen::welcome;
  trials_since_rest_ = 0;
  last_was_practice_ = false;
  const std::optional<TrialPlan> upcoming = session_->next();
  if (upcoming) {  // the first screen introduces the first round to come
    introduced_round_ = upcoming->round;
    show_examples(upcoming->round);
  }
  practice_first_ = upcoming && upcoming->practice;
  say("welcome screen: waiting for Space");
}

void SessionFlow::show_examples(int round) {
  if (round == examples_round_ || setup_.config.artifact_px.empty()) return;  // a frame study: no edge examples
  const double artifact_px = *std::max_element(setup_.config.artifact_px.begin(), setup_.config.artifact_px.end());
  if (hooks_.examples) hooks_.examples(session_->stimulus(round, artifact_px, 1.0, 1));
  examples_round_ = round;
}

std::string SessionFlow::round_line(int round) const {
  return setup_.config.text("round", session_->round_position(round) + 1, static_cast<int>(session_->rounds().size()));
}

std::string SessionFlow::progress() const {
  if (!session_) return "";
  if (plan_ && plan_->practice) return setup_.config.text("practice");
  const int round = session_->current_round();
  if (round >= static_cast<int>(session_->rounds().size())) return "";
  return round_line(round);
}

// Chooses what comes next: the end, a new round's instructions, a break, or the next trial.
void SessionFlow::advance() {
  plan_ = session_->next();
  if (!plan_) {
    screen_ = Screen::finished;
    say("session complete: " + std::to_string(session_->trials_done()) + " trials in " + session_->dir().string());
    return;
  }
  if (plan_->round != introduced_round_) {
    introduced_round_ = plan_->round;
    trials_since_rest_ = 0;  // the round's screen is a rest as well
    last_was_practice_ = false;
    show_examples(plan_->round);
    screen_ = Screen::round;
    say("round screen: " + round_line(plan_->round) + " (" + session_->condition(plan_->round) +
        (plan_->practice ? ", practice first" : "") + "), waiting for Space");
    return;
  }
  const int every = setup_.config.break_every_trials;
  if (every > 0 && trials_since_rest_ >= every && !last_was_practice_ && !plan_->practice) {
    screen_ = Screen::rest;
    say("break after " + std::to_string(session_->trials_done()) + " trials");
    return;
  }
  present();
}

// The next trial's stimuli, after a blank interval.
void SessionFlow::present() {
  if (hooks_.present) hooks_.present(*plan_);
  screen_ = Screen::blank;
  blank_until_ = now_s_ + setup_.iti_ms / 1000.0;
}

void SessionFlow::submit_id(const std::string& id) {
  if (screen_ != Screen::intake) return;
  intake_problem_ = setup_.id_problem ? setup_.id_problem(id) : "";
  if (!intake_problem_.empty()) {
    say("intake: refused: " + intake_problem_);
    return;
  }
  participant_ = id;
  if (!setup_.config.text("consent").empty()) {
    screen_ = Screen::consent;
    say("consent screen: waiting for agree (Enter) or decline (Escape)");
    return;
  }
  say("participant '" + json_input::printable(id) + "' accepted");
  open_session(nullptr);
}

void SessionFlow::agree() {
  if (screen_ != Screen::consent) return;
  say("consent given");
  if (setup_.intake) say("participant '" + json_input::printable(participant_) + "' accepted");
  open_session(consent_record(setup_.config.text("consent"), utc_now()));
}

void SessionFlow::escape() {
  switch (screen_) {
    case Screen::closed: return;
    case Screen::intake: say("intake cancelled: nothing written"); break;
    case Screen::consent: say("consent declined: nothing written"); break;
    case Screen::finished: break;
    default:
      say("stopped after " + std::to_string(session_->trials_done()) + " trials; continue with: penumbra-study run --resume " +
          session_->dir().string());
  }
  screen_ = Screen::closed;
}

void SessionFlow::quit() { escape(); }

void SessionFlow::space() {
  if (paused_) return;
  if (screen_ == Screen::welcome) {
    advance();
  } else if (screen_ == Screen::rest) {
    trials_since_rest_ = 0;
    advance();
  } else if (screen_ == Screen::round) {
    present();
  }
}

void SessionFlow::answer(Answer a, double when_s) {
  if (a == Answer::none || !answerable() || when_s < onset_s_) return;
  now_s_ = std::max(now_s_, when_s);
  const std::string response = response_for(a, setup_.config.task);
  const double rt_ms = std::round((when_s - onset_s_) * 1e6) / 1e3;  // to the microsecond
  const trial_log::FrameTiming timing = trial_log::frame_timing(onset_s_ - clock_start_s_, stimulus_frames_ms_, setup_.refresh_hz);
  const trial_log::TrialRow row = session_->record(*plan_, response, rt_ms, timing);
  onset_s_ = -1;
  char buf[200];
  std::snprintf(buf, sizeof buf, "trial %d: %s (%s), %.0f ms", row.trial, response.c_str(), row.correct ? "correct" : "wrong", rt_ms);
  status_.last_answer = buf;
  say(buf);
  std::snprintf(buf, sizeof buf, "trial %d: %d frames, mean %.1f ms, max %.1f ms", row.trial, timing.frames, timing.frame_ms_mean,
                timing.frame_ms_max);
  status_.last_timing = buf;
  ++status_.timed_trials;
  if (timing.dropped_frames.value_or(0) > 0) {
    ++status_.trials_with_drops;
    status_.dropped_frames += *timing.dropped_frames;
    std::snprintf(buf, sizeof buf, "warning: trial %d: %d dropped frame(s) while the stimulus was up (max %.1f ms, over %.1f ms)",
                  row.trial, *timing.dropped_frames, timing.frame_ms_max, status_.dropped_frame_ms);
    say(buf);
  }
  ++trials_since_rest_;
  last_was_practice_ = plan_->practice;
  if (plan_->practice && setup_.config.practice.feedback) {  // practice only: test trials never say
    feedback_ = setup_.config.text(row.correct ? "practice_feedback_correct" : "practice_feedback_wrong");
    feedback_correct_ = row.correct == 1;
    screen_ = Screen::feedback;
    feedback_until_ = now_s_ + setup_.config.practice.feedback_ms / 1000.0;
    say("trial " + std::to_string(row.trial) + " feedback: " + (row.correct ? "correct" : "wrong"));
    return;
  }
  advance();
}

void SessionFlow::toggle_pause() {
  if (!session_ || screen_ == Screen::finished || screen_ == Screen::closed) return;
  paused_ = !paused_;
  say(paused_ ? "paused by the experimenter" : "resumed by the experimenter");
  if (paused_ && (screen_ == Screen::blank || screen_ == Screen::trial)) screen_ = Screen::pause;
  if (!paused_ && screen_ == Screen::pause && !panel_covers()) advance();  // the withdrawn trial comes again (same plan)
}

void SessionFlow::end_round() {
  if (!session_ || screen_ == Screen::closed) return;
  const int round = session_->current_round();
  if (round >= static_cast<int>(session_->rounds().size())) return;
  say("round " + std::to_string(session_->round_position(round) + 1) + " (" + session_->condition(round) + ") ended by the experimenter");
  session_->end_round();
  if (screen_ == Screen::blank || screen_ == Screen::trial || screen_ == Screen::round) advance();
}

void SessionFlow::toggle_panel() {
  if (!setup_.admin_panel || !session_) return;  // no panel before the session exists (intake, consent)
  // The panel covers the stimuli: a trial on screen is withdrawn while it is open (no answer is
  // taken, its reaction time does not run) and comes again, the same plan, once it closes.
  panel_visible_ = !panel_visible_;
  if (panel_covers() && (screen_ == Screen::blank || screen_ == Screen::trial)) {
    screen_ = Screen::pause;
    onset_s_ = -1;
    say("trial " + std::to_string(plan_->trial) + " withdrawn: the admin panel is open");
  } else if (!panel_visible_ && !paused_ && screen_ == Screen::pause) {
    advance();
  }
}

void SessionFlow::tick(double now_s) {
  now_s_ = std::max(now_s_, now_s);
  if (screen_ == Screen::feedback && now_s_ >= feedback_until_) {
    feedback_.clear();
    if (paused_ || panel_covers()) screen_ = Screen::pause;  // the next trial waits
    else advance();
  }
  if (screen_ == Screen::blank && now_s_ >= blank_until_) {
    // Never under the admin panel or while paused: the trial waits until both are gone.
    screen_ = paused_ || panel_covers() ? Screen::pause : Screen::trial;
    onset_s_ = -1;
  }
}

void SessionFlow::swapped(Screen drawn, double swap_s) {
  now_s_ = std::max(now_s_, swap_s);
  if (drawn == Screen::intake && screen_ == Screen::intake && ++intake_frames_ == 2)
    say("intake screen: waiting for the participant id");  // ImGui gives the field the keyboard in the frame after it asks
  const bool first_trial_frame = drawn == Screen::trial && screen_ == Screen::trial && onset_s_ < 0;
  if (first_trial_frame) {
    onset_s_ = swap_s;
    stimulus_frames_ms_.clear();
  }
  if (drawn == Screen::trial && screen_ == Screen::trial && onset_s_ >= 0)
    stimulus_frames_ms_.push_back((swap_s - last_swap_s_) * 1000.0);
  last_swap_s_ = swap_s;
  if (first_trial_frame) {
    char buf[200];
    char level[40];  // a frame study shows a multiple k of the rule's c, the edge study a filter radius
    if (plan_->k > 0) std::snprintf(level, sizeof level, "k %.3g", plan_->k);
    else std::snprintf(level, sizeof level, "r %.2f px", plan_->stimulus.filter_radius_px);
    std::snprintf(buf, sizeof buf, "trial %d on screen (%s, %s, %s, %s)", plan_->trial, round_line(plan_->round).c_str(),
                  plan_->staircase_name.c_str(), level, plan_->practice ? "practice" : "QUEST");
    say(buf);
  }
}

ScreenText SessionFlow::text() const {
  const StudyConfig& c = setup_.config;
  ScreenText t;
  t.progress = progress();
  auto instructions = [&](const std::string& title, const std::string& intro, bool practice_next, bool round_below) {
    t.title = title;
    t.body = intro + "\n\n" + c.text("task");
    if (practice_next) t.body += "\n\n" + c.text(c.practice.feedback ? "practice_feedback_note" : "practice_note");
    t.jagged_label = c.text("example_jagged");
    t.straight_label = c.text("example_straight");
    t.examples = examples_round_ >= 0;
    t.round_line = round_below && examples_round_ >= 0 ? round_line(examples_round_) : "";
    t.button = paused_ ? "" : c.text(screen_ == Screen::welcome ? "start" : "continue");
    t.progress.clear();  // the instruction screens name the round themselves
  };
  switch (screen_) {
    case Screen::intake:
      t.title = c.name;
      t.body = intake_problem_;
      break;
    case Screen::consent:
      t.title = c.text("consent_title");
      t.body = c.text("consent");
      t.first = c.text("consent_agree");
      t.second = c.text("consent_decline");
      break;
    case Screen::welcome:
      instructions(c.text(resumed_ ? "welcome_back_title" : "welcome_title"), c.text("welcome"), practice_first_, true);
      break;
    case Screen::round:
      instructions(round_line(plan_->round), c.text("round_body"), plan_->practice, false);
      break;
    case Screen::rest:
      t.title = c.text("break_title");
      t.body = c.text("break");
      t.button = paused_ ? "" : c.text("continue");
      break;
    case Screen::pause:
      t.title = c.text("pause_title");
      t.body = c.text("pause");
      break;
    case Screen::finished:
      t.title = c.text("end_title");
      t.body = c.text("end");
      t.progress.clear();
      break;
    case Screen::blank:
    case Screen::closed:
      break;
    case Screen::trial:
    case Screen::feedback:
      t.question = c.text("question");
      t.first = c.text("answer_first");
      t.second = c.text("answer_second");
      if (screen_ == Screen::feedback) {
        t.feedback = feedback_;
        t.feedback_correct = feedback_correct_;
      }
      break;
  }
  return t;
}

FlowStatus SessionFlow::status() const {
  FlowStatus s = status_;
  s.screen = describe(screen_);
  s.paused = paused_;
  return s;
}

std::string unreachable(Screen target, const StudyConfig& c, bool intake, const Session* resumed) {
  switch (target) {
    case Screen::intake:
      return intake ? "" : "there is no intake screen: the participant id is given (--participant or --resume)";
    case Screen::consent:
      if (c.text("consent").empty()) return "the config has no consent text (texts.consent)";
      return resumed ? "a resumed session does not ask for consent again" : "";
    case Screen::round: {
      if (!resumed) return c.rounds.size() >= 2 ? "" : "the config has one round: its instructions are on the welcome screen";
      const int n = static_cast<int>(resumed->rounds().size());
      const int upcoming = resumed->current_round();
      if (upcoming < n && resumed->round_position(upcoming) + 1 < n) return "";
      return "no round is left after the one the welcome screen introduces";
    }
    case Screen::feedback: {
      if (!c.practice.feedback || c.practice.trials == 0) return "the config gives no practice feedback (practice.feedback, practice.trials)";
      if (!resumed) return "";
      const std::optional<TrialPlan> upcoming = resumed->next();
      if (upcoming && upcoming->practice) return "";
      if (c.practice.every_round && upcoming && resumed->round_position(upcoming->round) + 1 < static_cast<int>(resumed->rounds().size()))
        return "";
      return "no practice trial is left in this session";
    }
    default:
      return "";
  }
}

}  // namespace penumbra::procedure
