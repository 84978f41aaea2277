// The participant's flow without a window (procedure/session_flow.h): consent however the id
// arrives, nothing written before it, consent recorded; rests never next to practice and counted
// from the last rest screen; one round numbering on screens, status lines and the log; answers
// only once the stimulus is up; the admin panel withdrawing a trial; screens --screenshot-at
// cannot reach.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "json/json_input.h"
#include "log/trial_log.h"
#include "procedure/config.h"
#include "procedure/session.h"
#include "procedure/session_flow.h"
#include "procedure/session_record.h"
#include "text/fingerprint.h"

namespace {

namespace fs = std::filesystem;
using namespace penumbra;
using procedure::Screen;

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("penumbra-session-flow-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

// Two rounds, two sizes, short staircases; practice and breaks as given.
procedure::StudyConfig config_with(const nlohmann::json& extra) {
  nlohmann::json j = {{"artifact_px", {5, 10}},
                      {"rounds", {{{"pattern", "stair"}, {"contrast", 1.0}}, {{"pattern", "step"}, {"contrast", 0.5}}}},
                      {"stopping", {{"min_trials", 3}, {"max_trials", 3}, {"sd_below", 0.01}}},
                      {"round_order", "fixed"},
                      {"seed", 3u}};
  for (auto it = extra.begin(); it != extra.end(); ++it) j[it.key()] = it.value();
  return procedure::parse_config(j, "study.json");
}

// The flow with a clock of its own, its lines kept, and a session created in `dir` when it asks.
struct Driver {
  fs::path dir;
  procedure::StudyConfig config;
  std::vector<std::string> lines;
  std::vector<procedure::TrialPlan> presented;
  int examples = 0;
  int opened = 0;
  double t = 100;
  std::optional<procedure::SessionFlow> flow;

  Driver(const std::string& name, const procedure::StudyConfig& c, bool intake = false, const std::string& participant = "p1")
      : dir(fresh_dir(name)), config(c) {
    procedure::FlowSetup setup;
    setup.config = config;
    setup.intake = intake;
    setup.participant = participant;
    setup.iti_ms = 400;
    setup.refresh_hz = 60;
    setup.admin_panel = true;
    setup.id_problem = [](const std::string& id) { return id == "taken" ? "participant 'taken' already has a session" : ""; };
    setup.open = [this](const std::string& p, const nlohmann::json& consent) {
      ++opened;
      nlohmann::json extra = {{"observer_kind", "person"}};
      if (!consent.is_null()) extra["consent"] = consent;
      return procedure::Session::create(config, dir, p, extra);
    };
    flow.emplace(setup, hooks(), t);
  }
  procedure::FlowHooks hooks() {
    return {[this](const std::string& l) { lines.push_back(l); },
            [this](const procedure::TrialPlan& p) { presented.push_back(p); },
            [this](const stimuli::StimulusSpec&) { ++examples; }};
  }
  bool said(const std::string& prefix) const {
    for (const std::string& l : lines)
      if (l.rfind(prefix, 0) == 0) return true;
    return false;
  }
  // One frame: time passes, the timers run, the screen is drawn and swapped.
  void frame(double dt = 1.0 / 60) {
    t += dt;
    flow->tick(t);
    flow->swapped(flow->screen(), t);
  }
  // Space through instruction and break screens, frames through blanks and feedback, until a
  // trial is answerable (true) or the session is over (false).
  bool to_trial() {
    for (int i = 0; i < 10000; ++i) {
      const Screen s = flow->screen();
      if (s == Screen::finished || s == Screen::closed) return false;
      if (flow->answerable()) return true;
      if (s == Screen::welcome || s == Screen::round || s == Screen::rest) flow->space();
      else frame(0.1);
    }
    return false;
  }
  // The screens met on the way to the next trial (without the blank and trial frames).
  std::vector<Screen> answer_and_continue(procedure::Answer a, std::vector<Screen>* rests = nullptr) {
    t += 0.5;
    flow->answer(a, t);
    std::vector<Screen> seen;
    for (int i = 0; i < 10000; ++i) {
      const Screen s = flow->screen();
      if (s == Screen::finished || flow->answerable()) break;
      if (s == Screen::welcome || s == Screen::round || s == Screen::rest) {
        seen.push_back(s);
        flow->space();
      } else {
        frame(0.1);
      }
    }
    if (rests) *rests = seen;
    return seen;
  }
};

TEST(SessionFlow, ConsentIsAskedWhenTheIdIsGivenOnTheCommandLineAndDecliningWritesNothing) {
  const auto config = config_with({{"texts", {{"consent", "I agree to take part."}}}});
  Driver d("decline", config, false, "P05");
  EXPECT_EQ(d.flow->screen(), Screen::consent);
  EXPECT_TRUE(d.said("consent screen: waiting for agree (Enter) or decline (Escape)"));
  EXPECT_EQ(d.opened, 0);
  EXPECT_FALSE(fs::exists(d.dir));
  d.flow->space();  // Space is no answer to a consent question
  d.flow->answer(procedure::Answer::first, d.t);
  EXPECT_EQ(d.flow->screen(), Screen::consent);
  d.flow->escape();
  EXPECT_TRUE(d.flow->done());
  EXPECT_TRUE(d.said("consent declined: nothing written"));
  EXPECT_EQ(d.opened, 0);
  EXPECT_FALSE(fs::exists(d.dir));
}

TEST(SessionFlow, AgreeingCreatesTheSessionAndRecordsWhenAndWhichText) {
  const std::string text = "I agree to take part.\nMy data are kept anonymous.";
  const auto config = config_with({{"texts", {{"consent", text}}}});
  Driver d("agree", config, false, "P05");
  d.flow->agree();
  EXPECT_EQ(d.opened, 1);
  EXPECT_EQ(d.flow->screen(), Screen::welcome);
  EXPECT_TRUE(d.said("consent given"));
  const nlohmann::json j = json_input::read_file(d.dir / "session.json");
  ASSERT_TRUE(j.contains("consent")) << j.dump();
  EXPECT_EQ(j["consent"]["given"], true);
  EXPECT_EQ(j["consent"]["text_fingerprint"], text::fnv1a64_hex(text));
  EXPECT_TRUE(std::regex_match(j["consent"]["utc"].get<std::string>(), std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z)")));
  EXPECT_NO_THROW(procedure::check_consent_record(j, config, "session.json"));
  // A resume with this config needs that record: none, or consent to another text, is refused.
  nlohmann::json none = j;
  none.erase("consent");
  try {
    procedure::check_consent_record(none, config, "s/session.json");
    ADD_FAILURE() << "a session without consent was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("s/session.json: consent: the config has a consent text but the session records no consent", 0), 0u)
        << e.what();
  }
  const auto changed = config_with({{"texts", {{"consent", text + " Edited."}}}});
  EXPECT_THROW(procedure::check_consent_record(j, changed, "s/session.json"), std::runtime_error);
  // A config without a consent text asks nothing of the record.
  EXPECT_NO_THROW(procedure::check_consent_record(none, config_with({}), "s/session.json"));
  fs::remove_all(d.dir);
}

TEST(SessionFlow, IntakeRefusesAnIdThenAsksForConsentBeforeCreating) {
  const auto config = config_with({{"texts", {{"consent", "Agree?"}}}});
  Driver d("intake", config, true, "");
  EXPECT_EQ(d.flow->screen(), Screen::intake);
  EXPECT_FALSE(d.said("intake screen"));  // said once the field has the keyboard
  d.frame();
  d.frame();
  EXPECT_TRUE(d.said("intake screen: waiting for the participant id"));
  d.flow->submit_id("taken");
  EXPECT_EQ(d.flow->screen(), Screen::intake);
  EXPECT_EQ(d.flow->intake_problem(), "participant 'taken' already has a session");
  EXPECT_EQ(d.flow->text().body, "participant 'taken' already has a session");
  d.flow->submit_id("P07");
  EXPECT_EQ(d.flow->screen(), Screen::consent);
  EXPECT_EQ(d.flow->text().body, "Agree?");
  EXPECT_EQ(d.opened, 0);
  d.flow->agree();
  EXPECT_TRUE(d.said("participant 'P07' accepted"));
  EXPECT_EQ(d.opened, 1);
  EXPECT_EQ(d.flow->session().session_json()["participant"], "P07");
  fs::remove_all(d.dir);
}

TEST(SessionFlow, WithoutAConsentTextTheSessionOpensAtOnce) {
  Driver d("no-consent", config_with({}));
  EXPECT_EQ(d.opened, 1);
  EXPECT_EQ(d.flow->screen(), Screen::welcome);
  EXPECT_FALSE(d.flow->session().session_json().contains("consent"));
  fs::remove_all(d.dir);
}

// The defect a lab met: a round screen at trial 59, a practice trial, then "break after 60 trials".
TEST(SessionFlow, NoBreakNextToPracticeAndTheRoundScreenRestartsTheCount) {
  // Practice of 2 with feedback before every round; a break due every 4 trials; 6 test trials a round.
  const auto config = config_with({{"practice", {{"trials", 2}, {"every_round", true}, {"feedback", true}}}, {"break_every_trials", 4}});
  Driver d("breaks", config);
  ASSERT_TRUE(d.to_trial());
  int since_rest = 0;
  std::vector<std::pair<int, Screen>> rests;  // (trials done, screen) of each rest
  for (int guard = 0; guard < 100; ++guard) {
    const bool practice = d.flow->plan()->practice;
    std::vector<Screen> seen;
    d.answer_and_continue(procedure::Answer::first, &seen);
    ++since_rest;
    for (Screen s : seen) {
      rests.emplace_back(d.flow->session().trials_done(), s);
      if (s == Screen::rest) {
        EXPECT_FALSE(practice) << "a break right after a practice trial";
        ASSERT_TRUE(d.flow->plan());
        EXPECT_FALSE(d.flow->plan()->practice) << "a break right before a practice trial";
        EXPECT_EQ(since_rest, 4) << "the break comes 4 trials after the last rest";
      }
      since_rest = 0;
    }
    if (d.flow->screen() == Screen::finished) break;
  }
  // Round 1: 2 practice + 2 test trials, break, 4 test; the round screen, then the same in round 2.
  const std::vector<std::pair<int, Screen>> expected{{4, Screen::rest}, {8, Screen::round}, {12, Screen::rest}};
  EXPECT_EQ(rests, expected);
  EXPECT_TRUE(d.said("break after 4 trials"));
  fs::remove_all(d.dir);
}

TEST(SessionFlow, OneRoundNumberingOnScreensInStatusLinesAndInTheLog) {
  // The config's second round runs first: position and condition differ.
  auto config = config_with({{"round_order", "fixed"}, {"practice", {{"trials", 1}, {"every_round", false}, {"feedback", false}}}});
  config.round_order = "latin-square";
  Driver d("numbering", config, false, "p2");  // Latin-square row 2 of 2: rounds 1, 0
  ASSERT_EQ(d.flow->session().randomization().round_order, (std::vector<int>{1, 0}));
  EXPECT_EQ(d.flow->text().round_line, "Round 1 of 2");
  ASSERT_TRUE(d.to_trial());
  EXPECT_TRUE(d.said("trial 0 on screen (Round 1 of 2, a")) << d.lines.back();
  EXPECT_EQ(d.flow->text().progress, config.text("practice"));
  d.answer_and_continue(procedure::Answer::first);
  EXPECT_EQ(d.flow->text().progress, "Round 1 of 2");
  while (d.flow->plan()->round == 1) d.answer_and_continue(procedure::Answer::second);
  EXPECT_TRUE(d.said("round screen: Round 2 of 2 (stair/1), waiting for Space"));
  EXPECT_EQ(d.flow->text().progress, "Round 2 of 2");
  const auto log = trial_log::read(d.dir / "trials.csv");
  ASSERT_FALSE(log.rows.empty());
  for (const auto& row : log.rows) {
    EXPECT_EQ(row.round_position, row.condition_index == 1 ? 1 : 2);
  }
  EXPECT_EQ(log.rows.front().condition_index, 1);
  const std::string header = trial_log::header_line();
  EXPECT_NE(header.find(",condition_index,round_position,trial,"), std::string::npos) << header;
  fs::remove_all(d.dir);
}

TEST(SessionFlow, AnswersCountOnlyOnceTheStimulusIsUpAndReactionTimesAreMicroseconds) {
  Driver d("answers", config_with({}));
  d.flow->space();
  ASSERT_EQ(d.flow->screen(), Screen::blank);
  ASSERT_EQ(d.presented.size(), 1u);
  d.flow->answer(procedure::Answer::first, d.t);  // a key during the blank
  EXPECT_EQ(d.flow->session().trials_done(), 0);
  d.frame(0.5);  // the blank is over: the trial is drawn
  ASSERT_TRUE(d.flow->answerable());
  const double onset = d.flow->onset_s();
  d.flow->answer(procedure::Answer::first, onset - 0.01);  // pressed before the onset
  EXPECT_EQ(d.flow->session().trials_done(), 0);
  d.frame();
  d.frame();
  d.flow->answer(procedure::Answer::second, onset + 0.5123456789);
  EXPECT_EQ(d.flow->session().trials_done(), 1);
  const auto log = trial_log::read(d.dir / "trials.csv");
  ASSERT_EQ(log.rows.size(), 1u);
  EXPECT_NEAR(log.rows[0].rt_ms, 512.346, 1e-9);
  ASSERT_TRUE(log.rows[0].timing.has_value());
  EXPECT_EQ(log.rows[0].timing->frames, 3);
  std::ifstream in(d.dir / "trials.csv");
  const std::string csv((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(csv.find(",512.346,"), std::string::npos) << csv;
  fs::remove_all(d.dir);
}

TEST(SessionFlow, TheAdminPanelWithdrawsTheTrialAndItComesAgainUnchanged) {
  Driver d("panel", config_with({}));
  ASSERT_TRUE(d.to_trial());
  const procedure::TrialPlan before = *d.flow->plan();
  d.flow->toggle_panel();
  EXPECT_EQ(d.flow->screen(), Screen::pause);
  EXPECT_TRUE(d.said("trial 0 withdrawn: the admin panel is open"));
  d.flow->answer(procedure::Answer::first, d.t + 1);
  EXPECT_EQ(d.flow->session().trials_done(), 0);
  d.flow->toggle_panel();
  ASSERT_TRUE(d.to_trial());
  EXPECT_EQ(d.flow->plan()->stimulus.seed, before.stimulus.seed);
  EXPECT_EQ(d.flow->plan()->target, before.target);
  // Paused by the experimenter: the next trial waits, also after a round is ended.
  d.flow->toggle_pause();
  EXPECT_EQ(d.flow->screen(), Screen::pause);
  d.flow->end_round();
  d.frame(1.0);
  EXPECT_NE(d.flow->screen(), Screen::trial);
  d.flow->toggle_pause();
  fs::remove_all(d.dir);
}

TEST(SessionFlow, EscapeStopsBetweenTrialsWithAResumeCommand) {
  Driver d("escape", config_with({}));
  ASSERT_TRUE(d.to_trial());
  d.answer_and_continue(procedure::Answer::first);
  d.flow->escape();
  EXPECT_TRUE(d.flow->done());
  EXPECT_TRUE(d.said("stopped after 1 trials; continue with: penumbra-study run --resume " + d.dir.string()));
  fs::remove_all(d.dir);
}

TEST(SessionFlow, ScreensASessionWouldNeverShowAreNamed) {
  const auto plain = config_with({{"practice", {{"trials", 0}}}});
  EXPECT_EQ(procedure::unreachable(Screen::intake, plain, false, nullptr),
            "there is no intake screen: the participant id is given (--participant or --resume)");
  EXPECT_EQ(procedure::unreachable(Screen::intake, plain, true, nullptr), "");
  EXPECT_EQ(procedure::unreachable(Screen::consent, plain, false, nullptr), "the config has no consent text (texts.consent)");
  const auto consenting = config_with({{"texts", {{"consent", "Agree?"}}}});
  EXPECT_EQ(procedure::unreachable(Screen::consent, consenting, false, nullptr), "");
  EXPECT_EQ(procedure::unreachable(Screen::round, plain, false, nullptr), "");
  EXPECT_EQ(procedure::unreachable(Screen::feedback, plain, false, nullptr),
            "the config gives no practice feedback (practice.feedback, practice.trials)");
  auto one_round = plain;
  one_round.rounds.resize(1);
  EXPECT_EQ(procedure::unreachable(Screen::round, one_round, false, nullptr),
            "the config has one round: its instructions are on the welcome screen");
  // A resumed session: no consent again, and no round screen once the last round is next.
  Driver d("unreachable", consenting, false, "p1");
  d.flow->agree();
  EXPECT_EQ(procedure::unreachable(Screen::consent, consenting, false, &d.flow->session()),
            "a resumed session does not ask for consent again");
  EXPECT_EQ(procedure::unreachable(Screen::round, consenting, false, &d.flow->session()), "");
  fs::remove_all(d.dir);
}

}  // namespace
