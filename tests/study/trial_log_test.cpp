// Trial log (schema, append-only writer, validating reader) and study configs (errors naming the
// file and the field).
#include <gtest/gtest.h>

#include <map>
#include <set>

#include <filesystem>
#include <fstream>

#include "adaptive/calibration.h"
#include "config_error.h"
#include "log/trial_log.h"
#include "procedure/config.h"
#include "procedure/procedure.h"
#include "shadows/settings.h"

namespace {

namespace fs = std::filesystem;
using namespace penumbra;

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("penumbra-test-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

trial_log::TrialRow sample_row(int trial) {
  trial_log::TrialRow r;
  r.session_id = "p1-20250101T000000";
  r.participant = "p1";
  r.utc_time = "2025-01-01T00:00:00.000Z";
  r.round_position = 1;
  r.trial = trial;
  r.staircase = "a10";
  r.pattern = "stair";
  r.artifact_px = 10;
  r.task = "2afc";
  r.filter_radius_px = 31.622776601683793 + trial;
  r.intensity = std::log10(r.artifact_px / r.filter_radius_px);
  r.requested_filter_radius_px = r.filter_radius_px;
  r.kernel = "disk";
  r.target = "left";
  r.response = trial % 2 ? "left" : "right";
  r.correct = trial % 2;
  r.quest_mean = -0.1234567890123456789;
  r.quest_sd = 0.3;
  r.stimulus_seed = 4010436946754998ull;
  return r;
}

TEST(TrialLog, RoundTripsEveryValueExactly) {
  const fs::path dir = fresh_dir("log-roundtrip");
  {
    trial_log::Writer w(dir / "trials.csv", true);
    for (int t = 0; t < 3; ++t) w.append(sample_row(t));
  }
  {
    trial_log::Writer w(dir / "trials.csv", false);  // reopened: appends after the existing rows
    w.append(sample_row(3));
  }
  const auto log = trial_log::read(dir / "trials.csv");
  ASSERT_EQ(log.rows.size(), 4u);
  EXPECT_FALSE(log.torn_tail);
  for (int t = 0; t < 4; ++t) {
    EXPECT_EQ(log.rows[t].intensity, sample_row(t).intensity);  // bit for bit
    EXPECT_EQ(log.rows[t].quest_mean, sample_row(t).quest_mean);
    EXPECT_EQ(log.rows[t].stimulus_seed, sample_row(t).stimulus_seed);
    EXPECT_EQ(trial_log::format_row(log.rows[t]), trial_log::format_row(sample_row(t)));
  }
  EXPECT_THROW(trial_log::Writer(dir / "trials.csv", true), std::runtime_error);  // never recreated
}

// A number is written in the shortest form that reads back as the same double: a contrast of 0.3
// is "0.3" in trials.csv, not 0.29999999999999999 (what %.17g wrote), and still round-trips.
TEST(TrialLog, NumbersAreWrittenInTheirShortestExactForm) {
  trial_log::TrialRow r = sample_row(0);
  r.contrast = 0.3;
  r.quest_sd = 0.1 + 0.2;  // 0.30000000000000004: needs all 17 digits
  const std::string line = trial_log::format_row(r);
  EXPECT_NE(line.find(",0.3,"), std::string::npos) << line;
  EXPECT_EQ(line.find("0.2999999"), std::string::npos) << line;
  EXPECT_NE(line.find("0.30000000000000004"), std::string::npos) << line;
  const fs::path dir = fresh_dir("log-shortest");
  { trial_log::Writer(dir / "trials.csv", true).append(r); }
  const auto log = trial_log::read(dir / "trials.csv");
  ASSERT_EQ(log.rows.size(), 1u);
  EXPECT_EQ(log.rows[0].contrast, 0.3);
  EXPECT_EQ(log.rows[0].quest_sd, 0.1 + 0.2);
  EXPECT_EQ(log.rows[0].intensity, r.intensity);
}

TEST(TrialLog, ReaderNamesFileLineAndColumn) {
  const fs::path dir = fresh_dir("log-errors");
  auto write = [&](const std::string& body) {
    std::ofstream(dir / "t.csv") << trial_log::header_line() << body;
    return dir / "t.csv";
  };
  auto message = [&](const fs::path& p) {
    try {
      trial_log::read(p);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string good = trial_log::format_row(sample_row(0));
  std::string bad = good;
  bad.replace(bad.find(",stair,"), 7, ",stairs,");
  EXPECT_EQ(message(write(good + bad)), (dir / "t.csv").string() +
                                           ":3: column 'pattern': expected stair|step (found 'stairs')");
  std::string wrong_correct = trial_log::format_row(sample_row(1));
  wrong_correct.replace(wrong_correct.find(",left,left,1,"), 13, ",left,left,0,");
  EXPECT_NE(message(write(wrong_correct)).find(":2: column 'correct': does not agree"), std::string::npos);
  std::string wrong_intensity = good;
  wrong_intensity.replace(wrong_intensity.find(",2afc,") + 6, 4, "0.25");
  EXPECT_NE(message(write(wrong_intensity)).find("column 'intensity'"), std::string::npos);
  EXPECT_NE(message(write("a,b\n")).find(":2: expected 31 columns, found 2"), std::string::npos);
  // Free text the writer would refuse (a quote, a CR of a CRLF file, bytes that are not UTF-8) is
  // refused by the reader too, and the value is echoed short and escaped.
  for (const auto& [participant, shown] : std::vector<std::pair<std::string, std::string>>{
           {"p\"1", "p\"1"}, {"p1\r", "p1\\x0d"}, {"p\xff" "1", "p\\xff1"}, {"p\xc0\xaf", "p\\xc0\\xaf"}}) {
    std::string row = good;
    row.replace(row.find(",p1,"), 4, "," + participant + ",");
    EXPECT_EQ(message(write(row)), (dir / "t.csv").string() +
                                       ":2: column 'participant': expected UTF-8 text without quotes or control "
                                       "characters (found '" + shown + "')");
  }
  std::string long_name = good;
  long_name.replace(long_name.find(",p1,"), 4, "," + std::string(100000, 'p') + ",");
  EXPECT_LT(message(write(long_name)).size(), 300u);
  std::ofstream(dir / "h.csv") << "trial,response\n";
  EXPECT_NE(message(dir / "h.csv").find("h.csv:1: the header"), std::string::npos);

  // A torn last line is reported, not parsed.
  const auto torn = trial_log::read(write(good + good.substr(0, 20)));
  EXPECT_TRUE(torn.torn_tail);
  EXPECT_EQ(torn.rows.size(), 1u);
  EXPECT_EQ(torn.complete_bytes, trial_log::header_line().size() + good.size());
}

trial_log::TrialRow timed_row(int trial) {
  trial_log::TrialRow r = sample_row(trial);
  r.timing = trial_log::frame_timing(12.5 + trial, {16.9, 16.6, 40.1, 16.7}, 60);
  return r;
}

std::string read_error(const fs::path& p) {
  try {
    trial_log::read(p);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

// Issue 16: the timing columns. A frame interval over 1.5 refresh periods is a dropped frame.
TEST(TrialLog, FrameTimingCountsIntervalsOverOneAndAHalfPeriods) {
  const trial_log::FrameTiming t = trial_log::frame_timing(3.25, {16.9, 16.6, 40.1, 16.7, 25.1}, 60);
  EXPECT_EQ(t.onset_s, 3.25);
  EXPECT_EQ(t.frames, 5);
  EXPECT_NEAR(t.frame_ms_mean, 23.08, 1e-9);
  EXPECT_EQ(t.frame_ms_max, 40.1);
  EXPECT_EQ(t.dropped_frames, 2);  // 40.1 and 25.1 > 25 ms
  EXPECT_EQ(trial_log::frame_timing(0, {25.1}, 120).dropped_frames, 1);  // 12.5 ms at 120 Hz
  EXPECT_EQ(trial_log::frame_timing(0, {8.3, 12.4}, 120).dropped_frames, 0);
  EXPECT_FALSE(trial_log::frame_timing(0, {8.3, 100}, 0).dropped_frames.has_value());  // refresh rate unknown
  const trial_log::FrameTiming same = trial_log::frame_timing(0, std::vector<double>(7, 0.1), 60);
  EXPECT_LE(same.frame_ms_mean, same.frame_ms_max);  // the reader refuses mean > max
}

// New logs carry the timing (empty when not measured: headless); logs written before the timing
// columns still read, and a resumed one goes on in its own layout.
TEST(TrialLog, TimingColumnsRoundTripAndLogsWithoutThemStillRead) {
  const fs::path dir = fresh_dir("log-timing");
  {
    trial_log::Writer w(dir / "trials.csv", true);
    w.append(timed_row(0));
    w.append(sample_row(1));  // headless: not measured
    trial_log::TrialRow unknown_refresh = timed_row(2);
    unknown_refresh.timing->dropped_frames.reset();
    w.append(unknown_refresh);
  }
  const std::string text = [&] {
    std::ifstream in(dir / "trials.csv");
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  EXPECT_NE(text.find(",stimulus_seed,onset_s,frames,frame_ms_mean,frame_ms_max,dropped_frames\n"), std::string::npos);
  EXPECT_NE(text.find(",4010436946754998,12.5,4,22.575,40.1,1\n"), std::string::npos) << text;
  EXPECT_NE(text.find(",4010436946754998,,,,,\n"), std::string::npos) << text;
  EXPECT_NE(text.find(",4010436946754998,14.5,4,22.575,40.1,\n"), std::string::npos) << text;
  const auto log = trial_log::read(dir / "trials.csv");
  EXPECT_EQ(log.layout, trial_log::Layout::current);
  ASSERT_EQ(log.rows.size(), 3u);
  ASSERT_TRUE(log.rows[0].timing.has_value());
  EXPECT_EQ(log.rows[0].timing->frames, 4);
  EXPECT_EQ(log.rows[0].timing->dropped_frames, 1);
  EXPECT_EQ(log.rows[0].timing->frame_ms_max, 40.1);
  EXPECT_EQ(trial_log::format_row(log.rows[0]), trial_log::format_row(timed_row(0)));
  EXPECT_FALSE(log.rows[1].timing.has_value());
  ASSERT_TRUE(log.rows[2].timing.has_value());
  EXPECT_FALSE(log.rows[2].timing->dropped_frames.has_value());

  // A log from before the timing columns: read as it is, appended to in its own layout.
  {
    std::ofstream old(dir / "old.csv");
    old << trial_log::header_line(trial_log::Layout::without_timing);
    for (int t = 0; t < 2; ++t) old << trial_log::format_row(sample_row(t), trial_log::Layout::without_timing);
  }
  EXPECT_EQ(trial_log::header_line(trial_log::Layout::without_timing).find("onset_s"), std::string::npos);
  {
    trial_log::Writer w(dir / "old.csv", false);
    w.append(timed_row(2));  // its timing has no column there
  }
  const auto old = trial_log::read(dir / "old.csv");
  EXPECT_EQ(old.layout, trial_log::Layout::without_timing);
  ASSERT_EQ(old.rows.size(), 3u);
  for (const auto& r : old.rows) EXPECT_FALSE(r.timing.has_value());
  EXPECT_EQ(trial_log::format_row(old.rows[2], trial_log::Layout::without_timing),
            trial_log::format_row(sample_row(2), trial_log::Layout::without_timing));
  // Rows of one layout under the other's header are refused by their column count.
  {
    std::ofstream mixed(dir / "mixed.csv");
    mixed << trial_log::header_line(trial_log::Layout::without_timing) << trial_log::format_row(timed_row(0));
  }
  EXPECT_EQ(read_error(dir / "mixed.csv"), (dir / "mixed.csv").string() + ":2: expected 25 columns, found 31");
  fs::remove_all(dir);
}

// Issue 26: the log names the round two ways (the config's condition, the position a participant
// saw); logs with one column 'round' (the condition) still read and are appended to as they are.
TEST(TrialLog, RoundsAreNamedByConditionAndPositionAndOlderLogsStillRead) {
  const fs::path dir = fresh_dir("log-rounds");
  trial_log::TrialRow row = timed_row(0);
  row.condition_index = 3;
  row.round_position = 1;
  row.rt_ms = 412.34567891;
  const std::string line = trial_log::format_row(row);
  EXPECT_EQ(line.rfind("p1-20250101T000000,p1,2025-01-01T00:00:00.000Z,3,1,0,a10,", 0), 0u) << line;
  EXPECT_NE(line.find(",412.346,"), std::string::npos) << line;  // to the microsecond
  EXPECT_EQ(trial_log::columns()[3], "condition_index");
  EXPECT_EQ(trial_log::columns()[4], "round_position");
  EXPECT_EQ(trial_log::columns(trial_log::Layout::with_timing)[3], "round");
  {
    std::ofstream old(dir / "round.csv");
    old << trial_log::header_line(trial_log::Layout::with_timing) << trial_log::format_row(row, trial_log::Layout::with_timing);
  }
  {
    trial_log::Writer w(dir / "round.csv", false);
    w.append(timed_row(1));
  }
  const auto old = trial_log::read(dir / "round.csv");
  EXPECT_EQ(old.layout, trial_log::Layout::with_timing);
  ASSERT_EQ(old.rows.size(), 2u);
  EXPECT_EQ(old.rows[0].condition_index, 3);
  EXPECT_EQ(old.rows[0].round_position, 0);  // not recorded then
  // A position outside 1.. is refused by name.
  std::string bad = line;
  bad.replace(bad.find(",3,1,0,"), 7, ",3,0,0,");
  {
    std::ofstream(dir / "bad.csv") << trial_log::header_line() << bad;
  }
  EXPECT_EQ(read_error(dir / "bad.csv"),
            (dir / "bad.csv").string() + ":2: column 'round_position': expected an integer in [1, 1001] (found '0')");
  fs::remove_all(dir);
}

TEST(TrialLog, BadTimingValuesNameFileLineAndColumn) {
  const fs::path dir = fresh_dir("log-timing-errors");
  const std::string good = trial_log::format_row(timed_row(0));
  const std::string prefix = good.substr(0, good.find(",12.5,"));
  struct Case {
    std::string timing, message;
  };
  const std::vector<Case> cases{
      {"-0.5,4,22.5,40.1,1", "column 'onset_s': expected a time in [0, 1e7] s since the window opened (found '-0.5')"},
      {"nan,4,22.5,40.1,1", "column 'onset_s': expected a finite number (found 'nan')"},
      {"NA,4,22.5,40.1,1", "column 'onset_s': expected a finite number (found 'NA')"},
      {"12.5,0,22.5,40.1,0", "column 'frames': expected an integer in [1, 1000000000] (found '0')"},
      {"12.5,4.5,22.5,40.1,1", "column 'frames': expected an integer in [1, 1000000000] (found '4.5')"},
      {"12.5,4,inf,40.1,1", "column 'frame_ms_mean': expected a finite number (found 'inf')"},
      {"12.5,4,-1,40.1,1", "column 'frame_ms_mean': expected a frame interval in [0, 1e6] ms (found '-1')"},
      {"12.5,4,22.5,20,1", "column 'frame_ms_max': expected >= frame_ms_mean (found '20')"},
      {"12.5,4,22.5,40.1,5", "column 'dropped_frames': expected an integer in [0, 4] (found '5')"},
      {"12.5,4,22.5,40.1,-1", "column 'dropped_frames': expected an integer in [0, 4] (found '-1')"},
      {"12.5,4,22.5,,1", "column 'frame_ms_max': expected a value (the timing columns are all empty or all filled) (found '')"},
      {",4,22.5,40.1,1", "column 'onset_s': expected a value (the timing columns are all empty or all filled) (found '')"},
  };
  for (const Case& c : cases) {
    std::ofstream(dir / "t.csv") << trial_log::header_line() << good << prefix << "," << c.timing << "\n";
    EXPECT_EQ(read_error(dir / "t.csv"), (dir / "t.csv").string() + ":3: " + c.message) << c.timing;
  }
  fs::remove_all(dir);
}

using test::config_error;

TEST(StudyConfig, DefaultLoadsAndErrorsNameTheField) {
  const auto c = procedure::load_config(PENUMBRA_DATA_DIR "/studies/default.json");
  EXPECT_EQ(c.rounds.size(), 4u);
  EXPECT_EQ(c.artifact_px, (std::vector<double>{5, 10, 20}));
  EXPECT_DOUBLE_EQ(c.quest.p_threshold, 0.82);
  EXPECT_DOUBLE_EQ(c.quest.beta, 3.5);
  EXPECT_NEAR(c.display.arcmin(10), 15.73, 0.01);  // 10 px = 2.745 mm at 600 mm

  const nlohmann::json base = {{"rounds", {{{"pattern", "stair"}, {"contrast", 1.0}}}}};
  EXPECT_EQ(config_error(base), "no error");
  auto with = [&](const std::string& key, const nlohmann::json& v) {
    nlohmann::json j = base;
    j[key] = v;
    return config_error(j);
  };
  EXPECT_EQ(with("stopping", {{"min_trials", 0}}), "study.json: stopping.min_trials: expected an integer in [1, 10000], got 0");
  EXPECT_EQ(with("stopping", {{"min_trials", 20}, {"max_trials", 10}}),
            "study.json: stopping.max_trials: expected >= stopping.min_trials");
  EXPECT_EQ(with("rounds", {{{"pattern", "zigzag"}}}),
            "study.json: rounds[0].pattern: pattern 'zigzag': expected stair or step");
  EXPECT_EQ(with("quest", {{"beta", "steep"}}), "study.json: quest.beta: expected a number, got \"steep\"");
  EXPECT_EQ(with("artifact_px", {5, 5}), "study.json: artifact_px[1]: duplicate artifact size");
  EXPECT_EQ(with("colour", 1), "study.json: colour: unknown key (allowed: name, task, artifact_px, rounds, quest, intensity_bounds, stopping, "
            "practice_trials, practice_intensity, practice, texts, break_every_trials, seed, round_order, stimulus, display, "
            "description, yesno_scoring, readings, frames)");
  // Issue 14.8: a duplicated key in the file was read as its last value.
  const fs::path dup = fs::temp_directory_path() / ("penumbra-dup-" + std::to_string(::getpid()) + ".json");
  std::ofstream(dup) << R"({"rounds": [{"pattern": "stair"}], "stopping": {"max_trials": 40, "max_trials": 4}})";
  try {
    procedure::load_config(dup);
    ADD_FAILURE() << "a duplicated key was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), dup.string() + ": stopping.max_trials: duplicate key");
  }
  fs::remove(dup);
  EXPECT_EQ(with("display", {{"transfer", "pq"}}),
            "study.json: display.transfer: transfer function 'pq': expected srgb, gamma2.2 or linear");
  EXPECT_EQ(config_error(nlohmann::json::object()),
            "study.json: rounds: missing (a study needs its rounds: [{\"pattern\", \"contrast\"}])");
}

// yesno_scoring (issue 29): what a yes/no QUEST is fed, with the guess rate each scoring implies;
// readings: a design's declared choices, carried into session.json. The published design declares
// both and asks the thesis's question.
TEST(StudyConfig, YesNoScoringAndDeclaredReadings) {
  const nlohmann::json yesno = {{"task", "yesno"}, {"rounds", {{{"pattern", "stair"}, {"contrast", 1.0}}}}};
  auto error = [](nlohmann::json j, const std::string& key, const nlohmann::json& v) {
    j[key] = v;
    return config_error(j);
  };
  EXPECT_EQ(error(yesno, "yesno_scoring", "jagged_only"), "no error");
  EXPECT_EQ(error(yesno, "yesno_scoring", "both"), "study.json: yesno_scoring: yesno_scoring 'both': expected jagged_only or balanced");
  nlohmann::json twoafc = yesno;
  twoafc["task"] = "2afc";
  EXPECT_EQ(error(twoafc, "yesno_scoring", "balanced"),
            "study.json: yesno_scoring: only for task yesno (a 2afc trial is scored one way)");
  EXPECT_EQ(error(yesno, "readings", {{"kernel", 3}}), "study.json: readings.kernel: expected a non-empty string");
  EXPECT_EQ(error(yesno, "readings", "disk"),
            "study.json: readings: expected an object of \"choice\": \"what was chosen and why\"");

  nlohmann::json balanced_json = yesno;
  balanced_json["yesno_scoring"] = "balanced";
  const procedure::StudyConfig jagged = procedure::parse_config(yesno, "study.json");
  const procedure::StudyConfig balanced = procedure::parse_config(balanced_json, "study.json");
  EXPECT_DOUBLE_EQ(jagged.quest.gamma, 0.05);
  EXPECT_DOUBLE_EQ(jagged.quest.p_threshold, 0.658);
  EXPECT_DOUBLE_EQ(balanced.quest.gamma, 0.5);
  EXPECT_DOUBLE_EQ(balanced.quest.p_threshold, 0.82);
  EXPECT_FALSE(procedure::to_json(jagged).contains("yesno_scoring"));  // older sessions read back equal
  EXPECT_EQ(procedure::to_json(balanced)["yesno_scoring"], "balanced");

  // Scored balanced, a straight (catch) trial moves its staircase; scored jagged_only it does not.
  for (const procedure::StudyConfig* config : {&jagged, &balanced}) {
    procedure::StudyConfig c = *config;
    c.practice.trials = 0;
    procedure::Procedure proc(c);
    int straight_seen = 0;
    for (int i = 0; i < 40 && straight_seen == 0; ++i) {
      const std::optional<procedure::TrialPlan> plan = proc.next();
      ASSERT_TRUE(plan);
      const std::size_t before = proc.staircase(*plan).quest.trial_count();
      proc.apply(*plan, true);
      const std::size_t after = proc.staircase(*plan).quest.trial_count();
      if (plan->target == "straight") {
        ++straight_seen;
        EXPECT_EQ(after, before + (c.yesno_scoring == "balanced" ? 1u : 0u)) << c.yesno_scoring;
      } else {
        EXPECT_EQ(after, before + 1) << c.yesno_scoring;
      }
    }
    EXPECT_EQ(straight_seen, 1) << c.yesno_scoring;
  }

  const procedure::StudyConfig published = procedure::load_config(PENUMBRA_DATA_DIR "/studies/kreuzer2017.json");
  EXPECT_EQ(published.yesno_scoring, "balanced");
  EXPECT_EQ(published.text("question"), "Is the original image a line?");
  std::set<std::string> declared;
  for (const auto& [key, value] : published.readings) declared.insert(key);
  for (const char* key : {"question", "yesno_scoring", "straight_share", "kernel", "stimulus.size_px", "display", "contrast",
                          "practice", "break_every_trials"})
    EXPECT_TRUE(declared.count(key)) << key;
}

// stimulus.technique: the renderer's technique and its settings by penumbra-render's keys; the
// earlier kernel and taps fields do not mix with it, and pcf names its kernel (the log's column).
TEST(StudyConfig, StimulusTechniqueAndItsSettings) {
  const auto c = procedure::load_config(PENUMBRA_DATA_DIR "/studies/pcf-poisson.json");
  EXPECT_EQ(c.technique, "pcf");
  EXPECT_EQ(c.technique_settings, (std::vector<std::pair<std::string, std::string>>{{"pcf.kernel", "poisson"}}));
  EXPECT_EQ(c.kernel, stimuli::Kernel::poisson);
  EXPECT_EQ(procedure::to_json(c)["stimulus"],
            (nlohmann::json{{"size_px", 320}, {"technique", "pcf"}, {"settings", {{"pcf.kernel", "poisson"}}}}));

  const nlohmann::json base = {{"rounds", {{{"pattern", "stair"}, {"contrast", 1.0}}}}};
  auto with = [&](const nlohmann::json& stimulus) {
    nlohmann::json j = base;
    j["stimulus"] = stimulus;
    return config_error(j);
  };
  const nlohmann::json grid = {{"pcf.kernel", "grid"}};
  EXPECT_EQ(with({{"technique", "pcf"}, {"settings", {{"pcf.kernel", "grid"}, {"pcf.poisson_taps", 16}, {"pcf.rotate", false}}}}), "no error");
  EXPECT_EQ(with({{"technique", "pcf"}, {"settings", grid}, {"kernel", "disk"}}).rfind("study.json: stimulus.kernel: the kernel without a technique", 0), 0u);
  EXPECT_EQ(with({{"settings", grid}}), "study.json: stimulus.settings: needs stimulus.technique (the technique the settings are for)");
  EXPECT_EQ(with({{"technique", "pcf"}}).rfind("study.json: stimulus.settings: pcf.kernel is required with technique pcf", 0), 0u);
  EXPECT_EQ(with({{"technique", "pcf"}, {"settings", {{"pcf.kernel", "disk"}}}}), "no error");  // the exact disk
  EXPECT_EQ(with({{"technique", "pcf"}, {"settings", {{"pcf.kernel", "cone"}}}}),
            "study.json: stimulus.settings.pcf.kernel: kernel 'cone': expected disk, grid or poisson");
  EXPECT_EQ(with({{"technique", "pcf"}, {"settings", {{"pcf.kernel", {1, 2}}}}}),
            "study.json: stimulus.settings.pcf.kernel: expected a string, a number or true/false");
  EXPECT_EQ(with({{"technique", ""}}), "study.json: stimulus.technique: expected a technique name (penumbra-render --technique)");
  EXPECT_EQ(with({{"technique", "pcf"}, {"settings", "grid"}}), "study.json: stimulus.settings: expected an object of \"section.key\": value");
}

// Issue 44: `run --kernel` makes the lab's stimuli the engine's kernel. It replaces the kernel field
// of a config without a technique and pcf.kernel of one drawn by the renderer's PCF, and what
// session.json records (to_json) reads back with it; a technique without kernels refuses it.
TEST(StudyConfig, TheKernelOptionReplacesTheStimulusKernel) {
  procedure::StudyConfig lab = procedure::load_config(PENUMBRA_DATA_DIR "/studies/default-lab.json");
  ASSERT_EQ(lab.kernel, stimuli::Kernel::disk);
  procedure::set_stimulus_kernel(lab, stimuli::Kernel::grid);
  EXPECT_EQ(lab.kernel, stimuli::Kernel::grid);
  EXPECT_EQ(procedure::to_json(lab)["stimulus"]["kernel"], "grid");
  EXPECT_EQ(procedure::parse_config(procedure::to_json(lab), "session.json").kernel, stimuli::Kernel::grid);
  EXPECT_EQ(procedure::Procedure(lab).next()->stimulus.kernel, stimuli::Kernel::grid) << "the trials are drawn with it";

  procedure::StudyConfig drawn = procedure::load_config(PENUMBRA_DATA_DIR "/studies/pcf-poisson.json");
  procedure::set_stimulus_kernel(drawn, stimuli::Kernel::disk);
  EXPECT_EQ(drawn.kernel, stimuli::Kernel::disk);
  EXPECT_EQ(drawn.technique_settings, (std::vector<std::pair<std::string, std::string>>{{"pcf.kernel", "disk"}}));
  const procedure::StudyConfig back = procedure::parse_config(procedure::to_json(drawn), "session.json");
  EXPECT_EQ(back.kernel, stimuli::Kernel::disk);
  EXPECT_EQ(back.technique_settings, drawn.technique_settings);

  for (const char* name : {"vsm", "rpcf"}) {
    procedure::StudyConfig boxed = procedure::load_config(PENUMBRA_DATA_DIR "/studies/" + std::string(name) + ".json");
    const nlohmann::json before = procedure::to_json(boxed);
    try {
      procedure::set_stimulus_kernel(boxed, stimuli::Kernel::grid);
      ADD_FAILURE() << name << ": a kernel for a technique without kernels";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind("the stimuli are drawn by " + std::string(name) + ", which has no kernel", 0), 0u) << e.what();
    }
    EXPECT_EQ(procedure::to_json(boxed), before) << name << ": a refused kernel changes nothing";
  }
}

// Issue 44: the renderer's default PCF kernel is one a lab measures by default (default-lab.json's
// kernel: an entry the lab's fit writes is used without a fallback) and one the shipped calibrations
// have an entry for (the published entry, whose reading assumes the study's disk, and predicted.json).
TEST(StudyConfig, TheRenderersDefaultKernelIsOneTheLabAndTheShippedCalibrationsMeasure) {
  shadows::ShadowSettings defaults;
  defaults.technique = shadows::Technique::pcf;
  const std::string kernel = shadows::variant_choice(defaults);
  EXPECT_EQ(kernel, stimuli::to_string(procedure::load_config(PENUMBRA_DATA_DIR "/studies/default-lab.json").kernel));
  adaptive::Calibration lab;
  adaptive::CalibrationEntry fitted;
  fitted.technique = "pcf";
  fitted.kernel = stimuli::to_string(procedure::load_config(PENUMBRA_DATA_DIR "/studies/default-lab.json").kernel);
  fitted.obtained_by = adaptive::CalibrationMethod::study;
  lab.entries = {fitted};
  EXPECT_FALSE(lab.choose("pcf", kernel).fallback) << lab.choose("pcf", kernel).from;
  for (const char* shipped : {"default.json", "predicted.json"}) {
    const adaptive::Calibration cal = adaptive::load_calibration(PENUMBRA_DATA_DIR "/calibration/" + std::string(shipped));
    const adaptive::CalibrationChoice chosen = cal.choose("pcf", kernel);
    EXPECT_FALSE(chosen.fallback) << shipped << ": " << chosen.from;
    ASSERT_TRUE(chosen.entry) << shipped;
    EXPECT_TRUE(chosen.entry->kernel.empty() || chosen.entry->kernel == kernel) << shipped;
  }
  const std::string reading =
      nlohmann::json::parse(std::ifstream(PENUMBRA_DATA_DIR "/calibration/default.json"))["entries"][0]["threshold"]["reading"];
  EXPECT_NE(reading.find("the study's " + kernel + " is assumed"), std::string::npos)
      << "the published entry's kernel, as default.json reads it: " << reading;
}

// round_order "latin-square" (issue 16): balanced counterbalancing. Over a full set of rows every
// round runs once in every position, and every ordered pair of rounds is adjacent equally often
// (even n: once; odd n over 2n rows: twice); the row comes from the number the id ends in.
TEST(StudyConfig, LatinSquareRoundOrderIsBalanced) {
  for (int n : {1, 2, 3, 4, 5, 6}) {
    SCOPED_TRACE(n);
    const int rows = n % 2 == 0 ? n : 2 * n;
    std::map<std::pair<int, int>, int> position, follows;
    for (int p = 1; p <= rows; ++p) {
      const std::vector<int> row = procedure::latin_square_row(n, p);
      ASSERT_EQ(std::set<int>(row.begin(), row.end()).size(), static_cast<std::size_t>(n)) << p;
      for (int j = 0; j < n; ++j) ++position[{row[static_cast<std::size_t>(j)], j}];
      for (int j = 0; j + 1 < n; ++j) ++follows[{row[static_cast<std::size_t>(j)], row[static_cast<std::size_t>(j) + 1]}];
      EXPECT_EQ(procedure::latin_square_row(n, p + rows), row) << "rows repeat after " << rows;
    }
    for (const auto& [key, count] : position) EXPECT_EQ(count, rows / n) << key.first << " at " << key.second;
    if (n > 1) {
      EXPECT_EQ(follows.size(), static_cast<std::size_t>(n * (n - 1)));
      for (const auto& [key, count] : follows) EXPECT_EQ(count, rows / n) << key.first << " then " << key.second;
    }
  }
  EXPECT_EQ(procedure::participant_number("p07"), 7);
  EXPECT_EQ(procedure::participant_number("12"), 12);
  try {
    procedure::participant_number("alice");
    ADD_FAILURE() << "an id without a number got a row";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("round_order latin-square: participant 'alice' ends in no number", 0), 0u) << e.what();
  }
  procedure::StudyConfig c = procedure::load_config(PENUMBRA_DATA_DIR "/studies/default.json");
  c.round_order = "latin-square";
  EXPECT_EQ(procedure::randomize(c, "p2", std::nullopt).round_order, procedure::latin_square_row(4, 2));
  EXPECT_EQ(procedure::randomize(c, "p2", std::nullopt).round_order, (std::vector<int>{1, 2, 0, 3}));
}

// Issue 27: a log that resume and the fit passed although no session writes it: a utc_time of
// "yesterday", an onset of 1e308 s; and a CRLF or BOM file reported as a header mismatch without
// the cause.
TEST(TrialLog, ValuesNoSessionWritesAreRefusedAndSpreadsheetDamageIsNamed) {
  const fs::path dir = fresh_dir("log-values");
  const std::string good = trial_log::format_row(timed_row(0));
  auto with = [&](const std::string& from, const std::string& to) {
    std::string row = good;
    const std::size_t at = row.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    row.replace(at, from.size(), to);
    std::ofstream(dir / "t.csv") << trial_log::header_line() << row;
    return read_error(dir / "t.csv");
  };
  const std::string f = (dir / "t.csv").string();
  EXPECT_EQ(with("2025-01-01T00:00:00.000Z", "yesterday"),
            f + ":2: column 'utc_time': expected a UTC time as the study writes it, 2026-12-03T09:15:02.123Z (found 'yesterday')");
  EXPECT_EQ(with("2025-01-01T00:00:00.000Z", "2025-13-01T00:00:00.000Z").find("column 'utc_time'"), f.size() + 4);
  EXPECT_EQ(with(",12.5,4,", ",1e308,4,"), f + ":2: column 'onset_s': expected a time in [0, 1e7] s since the window opened (found '1e308')");
  EXPECT_EQ(with(",22.575,", ",1e300,").find("column 'frame_ms_mean'"), f.size() + 4);
  EXPECT_EQ(read_error(dir / "t.csv").find("no error"), std::string::npos);
  {
    std::ofstream(dir / "crlf.csv", std::ios::binary) << "session_id,participant\r\n";
    std::ofstream(dir / "bom.csv", std::ios::binary) << "\xEF\xBB\xBF" << trial_log::header_line() << good;
  }
  EXPECT_EQ(read_error(dir / "crlf.csv"),
            (dir / "crlf.csv").string() + ":1: lines end with \\r\\n (saved on Windows?); the log ends its lines with \\n only");
  EXPECT_EQ(read_error(dir / "bom.csv"), (dir / "bom.csv").string() +
                                             ":1: starts with a UTF-8 byte-order mark (saved by a spreadsheet?); the log is plain UTF-8: "
                                             "remove the first three bytes");
  fs::remove_all(dir);
}

// Issue 27: texts the participant's window cannot draw were shown as "??????"; a C1 control and an
// unknown {placeholder} were taken. Each is refused naming the field and the character.
TEST(StudyConfig, TextsTheWindowCannotDrawAreRefusedNamingTheCharacter) {
  nlohmann::json base = nlohmann::json::parse(R"({"rounds": [{"pattern": "stair", "contrast": 1.0}]})");
  auto with_text = [&](const std::string& key, const std::string& value) {
    nlohmann::json j = base;
    j["texts"] = {{key, value}};
    return config_error(j);
  };
  EXPECT_EQ(with_text("welcome", "\u4f60\u597d"),  // Chinese
            "study.json: texts.welcome: character U+4F60 '\u4f60' cannot be drawn by the participant's window (its font covers Latin, "
            "Greek and Cyrillic); translate or remove it");
  EXPECT_EQ(with_text("welcome", "Hallo\u0085Welt"), "study.json: texts.welcome: a control character (U+0085); only a newline (\\n) is allowed");
  EXPECT_EQ(with_text("welcome", "Hello {bogus}"),
            "study.json: texts.welcome: placeholder {bogus} is not filled in this text (only texts.round fills {round} and {rounds})");
  EXPECT_EQ(with_text("round", "Runde {round} von {total}"),
            "study.json: texts.round: placeholder {total} is not filled in (texts.round fills {round} and {rounds})");
  EXPECT_EQ(with_text("round", "Runde {round} von {rounds}"), "no error");
  EXPECT_EQ(with_text("welcome", "Gr\u00fc\u00dfe \u2014 \u0417\u0434\u0440\u0430\u0432\u0441\u0442\u0432\u0443\u0439\u0442\u0435 \u2190 {ok"), "no error");
  // Every default text can be drawn.
  for (const auto& e : procedure::text_table())
    for (const char* text : {e.default_2afc, e.default_yesno})
      if (text) {
        EXPECT_EQ(procedure::text_problem(e.key, text), "") << e.key;
      }
}

}  // namespace
