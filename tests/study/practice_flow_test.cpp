// The participant's flow in the procedure (issue 16): the practice block of a config (before every
// round with that round's pattern and contrast, or before the first round only as configs before it
// said), practice never touching QUEST, the participant's texts (defaults per task, checked as
// UTF-8, errors naming the field), and replay of logs written with either form.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "config_error.h"
#include "log/trial_log.h"
#include "procedure/config.h"
#include "procedure/procedure.h"
#include "procedure/session.h"
#include "procedure/session_record.h"

namespace {

namespace fs = std::filesystem;
using namespace penumbra;

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("penumbra-flow-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

using test::config_error;

// Four rounds (stair/step x full/half contrast), two sizes, short staircases.
nlohmann::json four_rounds(const nlohmann::json& practice) {
  nlohmann::json j = {{"artifact_px", {5, 10}},
                      {"rounds", {{{"pattern", "stair"}, {"contrast", 1.0}}, {{"pattern", "step"}, {"contrast", 1.0}},
                                  {{"pattern", "stair"}, {"contrast", 0.5}}, {{"pattern", "step"}, {"contrast", 0.5}}}},
                      {"stopping", {{"min_trials", 3}, {"max_trials", 3}, {"sd_below", 0.01}}},
                      {"seed", 11u}};
  if (!practice.is_null()) j["practice"] = practice;
  return j;
}

// Runs the procedure to its end, answering correctly every third trial; the plans in order.
std::vector<procedure::TrialPlan> run_all(procedure::Procedure& p) {
  std::vector<procedure::TrialPlan> plans;
  while (const auto plan = p.next()) {
    plans.push_back(*plan);
    p.apply(*plan, plan->trial % 3 != 0);
    if (plans.size() > 1000) break;
  }
  return plans;
}

TEST(PracticeFlow, PracticeBeforeEveryRoundShowsThatRoundsConditionAndNeverMovesQuest) {
  const auto config = procedure::parse_config(four_rounds({{"trials", 3}, {"intensity", 0.25}}), "study.json");
  EXPECT_TRUE(config.practice.every_round);  // the block's defaults
  EXPECT_TRUE(config.practice.feedback);
  procedure::Procedure p(config, procedure::randomize(config, "p3", std::nullopt));
  const auto plans = run_all(p);
  const auto& order = p.randomization().round_order;
  ASSERT_EQ(plans.size(), 4u * (3 + 2 * 3));
  std::size_t i = 0;
  for (const int round : order) {
    SCOPED_TRACE(round);
    for (int k = 0; k < 3; ++k, ++i) {  // the round opens with its practice
      const auto& plan = plans[i];
      EXPECT_TRUE(plan.practice) << "trial " << i;
      EXPECT_EQ(plan.round, round);
      EXPECT_EQ(plan.stimulus.pattern, config.rounds[static_cast<std::size_t>(round)].pattern);
      EXPECT_EQ(plan.stimulus.lit_linear, config.rounds[static_cast<std::size_t>(round)].contrast);
      EXPECT_NEAR(plan.intensity, 0.25, 1e-12);
      EXPECT_EQ(plan.staircase, k % 2);  // the sizes in turn
    }
    for (int k = 0; k < 6; ++k, ++i) {
      EXPECT_FALSE(plans[i].practice) << "trial " << i;
      EXPECT_EQ(plans[i].round, round);
    }
  }
  // Every staircase saw its 3 test trials only.
  for (const auto& round : p.rounds())
    for (const auto& sc : round) EXPECT_EQ(sc.quest.trial_count(), 3u) << sc.name;
}

TEST(PracticeFlow, FlatFieldsKeepTheFirstRoundOnlyPracticeOfOlderConfigs) {
  nlohmann::json j = four_rounds(nullptr);
  j["practice_trials"] = 2;
  j["practice_intensity"] = 0.4;
  const auto config = procedure::parse_config(j, "study.json");
  EXPECT_FALSE(config.practice.every_round);
  EXPECT_FALSE(config.practice.feedback);
  procedure::Procedure p(config, procedure::randomize(config, "p3", std::nullopt));
  const auto plans = run_all(p);
  ASSERT_EQ(plans.size(), 2u + 4 * 6);
  for (std::size_t i = 0; i < plans.size(); ++i) EXPECT_EQ(plans[i].practice, i < 2) << i;
  EXPECT_EQ(plans[0].round, p.randomization().round_order.front());
  // Written back as it was read, so session.json of such a config is what it always was.
  const nlohmann::json back = procedure::to_json(config);
  EXPECT_EQ(back["practice_trials"], 2);
  EXPECT_EQ(back["practice_intensity"], 0.4);
  EXPECT_FALSE(back.contains("practice"));
  EXPECT_FALSE(back.contains("texts"));
  // Neither form: the same (4 practice trials before the first round).
  EXPECT_EQ(procedure::parse_config(four_rounds(nullptr), "s").practice.trials, 4);
  EXPECT_FALSE(procedure::parse_config(four_rounds(nullptr), "s").practice.every_round);
}

TEST(PracticeFlow, PracticeBlockAndTextsRoundTripAndErrorsNameTheField) {
  nlohmann::json j = four_rounds({{"trials", 2}, {"every_round", false}, {"feedback", true}, {"feedback_ms", 500}});
  j["texts"] = {{"question", "Welche Seite zeigt die gezackte (treppenförmige) Kante?"}, {"round", "Runde {round} von {rounds}"}};
  const auto config = procedure::parse_config(j, "study.json");
  const auto again = procedure::parse_config(procedure::to_json(config), "session.json");
  EXPECT_EQ(again.practice.trials, 2);
  EXPECT_FALSE(again.practice.every_round);
  EXPECT_TRUE(again.practice.feedback);
  EXPECT_EQ(again.practice.feedback_ms, 500);
  EXPECT_EQ(again.texts, config.texts);
  EXPECT_EQ(again.text("question"), "Welche Seite zeigt die gezackte (treppenförmige) Kante?");
  EXPECT_EQ(again.text("round", 2, 4), "Runde 2 von 4");
  EXPECT_EQ(again.text("practice_feedback_correct"), "Correct");  // not given: the default
  EXPECT_EQ(again.text("consent"), "");

  // Defaults per task, in plain words.
  EXPECT_EQ(config.text("question"), "Welche Seite zeigt die gezackte (treppenförmige) Kante?");
  const auto plain = procedure::parse_config(four_rounds(nullptr), "s");
  EXPECT_EQ(plain.text("question"), "Which side shows the jagged (stair-stepped) edge?");
  EXPECT_EQ(plain.text("round", 1, 4), "Round 1 of 4");
  nlohmann::json yesno = four_rounds(nullptr);
  yesno["task"] = "yesno";
  EXPECT_EQ(procedure::parse_config(yesno, "s").text("question"), "Is this edge straight?");
  EXPECT_EQ(procedure::parse_config(yesno, "s").text("answer_first"), "Yes   \xe2\x86\x90 or F");
  for (const auto& e : procedure::text_table()) {
    EXPECT_NO_THROW(plain.text(e.key)) << e.key;
    EXPECT_STRNE(e.help, "") << e.key;
  }

  auto with = [&](const char* key, const nlohmann::json& value) {
    nlohmann::json k = four_rounds(nullptr);
    k[key] = value;
    return config_error(k);
  };
  EXPECT_EQ(with("practice", {{"every_round", "yes"}}), "study.json: practice.every_round: expected true or false, got \"yes\"");
  EXPECT_EQ(with("practice", {{"trials", -1}}), "study.json: practice.trials: expected an integer in [0, 1000], got -1");
  EXPECT_EQ(with("practice", {{"feedback_ms", 1e6}}), "study.json: practice.feedback_ms: expected a number in [0, 10000], got 1000000.0");
  EXPECT_EQ(with("practice", {{"trails", 4}}), "study.json: practice.trails: unknown key (allowed: trials, intensity, every_round, feedback, feedback_ms)");
  nlohmann::json both = four_rounds({{"trials", 2}});
  both["practice_trials"] = 3;
  EXPECT_EQ(config_error(both), "study.json: practice_trials: not with practice (practice.trials and practice.intensity say it)");
  EXPECT_EQ(with("texts", "hello"), "study.json: texts: expected an object of \"name\": \"text\"");
  EXPECT_EQ(with("texts", {{"welcome", 3}}), "study.json: texts.welcome: expected a string, got 3");
  EXPECT_EQ(with("texts", {{"welcome", "caf\xe9"}}), "study.json: texts.welcome: not valid UTF-8 (save the file as UTF-8)");
  EXPECT_EQ(with("texts", {{"task", "a\tb"}}), "study.json: texts.task: a control character (U+0009); only a newline (\\n) is allowed");
  EXPECT_EQ(with("texts", {{"start", ""}}), "study.json: texts.start: expected a non-empty text");
  EXPECT_EQ(with("texts", {{"consent", ""}}), "no error");
  EXPECT_EQ(with("texts", {{"welcome", std::string(procedure::kMaxTextBytes + 1, 'x')}}),
            "study.json: texts.welcome: longer than 4000 bytes");
  EXPECT_EQ(with("texts", {{"greeting", "hi"}}).rfind("study.json: texts.greeting: unknown key (allowed: welcome_title, ", 0), 0u)
      << with("texts", {{"greeting", "hi"}});
}

// A session of the new form written through Session (as penumbra-study does), then resumed: the
// replay (also penumbra-fit's integrity check) reproduces every row, practice before each round.
TEST(PracticeFlow, LogsWithPracticeBeforeEveryRoundReplayExactly) {
  const fs::path dir = fresh_dir("every-round");
  const auto config = procedure::parse_config(four_rounds({{"trials", 2}}), "study.json");
  int practice_rows = 0;
  {
    procedure::Session s = procedure::Session::create(config, dir, "p5", nlohmann::json::object());
    for (int t = 0; t < 20; ++t) {
      const auto plan = s.next();
      ASSERT_TRUE(plan);
      practice_rows += plan->practice;
      s.record(*plan, (t % 3 == 0) == (plan->target == "left") ? "right" : "left", 0);
    }
  }
  EXPECT_EQ(practice_rows, 2 + 2 + 2);  // two rounds done, the third begun (8 trials a round)
  procedure::Session resumed = procedure::Session::resume(dir);
  EXPECT_EQ(resumed.trials_done(), 20);
  const auto next = resumed.next();
  ASSERT_TRUE(next);
  EXPECT_FALSE(next->practice);
  EXPECT_EQ(next->round, resumed.randomization().round_order[2]);

  // A row moved between practice and test is named.
  auto rows = trial_log::read(dir / "trials.csv").rows;
  const auto record = procedure::check_session_json(nlohmann::json::parse(std::ifstream(dir / "session.json")), "session.json");
  rows[8].practice = 0;  // the second round's first practice trial
  try {
    procedure::replay_log(record, rows, "trials.csv");
    ADD_FAILURE() << "an edited practice flag replayed";
  } catch (const procedure::LogMismatch& e) {
    EXPECT_EQ(e.line, 10);
    EXPECT_NE(std::string(e.what()).find("column 'practice': '0'"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// The shipped lab config: the default design with practice before every round, with feedback.
TEST(PracticeFlow, TheLabConfigPractisesEveryRoundWithFeedback) {
  const auto lab = procedure::load_config(PENUMBRA_DATA_DIR "/studies/default-lab.json");
  const auto published = procedure::load_config(PENUMBRA_DATA_DIR "/studies/default.json");
  EXPECT_TRUE(lab.practice.every_round);
  EXPECT_TRUE(lab.practice.feedback);
  EXPECT_EQ(lab.practice.trials, 4);
  EXPECT_FALSE(published.practice.every_round);  // unchanged: its simulated sessions stay as measured
  nlohmann::json a = procedure::to_json(lab), b = procedure::to_json(published);
  for (auto* j : {&a, &b})
    for (const char* key : {"name", "practice", "practice_trials", "practice_intensity"}) j->erase(key);
  EXPECT_EQ(a, b) << "the same design otherwise";
}

// A session written before the practice block (tests/fuzz/fixtures: flat practice_trials 2) still
// replays row for row, its practice before the first round only.
TEST(PracticeFlow, OlderSessionsReplayAsBefore) {
  const fs::path fixtures = PENUMBRA_FIXTURES_DIR;
  const auto record = procedure::check_session_json(nlohmann::json::parse(std::ifstream(fixtures / "session.json")), "session.json");
  EXPECT_FALSE(record.config.practice.every_round);
  EXPECT_EQ(record.config.practice.trials, 2);
  const auto rows = trial_log::read(fixtures / "trials.csv").rows;
  ASSERT_GT(rows.size(), 2u);
  const procedure::Procedure p = procedure::replay_log(record, rows, "trials.csv");
  EXPECT_EQ(p.trials_done(), static_cast<int>(rows.size()));
  for (std::size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(rows[i].practice, i < 2 ? 1 : 0) << i;
}

}  // namespace
